// Online SAC training (`manibench train sac`): W environment workers
// (env_workers.hpp) step in parallel in the state mode while the learner
// takes its gradient steps; transitions go to a replay buffer; the agent
// is Algorithm "sac" (algorithms.hpp) and its checkpoints are the
// demonstration trainer's, so the torch_policy plugin runs them (the tanh
// of the Gaussian's mean). One directory per training:
//
//   DIR/train.yaml                 the options (what --resume DIR reads back)
//   DIR/log.csv                    one row per --log-every env steps: episodes,
//                                  return, success rate, losses, speeds, time shares
//   DIR/checkpoints/iter_N.pt      N env steps: agent, optimizers, generator,
//                                  counters and each worker's environment state
//   DIR/checkpoints/replay_N.pt    the replay buffer of the newest checkpoint only
//   DIR/policy.yaml                `checkpoint: <the newest>` (--policy-config takes it)
//   DIR/eval.csv, DIR/eval/iter_N/ with eval_every: env_steps, episodes,
//                                  successes, success_rate; each evaluation's results
//
// The learner acts for all workers at once, sends the actions, takes its
// gradient steps while they step (from the buffer as it was before their
// transitions: one round of lag), then stores their transitions. So one
// seed gives one learning curve for a given number of workers and threads,
// and a resumed run (the workers' environments restored from their saved
// states, the buffer and the generator from the files) continues as if it
// had never stopped (tested with one worker and one thread).
#pragma once

#include <manibench/learning/algorithms.hpp>
#include <manibench/learning/networks.hpp>
#include <manibench/learning/run_options.hpp>
#include <manibench/learning/trainer.hpp>

#include <functional>
#include <string>
#include <sys/types.h>
#include <vector>

namespace manibench {
class PluginRegistry;
}

namespace manibench::learning {

// RunOptions' fields (out_dir, algorithm, network: an MLP of Table 6's 3 x
// 256, seed, threads, device, checkpoint and log cadence in env steps,
// eval_every, eval_episodes per object of the training, eval_seed,
// command) and SAC's own.
struct SacOptions : RunOptions {
  SacOptions() : RunOptions("sac", /*checkpoint_every=*/50000, /*log_every=*/2000) {}

  std::string environment_id;        // a task or fixed-object id
  std::string split = "train";       // a task's objects (a fixed-object id has its own)
  std::vector<std::string> objects;  // empty: all of them; episodes go round them in order
  std::vector<std::string> config_files;  // --config layers (absolute paths)
  std::vector<std::string> config_sets;   // --set KEY=VALUE layers
  int64_t steps = 2000000;          // env steps in all (C.2: 2 x 10^6)
  unsigned workers = 4;             // C.2's sample-collecting processes
  int64_t replay_size = 1000000;    // Table 6
  double updates_per_step = 1;      // gradient steps per env step (Table 6: 1)
  // Uniform random actions for the first env steps (exploration before the
  // actor has learned anything; SAC's usual warm-up), and no gradient step
  // before the buffer holds this many transitions (at least a batch).
  int64_t random_steps = 4000;
  int64_t learning_starts = 1024;
  // C.2: the episode does not end at success while training (the agent
  // learns to stay successful); --early-done ends it there.
  bool early_done = false;
  // A worker silent this long on one request (a task stuck in a loop or a
  // system call) is killed and replaced, its episode dropped; 0: wait for
  // ever. A drawer's reset or step takes milliseconds even on the loaded
  // 2-core machine; the margin is for a machine swapping.
  double worker_timeout = 120;

  // RunOptions::checkRun and SAC's own (a LearningError naming the option).
  void check() const;
  void writeYaml(YAML::Node& node) const;
  static SacOptions readYaml(const YAML::Node& node);
};

struct SacProgress {
  int64_t env_steps = 0, total = 0, updates = 0, episodes = 0;
  double env_steps_per_second = 0, updates_per_second = 0;  // this run
  double mean_return = 0, success_rate = 0;                 // the last 20 episodes
  std::vector<pid_t> worker_pids;
};

struct SacHooks {
  std::function<void(const std::string&)> on_message;     // lines for the user (may be empty)
  std::function<void(const SacProgress&)> on_progress;    // after each round of steps (may be empty)
  std::function<bool()> should_stop;                      // polled every round (may be empty)
  // Evaluates the policy configuration (DIR/policy.yaml, the newest
  // checkpoint) into the folder; needed for eval_every (may be empty).
  std::function<EvaluationOutcome(const SacOptions&, const std::string& policy_config, const std::string& out_dir)>
      evaluate;
};

struct SacResult {
  int64_t env_steps = 0, updates = 0, episodes = 0;
  bool interrupted = false;
  std::string checkpoint;  // the newest
  double seconds = 0;
};

// Starts a training in options.out_dir (which must not hold one already).
// Forks the environment workers first: call it before this process starts
// libtorch's thread pools.
SacResult trainSac(const PluginRegistry& registry, const SacOptions& options, const SacHooks& hooks);
// Continues the training in `dir` from its newest checkpoint, up to `steps`
// env steps (0: as train.yaml says).
SacResult resumeSac(const PluginRegistry& registry, const std::string& dir, int64_t steps, const SacHooks& hooks);

}  // namespace manibench::learning
