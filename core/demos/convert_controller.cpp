// Demonstrations in another controller (`demos convert --controller`):
// the plan, and the exact conversion where the file's controller is a
// layer over the target (ABI 1.7), by stepping the layer at control rate
// and taking, at every control step, the base controller's action it
// reports; the tracked one is convert_tracked.cpp. docs/demonstrations.md.
#include <manibench/config.hpp>
#include <manibench/demos.hpp>

namespace manibench {

std::optional<ControllerConversion> planControllerConversion(const PluginRegistry& registry,
                                                             const DemoFileInfo& info,
                                                             const std::vector<std::string>& overrides) {
  const EnvironmentOptions wanted = calcEnvironmentOptions(calcDemoConfig(registry, info, overrides));
  if (wanted.controller.empty() || wanted.controller == info.controller) return std::nullopt;
  ControllerConversion plan;
  plan.source = info.controller;
  plan.target = wanted.controller;
  // The layer's environment: the file's configuration (with the user's
  // other overrides), observations of the state alone (the target's are
  // the ones recorded).
  std::vector<std::string> source_overrides;
  for (const std::string& assignment : overrides)
    if (assignment.rfind("control.controller=", 0) != 0 && assignment.rfind("observation.mode=", 0) != 0)
      source_overrides.push_back(assignment);
  {
    const Environment probe(registry, info.environment_id,
                            calcEnvironmentOptions(calcDemoConfig(registry, info, source_overrides)));
    if (probe.getControllerDescription().base_controller != plan.target) {
      // No layer over the target: the target tracks the recording at the
      // file's rate.
      plan.method = "tracked";
      plan.source_overrides = source_overrides;
      plan.source_overrides.push_back("observation.mode=state");
      plan.target_overrides = overrides;
      return plan;
    }
    plan.frame_skip = probe.getTaskDescription().frame_skip;
    // Control rate: each recorded step is frame_skip control steps of one
    // layer action, each of which the base needs an action of its own for.
    const std::string control_rate[] = {
        "control.frame_skip=1",
        "episode.max_steps=" + std::to_string(uint64_t(probe.getTaskDescription().max_episode_steps) * plan.frame_skip)};
    for (const std::string& assignment : control_rate) source_overrides.push_back(assignment);
  }
  plan.method = "exact";
  plan.source_overrides = source_overrides;
  plan.source_overrides.push_back("observation.mode=state");
  // The target: the layer's settings, the user's observation mode and the
  // target controller.
  plan.target_overrides = source_overrides;
  for (const std::string& assignment : overrides)
    if (assignment.rfind("observation.mode=", 0) == 0) plan.target_overrides.push_back(assignment);
  plan.target_overrides.push_back("control.controller=" + plan.target);
  return plan;
}

void startControllerConversion(Environment& source, Environment& target, const Trajectory& trajectory) {
  if (trajectory.getStateCount() != trajectory.steps + 1)
    throw DemoError("the trajectory has " + std::to_string(trajectory.getStateCount()) + " states for " +
                    std::to_string(trajectory.steps) + " steps");
  const std::vector<uint8_t> first = trajectory.getEnvState(0);
  const Environment::StateHeader header = Environment::readStateHeader(first);
  if (header.step != 0)
    throw DemoError("it starts at step " + std::to_string(header.step) +
                    " of its episode; only whole episodes (from their reset) convert to another controller");
  source.restoreState(first);
  // The target's episode starts from the same reset; its controller's
  // state is its own reset's.
  target.reset(header.object_id, header.seed);
  if (const std::string d = target.findSceneDifference(target.saveState(), first); !d.empty())
    throw DemoError("step 0: the target's reset differs from the recording's: " + d);
}

Trajectory convertTrajectoryController(Environment& source, Environment& target, const Trajectory& trajectory,
                                       uint32_t frame_skip) {
  startControllerConversion(source, target, trajectory);
  TrajectoryRecorder recorder(target);
  recorder.onReset(trajectory.object_id, trajectory.level, trajectory.seed);
  const uint32_t dim = target.getControllerDescription().action_dim;
  for (uint32_t k = 0; k < trajectory.steps; ++k) {
    const Eigen::VectorXd action = trajectory.getAction(k);
    for (uint32_t s = 0; s < frame_skip; ++s) {
      source.step(action);
      const Eigen::VectorXd base_action = source.getBaseAction(dim);
      const StepResult result = target.step(base_action);
      recorder.onStep(base_action, result);
      const Trajectory& converted = recorder.get();
      if (const std::string d =
              target.findSceneDifference(converted.getEnvState(converted.steps), source.saveState());
          !d.empty())
        throw DemoError("step " + std::to_string(k) + ", control step " + std::to_string(s) + ": the '" +
                        target.getControllerDescription().name + "' state differs from the '" +
                        source.getControllerDescription().name + "' one it should equal: " + d);
      if (result.isDone()) return recorder.take();
    }
    if (const std::string d = target.findSceneDifference(source.saveState(), trajectory.getEnvState(k + 1));
        !d.empty())
      throw DemoError("step " + std::to_string(k + 1) + ": the layer at control rate left the recording: " + d);
  }
  return recorder.take();
}

}  // namespace manibench
