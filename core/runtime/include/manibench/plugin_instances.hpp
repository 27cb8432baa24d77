// Host-side owners of plugin objects. Each wraps one handle created through
// the C ABI, destroys it exactly once, and turns every failed call into a
// PluginCallError naming the plugin, the call and the plugin's message.
#pragma once

#include <manibench/abi.h>
#include <manibench/error.hpp>
#include <manibench/geometry.hpp>
#include <manibench/observation_mode.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/scene_bridge.hpp>
#include <manibench/sdk/segment.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace manibench {

class PluginCallError : public Error {
 public:
  PluginCallError(const std::string& message, mb_status status)
      : Error(message), status_(status) {}
  mb_status status() const { return status_; }

 private:
  mb_status status_;
};

struct TaskDescription {
  std::string name;
  uint32_t observation_dim = 0;
  std::vector<sdk::Segment> observation_segments;
  std::vector<std::string> success_conditions;  // "success" is last
  std::vector<std::string> masks;
  std::string robot_articulation;
  std::vector<std::string> actuated_joints;
  std::string default_controller;
  std::string controller_config;
  double control_frequency = 100;
  uint32_t frame_skip = 5;
  uint32_t max_episode_steps = 200;
  std::string default_config;  // the task's YAML configuration layer
  // Leading values of the state that are the robot's own (what the visual
  // modes keep); equals observation_dim when the task does not say.
  uint32_t agent_state_dim = 0;
  // ABI 1.6: the named values measureProgress gives (abi.h); empty for a
  // task that has none or a plugin older than 1.6.
  std::vector<std::string> progress_signals;
};

struct ControllerDescription {
  std::string name;
  uint32_t action_dim = 0;
  std::vector<sdk::Segment> action_segments;
  uint32_t flags = 0;
  // ABI 1.7: the controller this one is a layer over ("": none).
  std::string base_controller;
};

class TaskInstance {
 public:
  TaskInstance(const PluginRegistry& registry, const std::string& name,
               const std::string& config_yaml);
  ~TaskInstance();
  TaskInstance(const TaskInstance&) = delete;
  TaskInstance& operator=(const TaskInstance&) = delete;

  const TaskDescription& getDescription() const { return description_; }
  const std::string& getLibraryPath() const { return library_path_; }
  std::vector<std::string> listObjects(const std::string& split) const;
  // ABI 1.8: an object's category ("" where it has none, or the plugin
  // predates it).
  std::string getObjectCategory(const std::string& object_id) const;
  void buildScene(SceneBridge& scene, const std::string& object_id);
  void reset(SceneBridge& scene, uint64_t seed);
  void observe(SceneBridge& scene, Eigen::VectorXd& out);
  double computeReward(SceneBridge& scene, const Eigen::VectorXd& action);
  void evaluateSuccess(SceneBridge& scene, std::vector<uint8_t>& flags,
                       std::vector<double>& values);
  // ABI 1.2 (abi.h, "state"): the task's episode state as bytes, and back.
  // A plugin built against an older ABI throws a PluginCallError that says
  // so (MB_UNSUPPORTED).
  std::vector<uint8_t> saveState();
  void restoreState(const std::vector<uint8_t>& bytes);
  // ABI 1.6: one value per description's progress_signals (none when it
  // has none).
  std::vector<double> measureProgress(SceneBridge& scene);

 private:
  const mb_task_descriptor* descriptor_;
  mb_task* handle_ = nullptr;
  std::string library_path_;
  TaskDescription description_;
};

class ControllerInstance {
 public:
  ControllerInstance(const PluginRegistry& registry, const std::string& name,
                     const std::string& config_yaml,
                     const mb_controller_context& context);
  ~ControllerInstance();
  ControllerInstance(const ControllerInstance&) = delete;
  ControllerInstance& operator=(const ControllerInstance&) = delete;

  const ControllerDescription& getDescription() const { return description_; }
  void reset(SceneBridge& scene);
  void compute(SceneBridge& scene, const Eigen::VectorXd& action,
               std::vector<DriveCommand>& drives);
  // As TaskInstance's.
  std::vector<uint8_t> saveState();
  void restoreState(const std::vector<uint8_t>& bytes);
  // ABI 1.7, a layer's: the base controller's action of the last compute
  // (`dim` values). PluginCallError when the controller is no layer.
  Eigen::VectorXd getBaseAction(uint32_t dim);

 private:
  const mb_controller_descriptor* descriptor_;
  mb_controller* handle_ = nullptr;
  std::string library_path_;
  ControllerDescription description_;
};

// The C view handed to a policy's act(): pointers into `state` and
// `visual` (which must outlive it); the visual fields of visual.mode only.
mb_observation makeObservationView(const Eigen::VectorXd& state, uint32_t step,
                                   const VisualObservation& visual);
// As above, and rgb bytes (observation.rgb_dtype uint8) converted into
// `rgb_floats` (byte / 255.0f: the float32 layout's values) for
// mb_observation.image_rgb, which is float.
mb_observation makeObservationView(const Eigen::VectorXd& state, uint32_t step,
                                   const VisualObservation& visual, std::vector<float>& rgb_floats);

struct PolicyLayout {
  std::string task_name;
  ObservationMode observation_mode = ObservationMode::State;
  uint32_t observation_dim = 0;
  std::vector<sdk::Segment> observation_segments;
  uint32_t action_dim = 0;
  std::vector<sdk::Segment> action_segments;
};

// The episode a policy starts: ABI 1.5's mb_episode_info (strings empty
// where the caller does not know them).
struct PolicyEpisode {
  std::string task_name;  // the registered task's, also for a fixed-object id
  std::string object_id;
  uint64_t seed = 0;
};

// What runEpisode asks of a policy: a plugin's policy in this process
// (PolicyInstance), or one run in a sandboxed process of its own (the
// evaluation kit's, evaluation/policy_process.hpp).
class ActingPolicy {
 public:
  virtual ~ActingPolicy() = default;
  // The policy's reset_episode where it has one (ABI 1.5), else its reset.
  virtual void reset(const PolicyEpisode& episode) = 0;
  // Writes the raw action; validation is the environment's job.
  virtual void act(const Eigen::VectorXd& observation, uint32_t step, Eigen::VectorXd& action,
                   const VisualObservation& visual) = 0;
};

class PolicyInstance : public ActingPolicy {
 public:
  PolicyInstance(const PluginRegistry& registry, const std::string& name,
                 const std::string& config_yaml, const PolicyLayout& layout);
  ~PolicyInstance() override;
  PolicyInstance(const PolicyInstance&) = delete;
  PolicyInstance& operator=(const PolicyInstance&) = delete;

  const std::string& getName() const { return name_; }
  const std::string& getLibraryPath() const { return library_path_; }
  void reset(const PolicyEpisode& episode) override;
  // An episode of which only the seed is known.
  void reset(uint64_t seed) { reset(PolicyEpisode{"", "", seed}); }
  // Writes the raw action; validation is the environment's job. `visual`
  // fills the ABI 1.1 fields of its mode (none in State); rgb as bytes
  // reaches the policy as the float32 layout's floats (makeObservationView).
  void act(const Eigen::VectorXd& observation, uint32_t step, Eigen::VectorXd& action,
           const VisualObservation& visual) override;
  void act(const Eigen::VectorXd& observation, uint32_t step, Eigen::VectorXd& action) {
    act(observation, step, action, VisualObservation());
  }

 private:
  const mb_policy_descriptor* descriptor_;
  mb_policy* handle_ = nullptr;
  std::string name_;
  std::string library_path_;
  uint32_t action_dim_ = 0;
  std::vector<float> rgb_floats_;  // act(): rgb bytes as floats for the ABI
};

}  // namespace manibench
