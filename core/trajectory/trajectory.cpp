// Trajectories in memory: what an episode was (actions, rewards, flags,
// observations, a state blob per step) and recording one from a live
// environment.
#include <manibench/trajectory.hpp>

#include <cstring>

namespace manibench {
namespace {

template <class T>
void append(std::vector<T>& to, const std::vector<T>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

}  // namespace

// --- Trajectory -----------------------------------------------------------------

std::vector<uint8_t> Trajectory::getEnvState(uint32_t t) const {
  if (t + 1 >= env_state_offsets.size())
    throw DemoError("trajectory has " + std::to_string(getStateCount()) + " states, no state " +
                    std::to_string(t));
  return std::vector<uint8_t>(env_states.begin() + std::ptrdiff_t(env_state_offsets[t]),
                              env_states.begin() + std::ptrdiff_t(env_state_offsets[t + 1]));
}

Eigen::VectorXd Trajectory::getAction(uint32_t t) const {
  return Eigen::Map<const Eigen::VectorXd>(actions.data() + std::size_t(t) * action_dim, action_dim);
}

Eigen::VectorXd Trajectory::getObservationState(uint32_t t) const {
  return Eigen::Map<const Eigen::VectorXd>(state.data() + std::size_t(t) * state_dim, state_dim);
}

VisualObservation Trajectory::getVisualObservation(uint32_t t) const {
  VisualObservation v;
  v.mode = mode;
  v.mask_count = mask_count;
  if (mode == ObservationMode::PointCloud) {
    std::size_t first = 0;
    for (uint32_t k = 0; k < t; ++k) first += point_counts[k];
    const std::size_t n = point_counts[t];
    v.points.mask_count = mask_count;
    v.points.xyz.assign(xyz.begin() + std::ptrdiff_t(3 * first), xyz.begin() + std::ptrdiff_t(3 * (first + n)));
    v.points.rgb.assign(point_rgb.begin() + std::ptrdiff_t(3 * first),
                        point_rgb.begin() + std::ptrdiff_t(3 * (first + n)));
    v.points.masks.assign(point_masks.begin() + std::ptrdiff_t(mask_count * first),
                          point_masks.begin() + std::ptrdiff_t(mask_count * (first + n)));
  } else if (mode == ObservationMode::Rgbd) {
    v.camera_count = camera_count;
    v.height = height;
    v.width = width;
    const std::size_t pixels = std::size_t(height) * width;
    auto slice = [&](const auto& all, std::size_t channels, auto& out) {
      const std::size_t size = pixels * channels;
      out.assign(all.begin() + std::ptrdiff_t(t * size), all.begin() + std::ptrdiff_t((t + 1) * size));
    };
    if (!image_rgb.empty()) slice(image_rgb, 3 * std::size_t(camera_count), v.rgb);
    if (!image_rgb_bytes.empty()) slice(image_rgb_bytes, 3 * std::size_t(camera_count), v.rgb_bytes);
    slice(depth, std::size_t(camera_count), v.depth);
    slice(image_masks, std::size_t(mask_count) * camera_count, v.masks);
  }
  return v;
}

void Trajectory::addObservation(const Eigen::VectorXd& observation, const VisualObservation& visual) {
  if (state.empty()) {
    state_dim = uint32_t(observation.size());
    mode = visual.mode;
    mask_count = visual.mask_count;
    camera_count = visual.camera_count;
    height = visual.height;
    width = visual.width;
  }
  if (uint32_t(observation.size()) != state_dim)
    throw DemoError("observations of " + std::to_string(observation.size()) + " and " +
                    std::to_string(state_dim) + " values in one trajectory");
  state.insert(state.end(), observation.data(), observation.data() + observation.size());
  if (mode == ObservationMode::PointCloud) {
    point_counts.push_back(uint32_t(visual.points.size()));
    append(xyz, visual.points.xyz);
    append(point_rgb, visual.points.rgb);
    append(point_masks, visual.points.masks);
  } else if (mode == ObservationMode::Rgbd) {
    append(image_rgb, visual.rgb);
    append(image_rgb_bytes, visual.rgb_bytes);
    append(depth, visual.depth);
    append(image_masks, visual.masks);
  }
}

void Trajectory::addEnvState(const std::vector<uint8_t>& blob) {
  append(env_states, blob);
  env_state_offsets.push_back(env_states.size());
}

void Trajectory::addStep(const Eigen::VectorXd& action, const StepResult& result,
                         const Eigen::VectorXd* policy_action) {
  if (steps == 0) {
    action_dim = uint32_t(action.size());
    condition_count = uint32_t(result.flags.size());
  }
  actions.insert(actions.end(), action.data(), action.data() + action.size());
  if (policy_action) policy_actions.insert(policy_actions.end(), policy_action->data(),
                                           policy_action->data() + policy_action->size());
  rewards.push_back(result.reward);
  // Gymnasium's split: ended by the task (success, when episodes stop
  // there) or by the time limit.
  // The file's convention (docs/demonstrations.md): terminated marks a
  // last step with success, truncated one without.
  const bool terminated_here = result.isDone() && result.success;
  terminated.push_back(terminated_here ? 1 : 0);
  truncated.push_back(result.isDone() && !terminated_here ? 1 : 0);
  success_flags.push_back(result.success ? 1 : 0);
  append(conditions, result.flags);
  success = result.success;
  total_reward += result.reward;
  ++steps;
}

void Trajectory::clearObservations() {
  state.clear();
  state_dim = 0;
  point_counts.clear();
  xyz.clear();
  point_rgb.clear();
  point_masks.clear();
  image_rgb.clear();
  image_rgb_bytes.clear();
  depth.clear();
  image_masks.clear();
}

// --- recording ---------------------------------------------------------------------

void TrajectoryRecorder::onReset(const std::string& object_id, uint64_t level, uint64_t seed) {
  trajectory_ = Trajectory();
  trajectory_.object_id = object_id;
  trajectory_.level = level;
  trajectory_.seed = seed;
  trajectory_.addObservation(env_.getObservation(), env_.getVisualObservation());
  trajectory_.addEnvState(env_.saveState());
}

void TrajectoryRecorder::onStep(const Eigen::VectorXd& action, const StepResult& result,
                                const Eigen::VectorXd* policy_action) {
  trajectory_.addStep(action, result, policy_action);
  trajectory_.addObservation(env_.getObservation(), env_.getVisualObservation());
  trajectory_.addEnvState(env_.saveState());
}

}  // namespace manibench
