// The manibench host program, run as a user runs it.
#include <manibench/config.hpp>

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "test_registry.hpp"

namespace manibench {
namespace {

using testing::getBuildTreeRegistry;
using testing::runCli;

using testing::contains;
using testing::expectMentions;

// A file with `text`, removed with the object.
class TempYaml {
 public:
  explicit TempYaml(const std::string& text) {
    char path[] = "/tmp/manibench_cli_config_XXXXXX.yaml";
    const int fd = mkstemps(path, 5);
    if (fd < 0) throw std::runtime_error("mkstemps failed");
    close(fd);
    path_ = path;
    std::ofstream(path_) << text;
  }
  ~TempYaml() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

TEST(Cli, HelpAndUsageErrors) {
  const auto help = runCli({"--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_TRUE(contains(help.out, "usage: manibench"));
  for (const char* command : {"list", "info", "run", "bench", "config", "demo", "demos", "eval", "render", "objects"}) {
    const auto r = runCli({command, "--help"});
    EXPECT_EQ(r.exit_code, 0) << command;
    EXPECT_TRUE(contains(r.out, std::string("usage: manibench ") + command)) << r.out;
  }
  EXPECT_EQ(runCli({}).exit_code, 2);
  const auto unknown = runCli({"frobnicate"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_TRUE(contains(unknown.err, "unknown command 'frobnicate'")) << unknown.err;
  const auto bad_option = runCli({"run", "Reach-v0", "--policy", "random", "--bogus"});
  EXPECT_EQ(bad_option.exit_code, 2);
  EXPECT_TRUE(contains(bad_option.err, "unknown option '--bogus'")) << bad_option.err;
  EXPECT_EQ(runCli({"run", "Reach-v0"}).exit_code, 2);  // no --policy
  EXPECT_EQ(runCli({"run", "Reach-v0", "--policy", "random", "--seed", "-3"}).exit_code, 2);
}

TEST(Cli, BenchReportsSpeedResetsAndTheIntegratorsWork) {
  // Reach-v0: 3 episodes of 100 steps over its train objects.
  const auto r = runCli({"bench", "Reach-v0", "--policy", "zero", "--steps", "300"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // A fixed step: 5 control ticks of 2 ms steps, one evaluation each.
  expectMentions(r.out, {"integrator implicit_euler", "300 env steps in 3 episodes", "env steps/s",
                         "resets: the first ", "ms per reset (2, a new object each)",
                         "physics per env step: 25.0 integrator steps", "25.0 evaluations of the dynamics"});
  const auto cpodes = runCli({"bench", "Reach-v0", "--policy", "zero", "--steps", "20", "--set",
                              "physics.integrator=cpodes"});
  ASSERT_EQ(cpodes.exit_code, 0) << cpodes.err;
  EXPECT_TRUE(contains(cpodes.out, "integrator cpodes")) << cpodes.out;
  EXPECT_TRUE(contains(cpodes.out, "Newton iterations")) << cpodes.out;
}

TEST(Cli, ListShowsEveryPluginWithItsLibrary) {
  const auto r = runCli({"list"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"Reach-v0", "reach_expert", "random", "zero", "joint_velocity", "joint_position"})
    EXPECT_TRUE(contains(r.out, name)) << name << "\n" << r.out;
  EXPECT_TRUE(contains(r.out, MANIBENCH_TEST_BUILD_PLUGIN_DIR)) << r.out;
  EXPECT_FALSE(contains(r.out, "refused")) << r.out;
}

TEST(Cli, ListReportsBrokenLibrariesAndKeepsWorking) {
  const auto r = runCli({"list"}, {std::string("MANIBENCH_PLUGIN_PATH=") + MANIBENCH_TEST_FIXTURE_DIR});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "refused libraries")) << r.out;
  EXPECT_TRUE(contains(r.out, "ABI 99.0")) << r.out;
  EXPECT_TRUE(contains(r.out, "Reach-v0")) << r.out;  // the build tree still loads
}

TEST(Cli, InfoPrintsLayouts) {
  const auto r = runCli({"info", "Reach-v0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expectMentions(r.out, {"observation (state), 15 values", "joint_positions", "action, 2 values", "shoulder",
                         "success conditions: reached static success", "objects: 8 train, 4 test"});
}

TEST(Cli, RunPrintsStepsReturnAndFlags) {
  const auto r = runCli({"run", "Reach-v0", "--policy", "reach_expert", "--seed", "1", "--split", "test"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "steps, return")) << r.out;
  EXPECT_TRUE(contains(r.out, "success")) << r.out;
  EXPECT_TRUE(contains(r.out, "yes")) << r.out;
  // Same seed, same output.
  EXPECT_EQ(r.out, runCli({"run", "Reach-v0", "--policy", "reach_expert", "--seed", "1", "--split", "test"}).out);
}

TEST(Cli, UnknownNamesAreClearErrors) {
  const auto policy = runCli({"run", "Reach-v0", "--policy", "nope"});
  EXPECT_EQ(policy.exit_code, 1);
  EXPECT_TRUE(contains(policy.err, "no policy named 'nope'")) << policy.err;
  EXPECT_TRUE(contains(policy.err, "reach_expert")) << policy.err;
  const auto task = runCli({"info", "Nope-v0"});
  EXPECT_EQ(task.exit_code, 1);
  EXPECT_TRUE(contains(task.err, "no task named 'Nope-v0'")) << task.err;
}

TEST(Cli, PolicyCanBeAPathToALibrary) {
  const auto r = runCli({"run", "Reach-v0", "--policy",
                         std::string(MANIBENCH_TEST_BUILD_PLUGIN_DIR) + "/libmanibench_example_policies.so"});
  // That library registers two policies: the host must say so, not guess.
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.err, "registers 2 policies")) << r.err;
}

// run --trace: one row per env step, as many values as the header names,
// the last row the successful, final one.
TEST(Cli, RunTraceWritesOneRowPerStep) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("manibench_trace_" + std::to_string(::getpid()) + ".csv")).string();
  const auto r = runCli({"run", "Reach-v0", "--policy", "reach_expert", "--seed", "3", "--trace", path});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(path);
  std::string header, line, last;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("step,obs.joint_positions[0],", 0), 0u) << header;
  EXPECT_TRUE(contains(header, ",action.shoulder,action.elbow,reward,reached,static,success,done")) << header;
  const auto count = [](const std::string& text) { return std::count(text.begin(), text.end(), ','); };
  int rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    EXPECT_EQ(count(line), count(header)) << "row " << rows;
    EXPECT_EQ(line.rfind(std::to_string(rows) + ",", 0), 0u) << line;
    last = line;
  }
  EXPECT_GT(rows, 5);
  EXPECT_EQ(last.substr(last.size() - 4), ",1,1") << last;  // success, done
  std::filesystem::remove(path);
}

TEST(Cli, UsageErrorsPrintTheCommandsOwnUsage) {
  struct Case {
    std::vector<std::string> arguments;
    const char* usage;
  };
  const Case cases[] = {
      {{"run", "Reach-v0"}, "usage: manibench run"},
      {{"run", "Reach-v0", "--policy", "zero", "--split", "dev"}, "usage: manibench run"},
      {{"info"}, "usage: manibench info"},
      {{"info", "Reach-v0", "--set"}, "usage: manibench info"},
      {{"list", "extra"}, "usage: manibench list"},
      {{"config", "Reach-v0", "Other-v0"}, "usage: manibench config"},
      {{"config", "--bogus"}, "usage: manibench config"},
      {{"demo", "now"}, "usage: manibench demo"},
      {{"demos"}, "usage: manibench demos"},
      {{"demos", "record"}, "usage: manibench demos"},
      {{"demos", "generate", "Reach-v0", "--out", "x.h5"}, "usage: manibench demos"},
      {{"demos", "replay"}, "usage: manibench demos"},
      {{"demos", "convert", "x.h5", "--out", "y.h5"}, "usage: manibench demos"},
  };
  for (const Case& c : cases) {
    const auto r = runCli(c.arguments);
    EXPECT_EQ(r.exit_code, 2) << c.arguments.front();
    EXPECT_TRUE(contains(r.err, c.usage)) << r.err;
    EXPECT_FALSE(contains(r.err, "Commands:")) << r.err;  // not the main usage
  }
  EXPECT_TRUE(contains(runCli({"frobnicate"}).err, "Commands:"));
  const auto help = runCli({"config", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_TRUE(contains(help.out, "usage: manibench config")) << help.out;
}

TEST(Cli, ConfigPrintsTheMergeAsYamlThatReadsBackEqual) {
  const TempYaml file("physics:\n  accuracy: 0.005\ncameras:\n  - name: top\n    far: 30\n");
  const ConfigSources sources{{file.path()}, {"control.frequency=50", "task={hold_steps: 3}"}};
  const auto r = runCli({"config", "Reach-v0", "--config", file.path(), "--set", sources.overrides[0],
                         "--set", sources.overrides[1]});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ConfigNode printed = parseConfig(r.out, "stdout");
  const ConfigNode merged = loadTaskConfig(getBuildTreeRegistry(), "Reach-v0", sources);
  EXPECT_TRUE(isSameConfig(printed, merged)) << r.out;
  EXPECT_EQ(printed.findPath("physics.accuracy")->scalar, "0.005");
  EXPECT_EQ(printed.findPath("control.frequency")->scalar, "50");

  // Plain `config Reach-v0` too; and the printout, fed back as a file,
  // changes nothing.
  const auto plain = runCli({"config", "Reach-v0"});
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_TRUE(isSameConfig(parseConfig(plain.out, "stdout"),
                           loadTaskConfig(getBuildTreeRegistry(), "Reach-v0", {})));
  const TempYaml again(plain.out);
  EXPECT_EQ(runCli({"config", "Reach-v0", "--config", again.path()}).out, plain.out);
  // Without a task: the built-in defaults.
  const auto builtin = runCli({"config"});
  ASSERT_EQ(builtin.exit_code, 0) << builtin.err;
  EXPECT_TRUE(isSameConfig(parseConfig(builtin.out, "stdout"), calcConfig(nullptr, {})));
}

TEST(Cli, ConfigExplainNamesEveryOrigin) {
  const TempYaml file("# tuned\nphysics:\n  default_density: 800\n");
  const auto r = runCli({"config", "Reach-v0", "--explain", "--config", file.path(), "--set",
                         "physics.accuracy=0.001"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "frequency: 100  # task Reach-v0 description")) << r.out;
  EXPECT_TRUE(contains(r.out, "integrator: implicit_euler  # task Reach-v0 defaults:2")) << r.out;
  EXPECT_TRUE(contains(r.out, "gravity: [0, 0, -9.81]  # built-in defaults:")) << r.out;
  EXPECT_TRUE(contains(r.out, "default_density: 800  # " + file.path() + ":3")) << r.out;
  EXPECT_TRUE(contains(r.out, "accuracy: 0.001  # --set physics.accuracy=0.001")) << r.out;
}

TEST(Cli, ConfigErrorsExitOneNamingFileLineAndKey) {
  const TempYaml typo("physics:\n  acuracy: 0.1\n");
  for (const char* command : {"config", "info", "run"}) {
    std::vector<std::string> arguments{command, "Reach-v0", "--config", typo.path()};
    if (std::string(command) == "run") arguments.insert(arguments.end(), {"--policy", "zero"});
    const auto r = runCli(arguments);
    EXPECT_EQ(r.exit_code, 1) << command;
    EXPECT_TRUE(contains(r.err, typo.path() + ":2: physics.acuracy: unknown key (did you mean "
                                              "physics.accuracy?)"))
        << r.err;
  }
  const auto range = runCli({"config", "Reach-v0", "--set", "physics.accuracy=5"});
  EXPECT_EQ(range.exit_code, 1);
  EXPECT_TRUE(contains(range.err, "--set physics.accuracy=5: physics.accuracy: must be in (0, 1], got 5"))
      << range.err;
  const auto missing = runCli({"run", "Reach-v0", "--policy", "zero", "--config", "/nonexistent/my.yaml"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_TRUE(contains(missing.err, "cannot read configuration file '/nonexistent/my.yaml': No such file"))
      << missing.err;
  const TempYaml malformed("physics: {accuracy: 0.1\n");
  const auto parse = runCli({"config", "--config", malformed.path()});
  EXPECT_EQ(parse.exit_code, 1);
  EXPECT_TRUE(contains(parse.err, malformed.path() + ":")) << parse.err;
  EXPECT_TRUE(contains(parse.err, "malformed YAML")) << parse.err;
  const auto no_equals = runCli({"config", "--set", "physics.accuracy"});
  EXPECT_EQ(no_equals.exit_code, 1);
  EXPECT_TRUE(contains(no_equals.err, "expected KEY=VALUE")) << no_equals.err;
}

TEST(Cli, InfoAndRunFollowTheConfiguration) {
  const auto info = runCli({"info", "Reach-v0", "--set", "control.frequency=50", "--set",
                            "control.frame_skip=2", "--controller", "joint_position"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_TRUE(contains(info.out, "control 50 Hz, frame skip 2, 100 steps per episode")) << info.out;
  EXPECT_TRUE(contains(info.out, "controller 'joint_position'")) << info.out;

  const TempYaml file("episode:\n  max_steps: 7\n");
  const auto run = runCli({"run", "Reach-v0", "--policy", "zero", "--config", file.path(), "--no-early-stop"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(contains(run.out, ": 7 steps, return")) << run.out;
}

TEST(Cli, PluginErrorsAboutConfigKeysNameWhereTheyWereSet) {
  const TempYaml file("task:\n  reach_tolerance: wide\n");
  const auto r = runCli({"run", "Reach-v0", "--policy", "zero", "--config", file.path()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.err, "reach_tolerance")) << r.err;
  EXPECT_TRUE(contains(r.err, "task.reach_tolerance is set at " + file.path() + ":2")) << r.err;
}

TEST(Cli, AMistypedTaskKeyIsRefusedWithTheClosestKeyAndWhereItWasSet) {
  const TempYaml file("task:\n  hold_steps: 3\n  reach_tolerence: 0.05\n");
  const auto r = runCli({"run", "Reach-v0", "--policy", "zero", "--config", file.path()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.err, "unknown key 'reach_tolerence', did you mean 'reach_tolerance'?")) << r.err;
  EXPECT_TRUE(contains(r.err, "task.reach_tolerence is set at " + file.path() + ":3")) << r.err;
}

}  // namespace
}  // namespace manibench

namespace manibench {
namespace {

TEST(CliBench, ReportsStepsPerSecond) {
  const auto r = testing::runCli({"bench", "Reach-v0", "--steps", "60", "--policy", "reach_expert"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("60 env steps in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("env steps/s"), std::string::npos) << r.out;
  const auto bad = testing::runCli({"bench", "Reach-v0", "--obs", "depth"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--obs must be state, pointcloud or rgbd"), std::string::npos) << bad.err;
}

// The stages of "per env step (ms): physics A, task B, render C, assembly D,
// policy E, other F; total G", by name.
std::map<std::string, double> parseStages(const std::string& out) {
  std::map<std::string, double> stages;
  const std::string head = "per env step (ms): ";
  const std::size_t at = out.find(head);
  if (at == std::string::npos) return stages;
  std::istringstream line(out.substr(at + head.size(), out.find('\n', at) - at - head.size()));
  std::string name;
  double value = 0;
  while (line >> name >> value) {
    stages[name] = value;
    line.ignore(1);  // ',' or ';'
  }
  return stages;
}

TEST(CliBench, TimesEachStageOfAnEnvStep) {
  for (const char* mode : {"state", "pointcloud", "rgbd"}) {
    const auto r = testing::runCli({"bench", "Reach-v0", "--steps", "30", "--policy", "random", "--obs", mode});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::map<std::string, double> stages = parseStages(r.out);
    ASSERT_EQ(stages.size(), 7u) << r.out;
    for (const char* name : {"physics", "task", "render", "assembly", "policy", "other", "total"})
      ASSERT_EQ(stages.count(name), 1u) << name << "\n" << r.out;
    // Every env step integrates, and the stages are parts of the total
    // (printed to the microsecond, so sums are within rounding).
    EXPECT_GT(stages.at("physics"), 0.0) << r.out;
    EXPECT_GT(stages.at("total"), 0.0) << r.out;
    double sum = 0;
    for (const auto& [name, value] : stages)
      if (name != "total" && name != "other") {
        EXPECT_GE(value, 0.0) << name << "\n" << r.out;
        sum += value;
      }
    EXPECT_LE(sum, stages.at("total") + 0.005) << r.out;
    EXPECT_NEAR(sum + stages.at("other"), stages.at("total"), 0.005) << r.out;
    if (std::string(mode) == "state") {
      EXPECT_EQ(stages.at("render"), 0.0) << "the state mode renders nothing\n" << r.out;
      EXPECT_EQ(stages.at("assembly"), 0.0) << r.out;
    } else {
      EXPECT_GT(stages.at("render"), 0.0) << mode << "\n" << r.out;
      EXPECT_GT(stages.at("assembly"), 0.0) << mode << "\n" << r.out;
    }
  }
}

}  // namespace
}  // namespace manibench
