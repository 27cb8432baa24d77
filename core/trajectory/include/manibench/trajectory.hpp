// One recorded episode in memory (supplement C.2's trajectories) and its
// recorder over the episode hooks. Below both the evaluation kit (whose
// workers record successful episodes and send them back) and the
// demonstration files (manibench/demos.hpp), which store them.
#pragma once

#include <manibench/environment.hpp>
#include <manibench/error.hpp>
#include <manibench/observation_mode.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench {

// A demonstration file or trajectory that cannot be used: not HDF5, not a
// demonstration file, another format version, cut short, a missing or
// malformed dataset. The message names the file and, where it is one
// trajectory's, the trajectory.
class DemoError : public Error {
 public:
  using Error::Error;
};

// One recorded episode: T steps, T + 1 observations and states (the reset's
// and each step's).
struct Trajectory {
  std::string object_id;
  uint64_t level = 0;  // the episode's index within its object (evaluation's level)
  uint64_t seed = 0;
  uint32_t steps = 0;  // T
  bool success = false;  // at the last step
  double total_reward = 0;
  // demos convert's tracked conversion: the largest distance (m) between
  // the target's TCP and the recording's; negative for any other.
  double tracking_error = -1;

  uint32_t action_dim = 0, condition_count = 0;
  std::vector<double> actions;  // T x action_dim, as the policy gave them (unclipped)
  // T x action_dim: the policy's own actions where noise was added to the
  // executed ones (demos generate --action-noise); empty otherwise.
  std::vector<double> policy_actions;
  std::vector<double> rewards;  // T
  std::vector<uint8_t> terminated, truncated, success_flags;  // T: success, time limit, `success`
  std::vector<uint8_t> conditions;  // T x condition_count: each success condition's flag

  // Observations, T + 1 of them. `state` is the task's vector (the visual
  // modes: the agent's part). Point clouds: point_counts[t] points each (the
  // same for every t unless the sampling does not pad), concatenated, rgb
  // in [0, 1]. Images: cameras stacked along the channels as
  // VisualObservation, rgb as floats (image_rgb) or bytes (image_rgb_bytes,
  // observation.rgb_dtype uint8).
  ObservationMode mode = ObservationMode::State;
  uint32_t state_dim = 0;
  std::vector<double> state;
  uint32_t mask_count = 0;
  std::vector<uint32_t> point_counts;
  std::vector<float> xyz, point_rgb;
  std::vector<uint8_t> point_masks;
  uint32_t camera_count = 0, height = 0, width = 0;
  std::vector<float> image_rgb, depth;
  std::vector<uint8_t> image_rgb_bytes, image_masks;

  // Environment::saveState() of the reset and of every step: T + 1 blobs,
  // blob t is env_states[env_state_offsets[t], env_state_offsets[t + 1]).
  std::vector<uint8_t> env_states;
  std::vector<uint64_t> env_state_offsets{0};

  uint32_t getObservationCount() const { return uint32_t(state_dim ? state.size() / state_dim : 0); }
  uint32_t getStateCount() const { return uint32_t(env_state_offsets.size() - 1); }
  std::vector<uint8_t> getEnvState(uint32_t t) const;
  Eigen::VectorXd getAction(uint32_t t) const;
  Eigen::VectorXd getObservationState(uint32_t t) const;
  // Observation t as the environment gave it (state vector and visual part).
  VisualObservation getVisualObservation(uint32_t t) const;

  // Recording (what TrajectoryRecorder does).
  void addObservation(const Eigen::VectorXd& state, const VisualObservation& visual);
  void addEnvState(const std::vector<uint8_t>& blob);
  // `policy_action`: what the policy gave when noise changed the executed
  // `action` (nullptr: the same).
  void addStep(const Eigen::VectorXd& action, const StepResult& result,
               const Eigen::VectorXd* policy_action = nullptr);
  // Drops every observation (before convertTrajectory records others).
  void clearObservations();
};

// Records an episode of `env` while it runs (wire it into runEpisode's
// hooks: onReset after the resets, onStep after each step).
class TrajectoryRecorder {
 public:
  explicit TrajectoryRecorder(Environment& env) : env_(env) {}
  void onReset(const std::string& object_id, uint64_t level, uint64_t seed);
  void onStep(const Eigen::VectorXd& action, const StepResult& result,
              const Eigen::VectorXd* policy_action = nullptr);
  Trajectory& get() { return trajectory_; }
  Trajectory take() { return std::move(trajectory_); }

 private:
  Environment& env_;
  Trajectory trajectory_;
};

}  // namespace manibench
