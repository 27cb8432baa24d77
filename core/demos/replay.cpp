// Replaying a trajectory with a check, converting its observations to
// another mode, and the configuration a demonstration file was made with.
#include <manibench/config.hpp>
#include <manibench/demos.hpp>

#include <cstring>
#include <sstream>

namespace manibench {
namespace {

std::string formatValue(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// The first index where two arrays differ bit for bit (memcmp per
// element), or -1.
template <class T>
long findDifference(const T* a, const T* b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    if (std::memcmp(a + i, b + i, sizeof(T)) != 0) return long(i);
  return -1;
}

// "observation[5] (segment 'tcp_pose' [3]): a vs b", or "".
std::string compareStates(const Eigen::VectorXd& replayed, const Eigen::VectorXd& recorded,
                          const std::vector<sdk::Segment>& segments) {
  if (replayed.size() != recorded.size())
    return "observation has " + std::to_string(replayed.size()) + " values, the recording " +
           std::to_string(recorded.size());
  const long i = findDifference(replayed.data(), recorded.data(), std::size_t(replayed.size()));
  if (i < 0) return "";
  std::string where;
  for (const sdk::Segment& s : segments)
    if (uint32_t(i) >= s.offset && uint32_t(i) < s.offset + s.size)
      where = " (segment '" + s.name + "' [" + std::to_string(uint32_t(i) - s.offset) + "])";
  return "observation[" + std::to_string(i) + "]" + where + ": replayed " +
         formatValue(replayed[i]) + " vs recorded " + formatValue(recorded[i]);
}

template <class T>
std::string compareArrays(const char* what, const std::vector<T>& replayed,
                          const std::vector<T>& recorded) {
  if (replayed.size() != recorded.size())
    return std::string(what) + " has " + std::to_string(replayed.size()) + " values, the recording " +
           std::to_string(recorded.size());
  const long i = findDifference(replayed.data(), recorded.data(), replayed.size());
  if (i < 0) return "";
  return std::string(what) + "[" + std::to_string(i) + "]: replayed " + formatValue(double(replayed[i])) +
         " vs recorded " + formatValue(double(recorded[i]));
}

std::string compareVisual(const VisualObservation& replayed, const VisualObservation& recorded) {
  for (std::string d : {compareArrays("point cloud xyz", replayed.points.xyz, recorded.points.xyz),
                        compareArrays("point cloud rgb", replayed.points.rgb, recorded.points.rgb),
                        compareArrays("point cloud masks", replayed.points.masks, recorded.points.masks),
                        compareArrays("image rgb", replayed.rgb, recorded.rgb),
                        compareArrays("image rgb bytes", replayed.rgb_bytes, recorded.rgb_bytes),
                        compareArrays("image depth", replayed.depth, recorded.depth),
                        compareArrays("image masks", replayed.masks, recorded.masks)})
    if (!d.empty()) return d;
  return "";
}

}  // namespace

// --- replay and conversion -------------------------------------------------------------

ReplayResult replayTrajectory(Environment& env, const Trajectory& t, bool check,
                              const std::function<void(uint32_t)>& on_step) {
  ReplayResult result;
  if (t.getStateCount() != t.steps + 1)
    throw DemoError("the trajectory has " + std::to_string(t.getStateCount()) + " states for " +
                    std::to_string(t.steps) + " steps");
  env.restoreState(t.getEnvState(0));
  if (on_step) on_step(0);
  const std::vector<sdk::Segment>& segments = env.calcPolicyLayout().observation_segments;
  auto differ = [&](uint32_t step, const std::string& what) {
    result.matches = false;
    result.divergence = "step " + std::to_string(step) + ": " + what;
  };
  if (check) {
    if (const std::string d = compareStates(env.getObservation(), t.getObservationState(0), segments);
        !d.empty())
      differ(0, d);
  }
  for (uint32_t k = 0; k < t.steps && result.matches; ++k) {
    const StepResult step = env.step(t.getAction(k));
    ++result.steps;
    if (on_step) on_step(k + 1);
    if (!check) continue;
    const uint32_t s = k + 1;  // the state after step k
    if (std::memcmp(&step.reward, &t.rewards[k], sizeof(double)) != 0) {
      differ(s, "reward: replayed " + formatValue(step.reward) + " vs recorded " +
                    formatValue(t.rewards[k]));
    } else if (const std::vector<uint8_t> flags(t.conditions.begin() + std::ptrdiff_t(k * t.condition_count),
                                                t.conditions.begin() + std::ptrdiff_t((k + 1) * t.condition_count));
               step.flags != flags) {
      differ(s, "success condition flags differ");
    } else if (const std::string d = env.findStateDifference(env.saveState(), t.getEnvState(s));
               !d.empty()) {
      differ(s, "state: " + d);
    } else if (const std::string d2 = compareStates(env.getObservation(), t.getObservationState(s), segments);
               !d2.empty()) {
      differ(s, d2);
    } else if (isVisualMode(t.mode)) {
      if (const std::string d3 = compareVisual(env.getVisualObservation(), t.getVisualObservation(s));
          !d3.empty())
        differ(s, d3);
    }
  }
  return result;
}

Trajectory convertTrajectory(Environment& env, const Trajectory& trajectory) {
  // Stepping the recorded actions from the first state reaches every
  // recorded state bit for bit (what replay --check verifies) at the cost
  // of a step, where restoring each state costs a reset; a state that
  // differs all the same is restored, so the observations are always those
  // of the recorded states.
  Trajectory converted = trajectory;
  converted.clearObservations();
  env.restoreState(trajectory.getEnvState(0));
  converted.addObservation(env.getObservation(), env.getVisualObservation());
  for (uint32_t k = 0; k < trajectory.steps; ++k) {
    env.step(trajectory.getAction(k));
    const std::vector<uint8_t> recorded = trajectory.getEnvState(k + 1);
    if (env.saveState() != recorded) env.restoreState(recorded);
    converted.addObservation(env.getObservation(), env.getVisualObservation());
  }
  return converted;
}

ConfigNode calcDemoConfig(const PluginRegistry& registry, const DemoFileInfo& info,
                          const std::vector<std::string>& overrides) {
  ConfigNode config = loadTaskConfig(registry, info.environment_id, {});
  try {
    mergeConfig(config, parseConfig(info.config, "the demonstration file's configuration"));
  } catch (const ConfigError& e) {
    throw DemoError(std::string("the file's configuration: ") + e.what());
  }
  for (const std::string& assignment : overrides) mergeConfig(config, parseConfigOverride(assignment));
  validateConfig(config);
  return config;
}

std::unique_ptr<Environment> makeDemoEnvironment(const PluginRegistry& registry,
                                                 const DemoFileInfo& info,
                                                 const std::vector<std::string>& overrides) {
  EnvironmentOptions options = calcEnvironmentOptions(calcDemoConfig(registry, info, overrides));
  options.stop_on_success = true;
  return std::make_unique<Environment>(registry, info.environment_id, options);
}

}  // namespace manibench
