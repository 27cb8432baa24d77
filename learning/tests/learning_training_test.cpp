// Training from real demonstration files (made by the built CLI from the
// Reach-v0 expert, converted to point clouds by the renderer), checkpoints
// and resumes, the torch_policy plugin loaded through the registry (the
// checkpoint's actions and a TorchScript module written by python3-torch),
// and the errors a user meets.
#include <manibench/learning/checkpoint.hpp>
#include <manibench/learning/compute.hpp>
#include <manibench/learning/dataset.hpp>
#include <manibench/learning/sac_trainer.hpp>
#include <manibench/learning/trainer.hpp>

#include <manibench/demos.hpp>
#include <manibench/environment.hpp>
#include <manibench/plugin_instances.hpp>

#include <test_registry.hpp>
#include "learning_test_support.hpp"
#include <test_support.hpp>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <fcntl.h>
#include <malloc.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

namespace manibench::learning {
namespace {

namespace fs = std::filesystem;
using manibench::testing::contains;
using manibench::testing::getBuildTreeRegistry;
using manibench::testing::runCli;

fs::path g_dir;

std::string file(const std::string& name) { return (g_dir / name).string(); }

class LearningTraining : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    g_dir = fs::temp_directory_path() / ("manibench_learning_test_" + std::to_string(getpid()));
    fs::create_directories(g_dir);
    auto run = [](const std::vector<std::string>& args) {
      const manibench::testing::CommandResult r = runCli(args);
      ASSERT_EQ(r.exit_code, 0) << r.err;
    };
    run({"demos", "generate", "Reach-v0", "--policy", "reach_expert", "--split", "train", "--per-object", "2",
         "--workers", "2", "--no-progress", "--out", file("reach.h5")});
    run({"demos", "convert", file("reach.h5"), "--obs", "pointcloud", "--trajectories", "traj_0,traj_1,traj_2,traj_3",
         "--workers", "2", "--no-progress", "--out", file("reach_pc.h5")});
    run({"demos", "generate", "Reach-v0", "--policy", "reach_expert", "--split", "train", "--objects", "0",
         "--per-object", "1", "--action-noise", "0.05", "--no-progress", "--out", file("reach_noisy.h5")});
    run({"demos", "generate", "OpenCabinetDrawer_2000_link_0-v0", "--policy", "open_cabinet_expert", "--controller",
         "mobile_panda_ee", "--per-object", "1", "--no-progress", "--out", file("drawer.h5")});
  }
  static void TearDownTestSuite() { fs::remove_all(g_dir); }

  static TrainOptions makeOptions(const std::string& algorithm, const std::string& out, int64_t iterations) {
    TrainOptions o;
    o.algorithm = AlgorithmOptions::makeDefaults(algorithm);
    o.algorithm.batch_size = 32;
    o.data.paths = {file("reach.h5")};
    o.out_dir = file(out);
    o.iterations = iterations;
    o.checkpoint_every = iterations;
    o.log_every = 10;
    return o;
  }
};

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_F(LearningTraining, BcDrivesTheLossOnOneShortTrajectoryNearZero) {
  TrainOptions o = makeOptions("bc", "one_trajectory", 1500);
  o.data.objects = {"0"};
  o.data.per_object = 1;
  o.algorithm.batch_size = 8;
  o.algorithm.weight_decay = 0;
  const TrainResult r = train(getBuildTreeRegistry(), o, {});
  EXPECT_EQ(r.iteration, 1500);
  // log.csv: iteration,seconds,loss,iterations_per_second; the first and last rows.
  std::ifstream log(file("one_trajectory/log.csv"));
  std::string header, line, first, last;
  std::getline(log, header);
  EXPECT_EQ(header, "iteration,seconds,loss,iterations_per_second");
  while (std::getline(log, line)) (first.empty() ? first : last) = line;
  auto loss = [](const std::string& row) {
    const std::size_t a = row.find(',', row.find(',') + 1) + 1;
    return std::stod(row.substr(a, row.find(',', a) - a));
  };
  // BC's state-mode defaults (tanh, Adam 1e-3): the last 10 iterations
  // averaged 5.3e-5 (2026-11-28; at 3e-4 the tanh made it 1.0e-4).
  EXPECT_LT(loss(last), 1e-4) << last;
  EXPECT_LT(loss(last), loss(first) / 100) << first << " / " << last;
}

TEST_F(LearningTraining, TheSameSeedGivesTheSameWeightsAndAnotherSeedOthers) {
  const TrainResult a = train(getBuildTreeRegistry(), makeOptions("bc", "seed_a", 40), {});
  const TrainResult b = train(getBuildTreeRegistry(), makeOptions("bc", "seed_b", 40), {});
  TrainOptions other = makeOptions("bc", "seed_c", 40);
  other.seed = 1;
  const TrainResult c = train(getBuildTreeRegistry(), other, {});
  EXPECT_TRUE(sameWeights(a.checkpoint, b.checkpoint));
  EXPECT_FALSE(sameWeights(a.checkpoint, c.checkpoint));
}

// log.csv without its timing columns (seconds, iterations per second).
std::vector<std::string> readLosses(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> rows;
  for (std::string line; std::getline(in, line);) {
    const std::size_t a = line.find(','), b = line.find(',', a + 1), c = line.rfind(',');
    rows.push_back(line.substr(0, a) + line.substr(b, c - b));
  }
  return rows;
}

// train.yaml as manibench wrote it before RunOptions: the evaluation's
// device at the top level as eval_device (the rest as now).
void rewriteInTheOldLayout(const std::string& dir) {
  const std::string file = (fs::path(dir) / "train.yaml").string();
  YAML::Node node = YAML::LoadFile(file);
  node["eval_device"] = node["evaluation"]["device"].as<std::string>();
  node["evaluation"].remove("device");
  std::ofstream(file) << YAML::Dump(node) << "\n";
}

TEST_F(LearningTraining, OneRunOptionsLayoutAndTheOldLayoutsStillRead) {
  // train.yaml's layout (RunOptions): the shared keys at the top level,
  // every evaluation key under `evaluation:`; each program's round trip.
  TrainOptions t = makeOptions("bc", "layout", 10);
  t.seed = 3;
  t.eval_every = 5;
  t.eval_episodes = 2;
  t.eval_seed = 77;
  t.eval_split = "test";
  t.eval_device = "cuda";
  YAML::Node node;
  t.writeYaml(node);
  for (const char* key : {"out_dir", "algorithm", "network", "seed", "threads", "device", "checkpoint_every",
                          "log_every", "command", "data", "iterations"})
    EXPECT_TRUE(node[key].IsDefined()) << key;
  for (const char* key : {"every", "episodes", "seed", "task", "split", "objects", "workers", "device"})
    EXPECT_TRUE(node["evaluation"][key].IsDefined()) << key;
  EXPECT_FALSE(node["eval_device"].IsDefined());
  EXPECT_EQ(YAML::Dump(node), [&] {
    YAML::Node again;
    TrainOptions::readYaml(node).writeYaml(again);
    return YAML::Dump(again);
  }());
  // The demonstration trainer's layout before: eval_device at the top level.
  node["eval_device"] = "cuda";
  node["evaluation"].remove("device");
  EXPECT_EQ(TrainOptions::readYaml(node).eval_device, "cuda");

  SacOptions s;
  s.out_dir = "sac";
  s.environment_id = "Reach-v0";
  s.eval_every = 100;
  s.eval_episodes = 3;
  s.eval_seed = 9;
  YAML::Node sac;
  s.writeYaml(sac);
  EXPECT_EQ(sac["evaluation"]["every"].as<int64_t>(), 100);
  EXPECT_FALSE(sac["eval_every"].IsDefined());
  EXPECT_EQ(sac["algorithm"]["name"].as<std::string>(), "sac");  // what `train --resume` dispatches on
  // SAC's layout before: flat eval_every, eval_episodes, eval_seed (each
  // absent in still older files: the defaults).
  sac.remove("evaluation");
  sac["eval_every"] = 200;
  sac["eval_episodes"] = 4;
  sac["eval_seed"] = 5;
  const SacOptions old = SacOptions::readYaml(sac);
  EXPECT_EQ(old.eval_every, 200);
  EXPECT_EQ(old.eval_episodes, 4u);
  EXPECT_EQ(old.eval_seed, 5u);
  sac.remove("eval_every");
  sac.remove("eval_episodes");
  sac.remove("eval_seed");
  const SacOptions older = SacOptions::readYaml(sac);
  EXPECT_EQ(older.eval_every, 0);
  EXPECT_EQ(older.eval_episodes, 10u);
  EXPECT_EQ(older.eval_seed, 1000u);
  EXPECT_EQ(older.checkpoint_every, s.checkpoint_every);

  // One check: the shared options' refusals name the option in both programs.
  auto refusal = [](const auto& options) {
    try {
      options.check();
    } catch (const LearningError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  TrainOptions bad_t = t;
  bad_t.log_every = 0;
  SacOptions bad_s = s;
  bad_s.log_every = 0;
  EXPECT_TRUE(contains(refusal(bad_t), "--log-every")) << refusal(bad_t);
  EXPECT_TRUE(contains(refusal(bad_s), "--log-every")) << refusal(bad_s);
  bad_t = t;
  bad_t.out_dir.clear();
  EXPECT_TRUE(contains(refusal(bad_t), "--out")) << refusal(bad_t);
}

TEST_F(LearningTraining, ARunDirectoryWrittenInTheOldLayoutResumesExactly) {
  const TrainResult straight = train(getBuildTreeRegistry(), makeOptions("bc", "old_straight", 40), {});
  TrainOptions o = makeOptions("bc", "old_layout", 20);
  o.eval_device = "cpu";
  train(getBuildTreeRegistry(), o, {});
  rewriteInTheOldLayout(file("old_layout"));
  const TrainResult resumed = resumeTraining(getBuildTreeRegistry(), file("old_layout"), 40, {});
  EXPECT_EQ(resumed.iteration, 40);
  EXPECT_TRUE(sameWeights(straight.checkpoint, resumed.checkpoint));
  EXPECT_EQ(readLosses(file("old_straight/log.csv")), readLosses(file("old_layout/log.csv")));
  // The resumed run wrote its train.yaml again, in the one layout.
  EXPECT_TRUE(YAML::LoadFile(file("old_layout/train.yaml"))["evaluation"]["device"].IsDefined());
}

TEST_F(LearningTraining, AResumedTrainingContinuesExactly) {
  struct Case {
    std::string algorithm, data;
    NetKind net;
    int64_t iterations;
  };
  // TD3+BC: targets, a delayed actor, noise; pn_transformer: dropout.
  for (const Case& c : {Case{"td3bc", "reach.h5", NetKind::Mlp, 30}, Case{"bcq", "reach.h5", NetKind::Mlp, 20},
                        Case{"bc", "reach_pc.h5", NetKind::PnTransformer, 6}}) {
    SCOPED_TRACE(c.algorithm + " " + toString(c.net));
    auto options = [&](const std::string& out, int64_t iterations, bool prefetch) {
      TrainOptions o = makeOptions(c.algorithm, out, iterations);
      o.prefetch = prefetch;
      o.data.paths = {file(c.data)};
      o.network.kind = c.net;
      o.network.width = 32;
      o.network.layers = 1;
      o.algorithm.batch_size = 8;
      o.checkpoint_every = 1000;
      return o;
    };
    const std::string name = c.algorithm + "_" + toString(c.net);
    const TrainResult straight = train(getBuildTreeRegistry(), options(name + "_straight", c.iterations, false), {});
    // A run stopped half-way (as Ctrl-C does: a checkpoint at the stop), then
    // resumed; it gathers its batches ahead (what CUDA does), so at the stop
    // one batch was gathered and not trained on: the checkpoint must say so.
    int64_t seen = 0;
    TrainHooks stop_half_way;
    stop_half_way.on_progress = [&](const TrainProgress& p) { seen = p.iteration; };
    stop_half_way.should_stop = [&] { return seen >= c.iterations / 2; };
    const TrainResult stopped =
        train(getBuildTreeRegistry(), options(name + "_resumed", c.iterations, true), stop_half_way);
    EXPECT_TRUE(stopped.interrupted);
    EXPECT_EQ(stopped.iteration, c.iterations / 2);
    const TrainResult resumed = resumeTraining(getBuildTreeRegistry(), file(name + "_resumed"), 0, {});
    EXPECT_EQ(resumed.iteration, c.iterations);
    EXPECT_TRUE(sameWeights(straight.checkpoint, resumed.checkpoint));
    // The loss log reads as one run's.
    EXPECT_EQ(readLosses(file(name + "_straight/log.csv")), readLosses(file(name + "_resumed/log.csv")));
  }
}

// The observations of a trajectory as the host hands them to a policy.
struct Recorded {
  Eigen::VectorXd state;
  VisualObservation visual;
};
std::vector<Recorded> readObservations(const std::string& path, int count) {
  DemoReader reader(path);
  const Trajectory t = reader.read(reader.getTrajectoryNames().front(), false);
  std::vector<Recorded> out;
  for (uint32_t i = 0; i < uint32_t(count) && i < t.getObservationCount(); ++i)
    out.push_back({t.getObservationState(i), t.getVisualObservation(i)});
  return out;
}

std::unique_ptr<Environment> makeEnvironmentOf(const std::string& demos) {
  DemoReader reader(demos);
  return makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
}

// The torch_policy plugin on TorchScript file `model`, acting on the first
// three recorded observations of `demos`: check(recorded, action) each.
template <class Check>
void actOnRecorded(const std::string& demos, const std::string& model, Check check) {
  const auto env = makeEnvironmentOf(demos);
  PolicyInstance policy(getBuildTreeRegistry(), "torch_policy", "torchscript: '" + model + "'",
                        env->calcPolicyLayout());
  for (const Recorded& r : readObservations(demos, 3)) {
    Eigen::VectorXd action(2);
    policy.act(r.state, 0, action, r.visual);
    check(r, action);
  }
}

TEST_F(LearningTraining, ThePolicyPluginActsAsTheNetwork) {
  for (const std::string data : {"reach.h5", "reach_pc.h5", "history"}) {
    SCOPED_TRACE(data);
    TrainOptions o = makeOptions("bc", "plugin_" + data, 20);
    o.data.paths = {file(data == "history" ? "reach.h5" : data)};
    o.network.kind = data == "reach_pc.h5" ? NetKind::PnTransformer : NetKind::Mlp;
    o.network.layers = 1;
    if (data == "history") {
      o.network.history = 3;
      o.network.step_input = true;
    }
    const TrainResult r = train(getBuildTreeRegistry(), o, {});
    const LoadedCheckpoint loaded = loadCheckpoint(r.checkpoint, torch::kCPU, false);
    const auto env = makeEnvironmentOf(o.data.paths[0]);
    PolicyInstance policy(getBuildTreeRegistry(), "torch_policy", "checkpoint: '" + r.checkpoint + "'",
                          env->calcPolicyLayout());
    policy.reset(0);
    DemoReader reader(o.data.paths[0]);
    const Trajectory t = reader.read("traj_0", false);
    DatasetOptions d;
    d.paths = o.data.paths;
    const DemoDataset dataset(d);
    const DataChunk chunk = dataset.load({0});
    at::Generator generator = at::detail::createCPUGenerator(0);
    for (uint32_t i = 0; i < 5; ++i) {
      Eigen::VectorXd action(2);
      policy.act(t.getObservationState(i), i, action, t.getVisualObservation(i));
      const torch::Tensor expected =
          loaded.algorithm->act(chunk.gatherObservations(torch::tensor({int64_t(i)}), o.network), generator);
      for (int j = 0; j < 2; ++j) EXPECT_EQ(action[j], double(expected[0][j].item<float>())) << "step " << i;
    }
  }
}

TEST_F(LearningTraining, InputsWithHistoryAreBuiltAlikeWhileActingAndTraining) {
  DatasetOptions d;
  d.paths = {file("reach.h5")};
  const DemoDataset dataset(d);
  const DataChunk chunk = dataset.load({1, 0});  // the second trajectory first: rows do not start at 0
  const ObservationSpec spec = calcDemoSpec(getBuildTreeRegistry(), dataset);
  NetOptions inputs;
  inputs.history = 3;
  inputs.action_history = 2;
  inputs.step_input = true;
  // Reach has no mobile base: a frame made up of its first values.
  inputs.robot_frame.base_position = 0;
  inputs.robot_frame.base_yaw = 2;
  inputs.robot_frame.entries = {{"points", RobotFrameInputs::Kind::Points, 3, 6},
                                {"pose", RobotFrameInputs::Kind::Pose, 8, 7}};
  EXPECT_EQ(calcInputStateDim(inputs, spec), 3 * 15 + 2 * 2 + 1 + 13);
  InputHistory history(inputs, spec);
  const int64_t first = dataset.getTrajectories()[1].steps + 1;  // trajectory 0's first row
  for (int episode = 0; episode < 2; ++episode) {  // reset() starts over
    history.reset();
    for (int64_t t = 0; t < 6; ++t) {
      const torch::Tensor row = torch::tensor({first + t});
      const torch::Tensor acting = history.makeInput(chunk.state.index_select(0, row), t);
      const torch::Tensor training = chunk.gatherObservations(row, inputs).state;
      ASSERT_TRUE(torch::equal(acting, training)) << "step " << t << "\n" << acting << training;
      history.setAction(chunk.actions[chunk.obs_transition[first + t].item<int64_t>()]);
    }
  }
}

TEST_F(LearningTraining, ATorchScriptModuleFromPythonRunsThroughThePlugin) {
  const std::string script = file("export.py"), state = file("state.pt"), cloud = file("cloud.pt");
  std::ofstream(script) << R"(import sys
from typing import Dict
import torch
class State(torch.nn.Module):
    def forward(self, obs: Dict[str, torch.Tensor]) -> torch.Tensor:
        return torch.tanh(0.5 * obs["state"][:, 0:2] + 0.1)
class Cloud(torch.nn.Module):
    def forward(self, obs: Dict[str, torch.Tensor]) -> torch.Tensor:
        seen = obs["seg"][:, :, 0].to(torch.float32)
        mean = (obs["xyz"][:, :, 0] * seen).sum(1) / seen.sum(1).clamp(min=1.0)
        return torch.stack([mean, obs["agent"][:, 1] * 0.0 + 0.25], dim=1)
torch.jit.save(torch.jit.script(State()), sys.argv[1])
torch.jit.save(torch.jit.script(Cloud()), sys.argv[2])
)";
  const std::string command = "/usr/bin/python3 " + script + " " + state + " " + cloud;
  ASSERT_EQ(std::system(command.c_str()), 0) << command << ": python3-torch is needed (scripts/install-deps)";
  actOnRecorded(file("reach.h5"), state, [](const Recorded& r, const Eigen::VectorXd& action) {
    for (int j = 0; j < 2; ++j) EXPECT_NEAR(action[j], std::tanh(0.5 * float(r.state[j]) + 0.1), 1e-6);
  });
  actOnRecorded(file("reach_pc.h5"), cloud, [](const Recorded& r, const Eigen::VectorXd& action) {
    double sum = 0, count = 0;
    const std::size_t n = r.visual.points.size();
    for (std::size_t p = 0; p < n; ++p)
      if (r.visual.points.masks[p * r.visual.points.mask_count] != 0) {
        sum += r.visual.points.xyz[3 * p];
        ++count;
      }
    ASSERT_GT(count, 0) << n << " points, " << r.visual.points.mask_count << " masks, " << r.visual.points.masks.size() << " mask bytes";
    EXPECT_NEAR(action[0], sum / count, 1e-5);
    EXPECT_EQ(action[1], 0.25);
  });
  // And an evaluation through the kit: workers load libtorch after their fork.
  std::ofstream(file("script_policy.yaml")) << "torchscript: '" << state << "'\n";
  const auto r = runCli({"eval", "Reach-v0", "--policy", "torch_policy", "--policy-config", file("script_policy.yaml"),
                         "--split", "train", "--objects", "0,1", "--episodes-per-object", "1", "--workers", "2",
                         "--no-progress", "--out", file("script_eval")});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(readFile(file("script_eval/summary.csv")), "all,2,")) << readFile(file("script_eval/summary.csv"));
  EXPECT_FALSE(contains(readFile(file("script_eval/episodes.csv")), "policy_error"));
}

TEST_F(LearningTraining, TrainEvaluatesThroughTheCommandLine) {
  const auto r = runCli({"train", "bc", "--demos", file("reach.h5"), "--out", file("cli_run"), "--iterations", "60",
                         "--batch-size", "16", "--eval-every", "30", "--eval-objects", "0", "--eval-episodes", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "BLAS: ")) << r.err;
  EXPECT_TRUE(contains(r.err, "intra-op thread")) << r.err;
  const std::string eval = readFile(file("cli_run/eval.csv"));
  EXPECT_TRUE(contains(eval, "\n30,train,1,")) << eval;
  EXPECT_TRUE(contains(eval, "\n60,train,1,")) << eval;
  // The training's own checkpoint runs trusted: sandboxed, a policy as slow as
  // BCQ on point clouds ran out of the sandbox's CPU time in every episode.
  const std::string summary = readFile(file("cli_run/eval/iter_30/summary.json"));
  EXPECT_TRUE(contains(summary, "\"sandbox\": false")) << summary;
  EXPECT_TRUE(fs::exists(file("cli_run/checkpoints/iter_0000060.pt")));
  EXPECT_TRUE(contains(readFile(file("cli_run/policy.yaml")), "iter_0000060.pt"));
  // Evaluation runs on the CPU unless asked, whatever trained the checkpoint.
  EXPECT_TRUE(contains(readFile(file("cli_run/policy.yaml")), "\ndevice: cpu\n")) << readFile(file("cli_run/policy.yaml"));
  // Starting again into the same directory is refused; --resume to more iterations is not.
  const auto again = runCli({"train", "bc", "--demos", file("reach.h5"), "--out", file("cli_run")});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_TRUE(contains(again.err, "holds a training already")) << again.err;
  const auto resumed = runCli({"train", "--resume", file("cli_run"), "--iterations", "70"});
  EXPECT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_TRUE(fs::exists(file("cli_run/checkpoints/iter_0000070.pt")));
  const auto usage = runCli({"train", "--demos", file("reach.h5")});
  EXPECT_EQ(usage.exit_code, 2);
  EXPECT_TRUE(contains(usage.err, "name one algorithm")) << usage.err;
}

// Ctrl-C reaches the whole process group: the periodic evaluation's
// `manibench eval` stops too (exit 130, its partial results written). The
// training stops as interrupted, not as a failed evaluation, and --resume
// evaluates that checkpoint again, keeping the episodes it had finished.
TEST_F(LearningTraining, CtrlCDuringAnEvaluationStopsCleanlyAndResumeEvaluatesAgain) {
  const std::string dir = file("ctrl_c_run"), pid_file = file("ctrl_c_run.pid");
  std::thread training([&] {
    const auto r = runCli({"train", "bc", "--demos", file("reach.h5"), "--out", dir, "--iterations", "40",
                           "--batch-size", "16", "--eval-every", "20", "--eval-objects", "0", "--eval-episodes",
                           "40"},
                          {}, [&] {
                            // In the forked child: a process group of its own
                            // (the test's is not signalled), its id written.
                            setpgid(0, 0);
                            char text[32];
                            const int n = snprintf(text, sizeof text, "%d", int(getpid()));
                            const int fd = open(pid_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
                            if (fd >= 0 && write(fd, text, size_t(n)) == n) close(fd);
                          });
    EXPECT_EQ(r.exit_code, 130) << r.err;
    EXPECT_TRUE(contains(r.err, "iteration 20: the evaluation was interrupted; --resume")) << r.err;
    EXPECT_FALSE(contains(r.err, "failed")) << r.err;
  });
  // The signal once the evaluation at iteration 20 has journaled episodes.
  const fs::path journal = fs::path(dir) / "eval" / "iter_20" / "journal.jsonl";
  const auto journalLines = [&] {
    const std::string text = fs::exists(journal) ? readFile(journal.string()) : std::string();
    return std::count(text.begin(), text.end(), '\n');
  };
  for (int i = 0; i < 6000 && journalLines() < 3; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const pid_t group = pid_t(std::atoi(readFile(pid_file).c_str()));
  ASSERT_GT(group, 0);
  EXPECT_GE(journalLines(), 3) << "the evaluation journaled no episode in 120 s";
  kill(-group, SIGINT);
  training.join();
  EXPECT_FALSE(contains(readFile(dir + "/eval.csv"), "\n20,")) << readFile(dir + "/eval.csv");
  EXPECT_TRUE(fs::exists(dir + "/checkpoints/iter_0000020.pt"));
  EXPECT_FALSE(fs::exists(dir + "/checkpoints/iter_0000040.pt"));

  const auto resumed = runCli({"train", "--resume", dir});
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  const std::string eval = readFile(dir + "/eval.csv");
  EXPECT_TRUE(contains(eval, "\n20,train,40,")) << eval;
  EXPECT_TRUE(contains(eval, "\n40,train,40,")) << eval;
  EXPECT_EQ(std::count(eval.begin(), eval.end(), '\n'), 3) << eval;
  EXPECT_TRUE(contains(readFile(dir + "/eval/iter_20/eval.log"), "resuming: ")) << readFile(dir + "/eval/iter_20/eval.log");
  EXPECT_FALSE(fs::exists(dir + "/eval_pending"));
}

TEST_F(LearningTraining, BadInputsAreClearErrors) {
  const PluginRegistry& registry = getBuildTreeRegistry();
  auto message = [&](TrainOptions o) {
    try {
      train(registry, o, {});
    } catch (const LearningError& e) {
      return std::string(e.what());
    }
    ADD_FAILURE() << "trained";
    return std::string();
  };
  // A missing file.
  TrainOptions o = makeOptions("bc", "missing", 10);
  o.data.paths = {file("nothing.h5")};
  std::string m = message(o);
  EXPECT_TRUE(contains(m, "no such demonstration file") && contains(m, "nothing.h5")) << m;
  // Files of two tasks, and of two modes: both named.
  o = makeOptions("bc", "mixed", 10);
  o.data.paths = {file("reach.h5"), file("drawer.h5")};
  m = message(o);
  EXPECT_TRUE(contains(m, "disagree on the task") && contains(m, "Reach-v0") && contains(m, "OpenCabinetDrawer-v0"))
      << m;
  o.data.paths = {file("reach.h5"), file("reach_pc.h5")};
  m = message(o);
  EXPECT_TRUE(contains(m, "observation mode") && contains(m, "reach_pc.h5")) << m;
  // A network of the wrong mode.
  o = makeOptions("bc", "wrong_net", 10);
  o.network.kind = NetKind::PointNet;
  m = message(o);
  EXPECT_TRUE(contains(m, "needs pointcloud observations")) << m;
  // A loss that is not finite stops the training, naming the iteration.
  o = makeOptions("bc", "diverges", 200);
  o.algorithm.lr = 1e30;
  m = message(o);
  EXPECT_TRUE(contains(m, "iteration ") && contains(m, "the loss is") && contains(m, "training stopped")) << m;
}

TEST_F(LearningTraining, ACheckpointOfAnotherTaskIsRefusedNamingBoth) {
  const TrainResult r = train(getBuildTreeRegistry(), makeOptions("bc", "other_task", 10), {});
  const auto env = makeEnvironmentOf(file("drawer.h5"));
  try {
    PolicyInstance policy(getBuildTreeRegistry(), "torch_policy", "checkpoint: '" + r.checkpoint + "'",
                          env->calcPolicyLayout());
    FAIL() << "a Reach checkpoint ran on OpenCabinetDrawer";
  } catch (const std::exception& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, "the task of the checkpoint") && contains(m, "Reach-v0") &&
                contains(m, "OpenCabinetDrawer-v0"))
        << m;
  }
  // A key the plugin does not know, and a checkpoint that is not there.
  EXPECT_THROW(PolicyInstance(getBuildTreeRegistry(), "torch_policy", "chekpoint: x", env->calcPolicyLayout()),
               std::exception);
  try {
    PolicyInstance(getBuildTreeRegistry(), "torch_policy", "checkpoint: /nowhere/x.pt", env->calcPolicyLayout());
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_TRUE(contains(e.what(), "no such checkpoint '/nowhere/x.pt'")) << e.what();
  }
}

TEST_F(LearningTraining, NoisyDemonstrationsTeachThePolicysOwnActions) {
  DemoReader reader(file("reach_noisy.h5"));
  const Trajectory t = reader.read("traj_0", false);
  ASSERT_FALSE(t.policy_actions.empty());
  for (const bool executed : {false, true}) {
    DatasetOptions d;
    d.paths = {file("reach_noisy.h5")};
    d.executed_actions = executed;
    const DataChunk chunk = DemoDataset(d).load({0});
    const std::vector<double>& expected = executed ? t.actions : t.policy_actions;
    ASSERT_EQ(chunk.actions.numel(), int64_t(expected.size()));
    for (std::size_t i = 0; i < expected.size(); ++i)
      ASSERT_EQ(chunk.actions.view({-1})[int64_t(i)].item<float>(), float(std::clamp(expected[i], -1.0, 1.0)))
          << (executed ? "executed " : "policy ") << i;
  }
}

// A training that evaluates says how many episodes the kit failed and where
// their reasons are, not only a success count that counts them as 0.
TEST(EvaluationOutcome, FailedEpisodesAreNamedWithWhereTheirReasonsAre) {
  EvaluationOutcome outcome;
  outcome.episodes = 25;
  EXPECT_EQ(describeFailures(outcome, "run/eval/iter_300"), "");
  outcome.failures = 3;
  EXPECT_EQ(describeFailures(outcome, "run/eval/iter_300"), "; 3 of them failed (why: run/eval/iter_300/episodes.csv)");
}

// A block as large as a point-cloud batch's activations: glibc mmaps it
// afresh on every allocation by default (mallinfo2's hblks counts mmapped
// blocks); in a training process it comes from the heap, which keeps it
// after it is freed (arena: the heap's bytes).
TEST(LearningCompute, TrainingKeepsFreedMemoryForTheNextAllocation) {
  if (manibench::testing::kAddressSanitized) GTEST_SKIP() << "AddressSanitizer's allocator is not glibc's";
  const std::size_t bytes = std::size_t(256) << 20;
  struct Seen {
    std::size_t mapped_while_held, heap_after_free;
  };
  auto allocateAndFree = [&] {
    char* volatile block = static_cast<char*>(std::malloc(bytes));
    block[0] = 1;
    const std::size_t mapped = mallinfo2().hblks;
    std::free(block);
    return Seen{mapped, mallinfo2().arena};
  };
  // glibc's defaults, as another test in this process may have trained.
  mallopt(M_MMAP_MAX, 65536);
  mallopt(M_TRIM_THRESHOLD, 128 * 1024);
  malloc_trim(0);
  const std::size_t mapped_before = mallinfo2().hblks;
  EXPECT_EQ(allocateAndFree().mapped_while_held, mapped_before + 1);
  setKeepFreedMemory();
  const std::size_t heap_before = mallinfo2().arena;
  const Seen kept = allocateAndFree();
  EXPECT_EQ(kept.mapped_while_held, mapped_before);
  EXPECT_GE(kept.heap_after_free, heap_before + bytes);
}

TEST_F(LearningTraining, AStreamedSetVisitsEveryTransitionOncePerEpoch) {
  DatasetOptions d;
  d.paths = {file("reach.h5")};
  d.cache_bytes = 20000;  // a few trajectories per window
  const DemoDataset dataset(d);
  ASSERT_TRUE(dataset.isStreamed());
  BatchSampler a(dataset, 16, 5, true), b(dataset, 16, 5, true);
  std::set<std::vector<float>> seen;
  for (int64_t i = 0; i < a.getBatchesPerEpoch(); ++i) {
    const TransitionBatch x = a.next(), y = b.next();
    ASSERT_TRUE(torch::equal(x.obs.state, y.obs.state));
    for (int64_t r = 0; r < x.obs.size(); ++r) {
      const torch::Tensor row = torch::cat({x.obs.state[r], x.actions[r]});
      seen.insert(std::vector<float>(row.data_ptr<float>(), row.data_ptr<float>() + row.numel()));
    }
  }
  EXPECT_EQ(seen.size(), std::size_t(a.getBatchesPerEpoch() * 16));  // no transition twice
  EXPECT_GT(seen.size(), dataset.getTransitionCount() * 8 / 10);    // few dropped
}

}  // namespace
}  // namespace manibench::learning
