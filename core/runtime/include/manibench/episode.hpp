// One episode of a policy in an environment: the host's only episode loop.
// `run`, `bench`, video recording and the evaluation's workers all run
// episodes through runEpisode, and observe it through hooks (timers, video
// frames, a worker's heartbeat) instead of writing the loop again.
//
// The order of calls is the per-step contract of abi.h:
//   Environment::reset (task reset, controller reset, observe), policy reset,
//   then per step: policy act, Environment::step (frame_skip x controller
//   compute and physics, compute_reward, evaluate_success once, observe),
//   until the step says done.
#pragma once

#include <manibench/environment.hpp>
#include <manibench/plugin_instances.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace manibench {

// What runEpisode is doing, in order.
enum class EpisodePhase : uint32_t { EnvReset, PolicyReset, PolicyAct, EnvStep };

// One whole episode of a policy in an environment.
struct EpisodeResult {
  std::string object_id;
  uint64_t seed = 0;
  uint32_t steps = 0;
  double total_reward = 0;
  bool success = false;  // at the last step
  // At any step: differs from `success` only in an environment that does
  // not stop on success (ManiSkill3's success_once beside success_at_end).
  bool success_once = false;
  std::vector<std::string> condition_names;
  std::vector<uint8_t> final_flags;
  std::vector<double> final_values;
};

struct EpisodeHooks {
  // On entering each phase; `step` is the env step being taken (0 during
  // the resets). May be empty.
  std::function<void(EpisodePhase phase, uint32_t step)> on_phase;
  // After the environment's reset, before the policy's (a recorder takes
  // the first observation and state here). May be empty.
  std::function<void()> on_reset;
  // Between the policy's act and the env step: may change the action that
  // is executed (exploration noise injected into a scripted expert's
  // actions while the clean ones are recorded, say). May be empty.
  std::function<void(Eigen::VectorXd& action)> perturb_action;
  // After each env step and before on_step, with the action executed (as
  // the policy gave it, or as perturb_action left it: unclipped). May be
  // empty.
  std::function<void(const Eigen::VectorXd& action, const StepResult& step)> on_transition;
  // After each env step, with that step and the episode so far; returning
  // false ends the episode after this step (a step budget). May be empty.
  std::function<bool(const StepResult& step, const EpisodeResult& so_far)> on_step;
};

// Resets `env` on (object_id, seed) and `policy` with `seed`, then steps
// until done (or until on_step says stop). Errors propagate as thrown (the
// environment's name the episode; the policy's are PluginCallErrors): a
// caller that needs to know where one happened watches on_phase.
EpisodeResult runEpisode(Environment& env, ActingPolicy& policy, const std::string& object_id,
                         uint64_t seed, const EpisodeHooks& hooks = {});

}  // namespace manibench
