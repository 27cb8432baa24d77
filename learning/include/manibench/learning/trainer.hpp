// The training loop of `manibench train`: demonstrations in, checkpoints,
// a loss log and (through a hook) success rates out, in one directory:
//
//   DIR/train.yaml            the options (what --resume DIR reads back)
//   DIR/log.csv               iteration, seconds, each loss (averaged since the previous row), it/s
//   DIR/eval.csv              iteration, split, episodes, successes, success_rate
//   DIR/checkpoints/iter_N.pt every --checkpoint-every iterations, at the end and on a stop
//   DIR/policy.yaml           `checkpoint: <the newest>`, `device: <eval_device>`: what --policy-config takes
//   DIR/environment.yaml      the demonstrations' environment configuration (--config takes it)
//   DIR/eval/iter_N/          each evaluation's results (manibench eval --out)
//
// Same seed, same data, same options, one thread: the same weights bit for
// bit; a resumed run continues as if it had never stopped.
#pragma once

#include <manibench/learning/algorithms.hpp>
#include <manibench/learning/dataset.hpp>
#include <manibench/learning/run_options.hpp>

#include <functional>
#include <string>
#include <vector>

namespace manibench {
class PluginRegistry;
}

namespace manibench::learning {

// RunOptions' fields (out_dir, algorithm, network, seed, threads, device,
// checkpoint and log cadence in iterations, eval_every, eval_episodes per
// object, eval_seed, command) and the demonstration trainer's own.
struct TrainOptions : RunOptions {
  TrainOptions() : RunOptions("bc", /*checkpoint_every=*/1000, /*log_every=*/100) {}

  // network.kind was not chosen: mlp for state demonstrations,
  // pn_transformer for point clouds.
  bool pick_network = false;
  // algorithm.lr, algorithm.weight_decay were not chosen: ManiSkill-Learn's
  // for the demonstrations' observation mode (AlgorithmOptions::makeDefaults).
  bool pick_lr = false;
  bool pick_weight_decay = false;
  DatasetOptions data;
  int64_t iterations = 10000;  // gradient steps in all
  // Gather the next batch in another thread while the current one trains:
  // always on CUDA; on the CPU off unless asked (the gather then competes
  // with the step for the cores). The weights are the same either way.
  bool prefetch = false;
  bool normalize_state = false;  // (s - mean) / std per feature, from the demonstrations
  // Append the state's world-frame segments in the robot base's frame
  // (robot_frame.hpp); resolved into network.robot_frame when training starts.
  bool robot_frame = false;
  // The evaluation's own (train.yaml's `evaluation:` beside RunOptions'):
  std::string eval_task;  // a task or fixed-object id (default: the demonstrations' environment)
  std::string eval_split = "train";
  std::vector<std::string> eval_objects;  // empty: the split's
  unsigned eval_workers = 1;
  // The device policy.yaml names for evaluating the checkpoints (the
  // torch_policy plugin runs inside the environment's process, one
  // observation at a time: the CPU unless asked, whatever trained it).
  std::string eval_device = "cpu";

  // RunOptions::checkRun and the iterations (a LearningError naming the option).
  void check() const;
  void writeYaml(YAML::Node& node) const;
  static TrainOptions readYaml(const YAML::Node& node);
};

struct TrainProgress {
  int64_t iteration = 0;  // done
  int64_t total = 0;
  std::vector<std::string> loss_names;
  std::vector<double> losses;  // the last iteration's
  double elapsed = 0;          // s, this run
  double iterations_per_second = 0;
};

struct EvaluationOutcome {
  // failures: episodes the kit failed (the policy threw, timed out or gave a
  // NaN action), counted as unsuccessful; their reasons are in the run's
  // episodes.csv.
  uint32_t episodes = 0, successes = 0, failures = 0;
  double success_rate = 0;
  // The evaluation was stopped before it finished (Ctrl-C reaches the
  // evaluating process too): the counts are not a result, the training
  // stops as interrupted, and --resume evaluates the checkpoint again.
  bool interrupted = false;
};

// "" when no episode failed, else "; N of them failed (why: OUT_DIR/episodes.csv)",
// for the line a training prints after an evaluation.
std::string describeFailures(const EvaluationOutcome& outcome, const std::string& out_dir);

// What to evaluate: the newest checkpoint's policy configuration, on the
// demonstrations' environment (their configuration file, written into the
// training's directory as environment.yaml) unless the options name another.
struct EvaluationRequest {
  const TrainOptions* options = nullptr;
  std::string environment_id;      // the demonstrations' (a task or fixed-object id)
  std::string environment_config;  // DIR/environment.yaml
  std::string policy_config;       // DIR/policy.yaml
  std::string out_dir;             // DIR/eval/iter_N
  int64_t iteration = 0;
};

struct TrainHooks {
  std::function<void(const std::string&)> on_message;       // lines for the user (may be empty)
  std::function<void(const TrainProgress&)> on_progress;    // after each iteration (may be empty)
  std::function<bool()> should_stop;                        // polled every iteration (may be empty)
  // Runs the evaluation the request describes; may be empty.
  std::function<EvaluationOutcome(const EvaluationRequest&)> evaluate;
};

struct TrainResult {
  int64_t iteration = 0;  // reached
  bool interrupted = false;
  std::string checkpoint;  // the newest
  double seconds = 0;
};

// Starts a training in options.out_dir (which must not hold one already).
TrainResult train(const PluginRegistry& registry, const TrainOptions& options, const TrainHooks& hooks);
// Continues the training in `dir` from its newest checkpoint, up to
// `iterations` (0: as train.yaml says).
TrainResult resumeTraining(const PluginRegistry& registry, const std::string& dir, int64_t iterations,
                           const TrainHooks& hooks);

// The newest checkpoint in DIR/checkpoints ("" if none).
std::string findNewestCheckpoint(const std::string& dir);

}  // namespace manibench::learning
