// SAC online (sac_trainer.hpp) on Reach-v0 with real environment workers:
// the same seed gives the same learning curve, a resumed run continues
// exactly (the workers' environments restored mid-episode), a worker that
// dies or hangs is reported and replaced, the checkpoint runs in the torch_policy
// plugin through `manibench eval`, and a small agent learns Reach.
#include <manibench/learning/sac_trainer.hpp>

#include <test_registry.hpp>
#include <test_support.hpp>

#include "learning_test_support.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <signal.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace manibench::learning {
namespace {

namespace fs = std::filesystem;
using manibench::testing::contains;
using manibench::testing::getBuildTreeRegistry;
using manibench::testing::runCli;

class Sac : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("manibench_sac_test_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string path(const std::string& name) { return (dir_ / name).string(); }

  // A small agent on one Reach arm: a few hundred steps in a second or two.
  static SacOptions makeOptions(const std::string& out, int64_t steps) {
    SacOptions o;
    o.out_dir = path(out);
    o.environment_id = "Reach-v0";
    o.objects = {"0"};
    o.workers = 1;
    o.steps = steps;
    o.replay_size = 10000;
    o.algorithm.batch_size = 32;
    o.network.mlp_hidden = {32, 32};
    o.random_steps = 100;
    o.learning_starts = 64;
    o.log_every = 50;
    o.checkpoint_every = 250;
    return o;
  }
  static fs::path dir_;
};
fs::path Sac::dir_;

// log.csv without its timing columns (seconds, speeds, time shares).
std::vector<std::string> readCurve(const std::string& file) {
  std::ifstream in(file);
  std::vector<std::string> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
    std::string kept;
    for (std::size_t i = 0; i + 6 < cells.size(); ++i)
      if (i != 2) kept += cells[i] + ",";
    rows.push_back(kept);
  }
  return rows;
}

// episodes.csv's rows as object, seed, steps and return, in the file's order.
std::vector<std::string> readEpisodes(const std::string& file) {
  std::ifstream in(file);
  std::vector<std::string> rows;
  std::string line;
  std::getline(in, line);  // index,object,level,seed,steps,return,...
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
    if (cells.size() > 5) rows.push_back(cells[1] + "," + cells[3] + "," + cells[4] + "," + cells[5]);
  }
  return rows;
}

TEST_F(Sac, TheSameSeedGivesTheSameCurveAndAResumedRunContinuesExactly) {
  const SacResult a = trainSac(getBuildTreeRegistry(), makeOptions("a", 600), {});
  const SacResult b = trainSac(getBuildTreeRegistry(), makeOptions("b", 600), {});
  EXPECT_EQ(a.env_steps, 600);
  EXPECT_EQ(a.updates, 600 - 64);  // one per env step once the buffer holds 64
  EXPECT_EQ(a.episodes, 6);
  EXPECT_TRUE(sameWeights(a.checkpoint, b.checkpoint));
  const std::vector<std::string> curve = readCurve(path("a/log.csv"));
  EXPECT_EQ(curve.size(), 13u);
  EXPECT_EQ(curve, readCurve(path("b/log.csv")));

  // Stopped at 250 env steps (in the third episode), resumed to 600, its
  // train.yaml in the layout before RunOptions (flat eval_every,
  // eval_episodes, eval_seed): an older run directory resumes as well.
  const SacResult first = trainSac(getBuildTreeRegistry(), makeOptions("c", 250), {});
  EXPECT_EQ(first.env_steps, 250);
  {
    YAML::Node node = YAML::LoadFile(path("c/train.yaml"));
    for (const std::string key : {"every", "episodes", "seed"}) node["eval_" + key] = node["evaluation"][key];
    node.remove("evaluation");
    std::ofstream(path("c/train.yaml")) << YAML::Dump(node) << "\n";
  }
  std::vector<std::string> messages;
  SacHooks hooks;
  hooks.on_message = [&](const std::string& line) { messages.push_back(line); };
  const SacResult resumed = resumeSac(getBuildTreeRegistry(), path("c"), 600, hooks);
  EXPECT_EQ(resumed.env_steps, 600);
  EXPECT_TRUE(sameWeights(a.checkpoint, resumed.checkpoint));
  EXPECT_EQ(curve, readCurve(path("c/log.csv")));
  EXPECT_TRUE(std::any_of(messages.begin(), messages.end(),
                          [](const std::string& m) { return contains(m, "resuming from"); }));
  // Only the newest checkpoint keeps its replay buffer.
  EXPECT_TRUE(fs::exists(path("c/checkpoints/replay_0000600.pt")));
  EXPECT_FALSE(fs::exists(path("c/checkpoints/replay_0000250.pt")));

  SacOptions other = makeOptions("d", 600);
  other.seed = 1;
  EXPECT_FALSE(sameWeights(a.checkpoint, trainSac(getBuildTreeRegistry(), other, {}).checkpoint));
}

TEST_F(Sac, ADyingWorkerIsReportedAndReplaced) {
  SacOptions o = makeOptions("dying", 400);
  o.workers = 2;
  std::vector<std::string> messages;
  pid_t killed = 0, killed_at_checkpoint = 0;
  std::vector<pid_t> last_pids;
  bool replacement_alive = false;
  SacHooks hooks;
  hooks.on_message = [&](const std::string& line) { messages.push_back(line); };
  hooks.on_progress = [&](const SacProgress& p) {
    last_pids = p.worker_pids;
    if (killed != 0 && p.worker_pids.at(1) != killed) replacement_alive = ::kill(p.worker_pids[1], 0) == 0;
    if (killed == 0 && p.env_steps >= 120) {
      killed = p.worker_pids.at(1);
      ::kill(killed, SIGKILL);
    }
    // Just before the checkpoint at 250 env steps asks the workers for their states.
    if (killed_at_checkpoint == 0 && p.env_steps >= 250) {
      killed_at_checkpoint = p.worker_pids.at(0);
      ::kill(killed_at_checkpoint, SIGKILL);
    }
  };
  const SacResult r = trainSac(getBuildTreeRegistry(), o, hooks);
  EXPECT_GE(r.env_steps, 400);
  ASSERT_NE(killed, 0);
  const auto died = std::find_if(messages.begin(), messages.end(), [&](const std::string& m) {
    return contains(m, "environment worker 1 (pid " + std::to_string(killed) + ") killed by signal 9 (SIGKILL");
  });
  ASSERT_NE(died, messages.end());
  EXPECT_TRUE(contains(*died, "is dropped")) << *died;
  ASSERT_EQ(last_pids.size(), 2u);
  EXPECT_NE(last_pids[1], killed);
  EXPECT_TRUE(replacement_alive);
  ASSERT_NE(killed_at_checkpoint, 0);
  EXPECT_TRUE(std::any_of(messages.begin(), messages.end(), [&](const std::string& m) {
    return contains(m, "environment worker 0 (pid " + std::to_string(killed_at_checkpoint) + ") killed by signal 9 (SIGKILL");
  }));
  int checkpoints = 0;
  for (const auto& entry : fs::directory_iterator(path("dying/checkpoints")))
    checkpoints += entry.path().filename().string().rfind("iter_", 0) == 0 ? 1 : 0;
  EXPECT_EQ(checkpoints, 2);  // at 250 (or 251: a dropped step shifts the count) and at the end
}

// A worker that stops answering (SIGSTOP: as a task stuck in a loop or a
// system call) is killed after the reply timeout and replaced; the run
// goes on to its end.
TEST_F(Sac, AHangingWorkerIsKilledAndReplaced) {
  SacOptions o = makeOptions("hanging", 300);
  o.workers = 2;
  o.worker_timeout = 3;
  std::vector<std::string> messages;
  pid_t stopped = 0;
  std::vector<pid_t> last_pids;
  SacHooks hooks;
  hooks.on_message = [&](const std::string& line) { messages.push_back(line); };
  hooks.on_progress = [&](const SacProgress& p) {
    last_pids = p.worker_pids;
    if (stopped == 0 && p.env_steps >= 100) {
      stopped = p.worker_pids.at(1);
      ::kill(stopped, SIGSTOP);
    }
  };
  const SacResult r = trainSac(getBuildTreeRegistry(), o, hooks);
  EXPECT_GE(r.env_steps, 300);
  ASSERT_NE(stopped, 0);
  const auto hung = std::find_if(messages.begin(), messages.end(), [&](const std::string& m) {
    return contains(m, "environment worker 1 (pid " + std::to_string(stopped) + ") did not answer within 3 s; killed it");
  });
  ASSERT_NE(hung, messages.end());
  EXPECT_TRUE(contains(*hung, "is dropped")) << *hung;
  ASSERT_EQ(last_pids.size(), 2u);
  EXPECT_NE(last_pids[1], stopped);
  // Killed, not left stopped: the pid is gone (or, reaped and reused, no longer stopped).
  std::ifstream stat("/proc/" + std::to_string(stopped) + "/stat");
  std::string line;
  if (std::getline(stat, line)) {
    EXPECT_FALSE(contains(line, ") T ")) << line;
  }
}

TEST_F(Sac, TheTorchPolicyPluginRunsTheAgent) {
  const SacResult r = trainSac(getBuildTreeRegistry(), makeOptions("plugin", 200), {});
  const manibench::testing::CommandResult eval =
      runCli({"eval", "Reach-v0", "--split", "train", "--objects", "0", "--policy", "torch_policy", "--policy-config",
              path("plugin/policy.yaml"), "--episodes-per-object", "2", "--no-progress", "--out", path("plugin/eval")});
  ASSERT_EQ(eval.exit_code, 0) << eval.err;
  EXPECT_TRUE(fs::exists(path("plugin/eval/summary.json")));
  EXPECT_TRUE(contains(r.checkpoint, "iter_0000200.pt"));
}

// --eval-every: the deterministic actor through `manibench eval` at 100
// and 200 env steps, one row each in eval.csv.
TEST_F(Sac, PeriodicEvaluationsGoToEvalCsv) {
  const manibench::testing::CommandResult r =
      runCli({"train", "sac", "Reach-v0", "--objects", "0", "--out", path("evaluated"), "--steps", "200",
              "--workers", "1", "--batch-size", "32", "--hidden", "16", "--random-steps", "100", "--learning-starts",
              "64", "--eval-every", "100", "--eval-episodes", "2", "--no-progress"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream csv(path("evaluated/eval.csv"));
  std::vector<std::string> lines;
  for (std::string line; std::getline(csv, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0], "env_steps,episodes,successes,success_rate");
  EXPECT_EQ(lines[1].rfind("100,2,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[2].rfind("200,2,", 0), 0u) << lines[2];
  EXPECT_TRUE(fs::exists(path("evaluated/eval/iter_0000100/summary.json")));
  EXPECT_TRUE(fs::exists(path("evaluated/checkpoints/iter_0000100.pt")));
  EXPECT_TRUE(contains(r.err, "evaluation at 200 env steps: success")) << r.err;
}

// Two Reach objects at a budget no agent succeeds in: each is retrained
// once with its next seed, both end below the threshold with their own
// directories and policy configurations; the same command again finds
// them done.
TEST_F(Sac, APopulationTrainsOneAgentPerObjectAndRetrainsThoseBelowTheThreshold) {
  const std::vector<std::string> command = {
      "train", "sac-population", "Reach-v0", "--objects", "0,1", "--out", path("population"), "--steps", "200",
      "--workers", "1", "--batch-size", "32", "--hidden", "16", "--random-steps", "100", "--learning-starts", "64",
      "--max-attempts", "2", "--eval-episodes", "1", "--demos", "1"};
  const manibench::testing::CommandResult first = runCli(command);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  for (const std::string object : {"0", "1"}) {
    const fs::path dir = path("population/objects/" + object);
    EXPECT_TRUE(fs::exists(dir / "attempt_0/checkpoints/iter_0000200.pt")) << object;
    EXPECT_TRUE(fs::exists(dir / "attempt_1/checkpoints/iter_0000200.pt")) << object;
    EXPECT_TRUE(fs::exists(dir / "policy.yaml")) << object;
    EXPECT_TRUE(contains(first.err, "object " + object + ": no demonstrations (its agent is below the threshold)"));
    // Its own seed per attempt, from the base seed and the object id.
    const YAML::Node a = YAML::LoadFile((dir / "attempt_0/train.yaml").string());
    const YAML::Node b = YAML::LoadFile((dir / "attempt_1/train.yaml").string());
    EXPECT_NE(a["seed"].as<uint64_t>(), b["seed"].as<uint64_t>());
    EXPECT_EQ(a["environment"].as<std::string>(), "Reach_" + object + "-v0");
    EXPECT_EQ(a["workers"].as<unsigned>(), 1u);
  }
  const YAML::Node summary = YAML::LoadFile(path("population/population.yaml"));
  EXPECT_EQ(summary["objects"]["0"]["state"].as<std::string>(), "below_threshold");
  EXPECT_EQ(summary["objects"]["1"]["attempts"].as<unsigned>(), 2u);
  EXPECT_NE(YAML::LoadFile((fs::path(path("population/objects/0")) / "attempt_0/train.yaml").string())["seed"].as<uint64_t>(),
            YAML::LoadFile((fs::path(path("population/objects/1")) / "attempt_0/train.yaml").string())["seed"].as<uint64_t>());

  const manibench::testing::CommandResult again = runCli(command);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(contains(again.err, "object 0: done before")) << again.err;
  EXPECT_FALSE(contains(again.err, "training (seed")) << again.err;

  // population.yaml as torch_policy's configuration: each episode is acted
  // by its object's agent (ABI 1.5's reset_episode), so every episode is
  // the one that object's agent makes alone, not the other agent's.
  auto evaluate = [&](const std::string& environment, const std::string& objects, const std::string& config,
                      const std::string& out) {
    const manibench::testing::CommandResult eval =
        runCli({"eval", environment, "--split", "train", "--objects", objects, "--policy", "torch_policy",
                "--policy-config", config,
                "--episodes-per-object", "2", "--no-progress", "--out", path(out)});
    EXPECT_EQ(eval.exit_code, 0) << eval.err;
    return readEpisodes(path(out + "/episodes.csv"));
  };
  const auto both = evaluate("Reach-v0", "0,1", path("population/population.yaml"), "population_eval");
  const auto own0 = evaluate("Reach_0-v0", "0", path("population/objects/0/policy.yaml"), "own0_eval");
  const auto own1 = evaluate("Reach_1-v0", "1", path("population/objects/1/policy.yaml"), "own1_eval");
  const auto other0 = evaluate("Reach_0-v0", "0", path("population/objects/1/policy.yaml"), "other0_eval");
  ASSERT_EQ(both.size(), 4u);
  std::vector<std::string> expected = own0;
  expected.insert(expected.end(), own1.begin(), own1.end());
  EXPECT_EQ(both, expected);
  EXPECT_NE(own0, other0);
}

TEST_F(Sac, BadOptionsAreErrorsThatNameThem) {
  SacOptions o = makeOptions("bad", 100);
  o.objects = {"99"};
  EXPECT_THROW(
      {
        try {
          trainSac(getBuildTreeRegistry(), o, {});
        } catch (const LearningError& e) {
          EXPECT_TRUE(contains(e.what(), "'99' is not an object of Reach-v0")) << e.what();
          throw;
        }
      },
      LearningError);
  EXPECT_FALSE(fs::exists(path("bad/train.yaml")));
}

}  // namespace
}  // namespace manibench::learning
