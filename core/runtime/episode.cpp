#include <manibench/episode.hpp>

namespace manibench {

EpisodeResult runEpisode(Environment& env, ActingPolicy& policy, const std::string& object_id,
                         uint64_t seed, const EpisodeHooks& hooks) {
  auto enter = [&](EpisodePhase phase, uint32_t step) {
    if (hooks.on_phase) hooks.on_phase(phase, step);
  };
  enter(EpisodePhase::EnvReset, 0);
  env.reset(object_id, seed);
  if (hooks.on_reset) hooks.on_reset();
  enter(EpisodePhase::PolicyReset, 0);
  policy.reset(PolicyEpisode{env.getTaskDescription().name, object_id, seed});
  EpisodeResult result;
  result.object_id = object_id;
  result.seed = seed;
  result.condition_names = env.getTaskDescription().success_conditions;
  Eigen::VectorXd action;
  for (;;) {
    enter(EpisodePhase::PolicyAct, env.getElapsedSteps());
    policy.act(env.getObservation(), env.getElapsedSteps(), action, env.getVisualObservation());
    if (hooks.perturb_action) hooks.perturb_action(action);
    enter(EpisodePhase::EnvStep, env.getElapsedSteps());
    const StepResult step = env.step(action);
    if (hooks.on_transition) hooks.on_transition(action, step);
    result.total_reward += step.reward;
    result.final_flags = step.flags;
    result.final_values = step.values;
    result.success = step.success;
    result.success_once = result.success_once || step.success;
    result.steps = env.getElapsedSteps();
    const bool go_on = !hooks.on_step || hooks.on_step(step, result);
    if (step.isDone() || !go_on) break;
  }
  return result;
}

}  // namespace manibench
