// An environment: one task plugin, its scene, and the controller that turns
// normalized actions into joint drives. One env step = frame_skip control
// steps of 1/control_frequency seconds each.
#pragma once

#include <manibench/plugin_instances.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/scene.hpp>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace manibench {

// The action broke the contract (wrong size, NaN, infinity). The message
// names the episode's object and seed, the step and the index.
class InvalidAction : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Physics failed during a step (divergence); names object, seed and step.
class EpisodeFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct EnvironmentOptions {
  std::string task_config;        // YAML for the task plugin
  std::string controller;         // empty: the task's default controller
  std::string controller_config;  // empty: the task's controller config
  PhysicsSettings physics;
  // End the episode as soon as `success` holds (as ManiSkill's done flag).
  bool stop_on_success = true;
};

struct StepResult {
  double reward = 0;
  bool done = false;      // success (when stop_on_success) or time limit
  bool success = false;   // the last condition
  std::vector<uint8_t> flags;   // one per success condition
  std::vector<double> values;   // one per success condition
};

class Environment {
 public:
  // Loads the task and builds the scene of its first train object (so the
  // controller, and with it the action layout, exists from the start).
  Environment(const PluginRegistry& registry, const std::string& task_name,
              EnvironmentOptions options = {});
  ~Environment();

  const TaskDescription& getTaskDescription() const;
  const ControllerDescription& getControllerDescription() const;
  PolicyLayout calcPolicyLayout(const std::string& observation_mode = "state") const;
  std::vector<std::string> listObjects(const std::string& split) const;

  // Starts an episode on `object_id` (rebuilding the scene only when the
  // object changes) with randomization from `seed`. Identical arguments give
  // identical episodes, whatever ran before.
  void reset(const std::string& object_id, uint64_t seed);
  // Validates (size, finite), clips to [-1, 1], runs frame_skip control
  // steps, then computes reward, success and the next observation.
  StepResult step(const Eigen::VectorXd& action);

  const Eigen::VectorXd& getObservation() const { return observation_; }
  uint32_t getElapsedSteps() const { return elapsed_steps_; }
  const std::string& getObjectId() const { return object_id_; }
  uint64_t getSeed() const { return seed_; }
  const Scene& getScene() const;
  Scene& updScene();

 private:
  void buildScene(const std::string& object_id);
  std::string describeEpisode() const;

  const PluginRegistry& registry_;
  EnvironmentOptions options_;
  std::unique_ptr<TaskInstance> task_;
  std::unique_ptr<Scene> scene_;
  std::unique_ptr<SceneBridge> bridge_;
  std::unique_ptr<ControllerInstance> controller_;
  std::optional<SceneState> initial_state_;
  int robot_ = -1;
  std::vector<int> actuated_joints_;
  std::vector<mb_drive_command> drives_;
  std::string object_id_;
  bool scene_built_ = false;
  uint64_t seed_ = 0;
  uint32_t elapsed_steps_ = 0;
  Eigen::VectorXd observation_;
  Eigen::VectorXd clipped_action_;
};

// One whole episode of a policy in an environment.
struct EpisodeResult {
  std::string object_id;
  uint64_t seed = 0;
  uint32_t steps = 0;
  double total_reward = 0;
  bool success = false;
  std::vector<std::string> condition_names;
  std::vector<uint8_t> final_flags;
  std::vector<double> final_values;
};

EpisodeResult runEpisode(Environment& env, PolicyInstance& policy,
                         const std::string& object_id, uint64_t seed);

}  // namespace manibench
