// An environment: one task plugin, its scene, and the controller that turns
// normalized actions into joint drives. One env step = frame_skip control
// steps of 1/control_frequency seconds each.
#pragma once

#include <manibench/plugin_instances.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/pointcloud.hpp>
#include <manibench/renderer.hpp>
#include <manibench/scene.hpp>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace manibench {

// The action broke the contract (wrong size, NaN, infinity). The message
// names the episode's object and seed, the step and the index.
class InvalidAction : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Physics diverged or rendering failed during a reset or step; the message
// names the task, object, seed and step.
class EpisodeFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A contact material for one link (or every link) of an articulation,
// set after the task has built its scene and before it is finalized.
struct BodyContactMaterial {
  std::string articulation;
  std::string link;  // empty: every link of the articulation
  ContactMaterial material;
  std::string source;  // where it was configured ("my.yaml:7: ..."), for errors
};

// Self-collision of one articulation, set like BodyContactMaterial.
struct SelfCollisionSetting {
  std::string articulation;
  bool enabled = false;
  std::string source;
};

// A camera of the visual observation modes: mounted on a link (it moves
// with it) or fixed in the world.
struct CameraMount {
  CameraSpec spec;           // name, image size, fovy, near and far
  std::string articulation;  // empty: fixed in the world
  std::string link;          // empty: the articulation's root
  Pose pose;                 // in the mount frame (SAPIEN: +x optical axis, +z up)
  std::string source;        // where it was configured, for errors
};

// The observation modes (ManiSkill's obs_mode).
inline const std::vector<std::string>& getObservationModes() {
  static const std::vector<std::string> modes{"state", "pointcloud", "rgbd"};
  return modes;
}

// What an environment is built with; manibench/config.hpp derives these
// from the layered YAML configuration.
struct EnvironmentOptions {
  std::string task_config;        // YAML for the task plugin
  std::string controller;         // empty: the task's default controller
  std::string controller_config;  // empty: the task's controller config
  PhysicsSettings physics;
  // Applied in order, so a later entry for the same link wins.
  std::vector<BodyContactMaterial> contact_materials;
  std::optional<ContactMaterial> ground_material;  // unset: physics.default_material
  std::vector<SelfCollisionSetting> self_collision;
  // End the episode as soon as `success` holds (as ManiSkill's done flag).
  bool stop_on_success = true;
  // Overrides of the task's timing; unset: the task's own values. They
  // change getTaskDescription() too, so that everything downstream (the
  // controller's filter, policies, printing) sees the values in force.
  std::optional<double> control_frequency;    // Hz, > 0
  std::optional<uint32_t> frame_skip;         // >= 1
  std::optional<uint32_t> max_episode_steps;  // >= 1

  // "state": the task's vector only. "pointcloud" and "rgbd" add, from
  // every camera, a fused world-frame point cloud subsampled as supplement
  // D.1 (`pointcloud`) or the stacked images (see VisualObservation). Only
  // these two modes create a renderer (and so touch EGL), lazily.
  std::string observation_mode = "state";
  std::vector<CameraMount> cameras;  // names unique; rgbd: all of one size
  LightingSpec lighting;
  PointCloudSampling pointcloud;
  RenderOptions render;
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
  // `environment_id` is a task name or a fixed-object id such as
  // "OpenCabinetDrawer_1000-v0" (manibench/task_name.hpp): then the
  // environment has only the objects of that id (searched in both splits),
  // listObjects returns them whatever the split (as ManiSkill's fixed
  // environments: the object is the choice), the first scene is the first
  // of them, and a reset on any other object throws std::invalid_argument.
  Environment(const PluginRegistry& registry, const std::string& environment_id,
              EnvironmentOptions options = {});
  ~Environment();

  // The task's description with the options' timing overrides applied; its
  // name is the registered task's, even for a fixed-object id.
  const TaskDescription& getTaskDescription() const;
  // The id the environment was made with ("Reach_3-v0", or the task name).
  const std::string& getEnvironmentId() const { return environment_id_; }
  // A fixed-object environment's objects; empty for a plain task.
  const std::vector<std::string>& getFixedObjects() const { return fixed_objects_; }
  const ControllerDescription& getControllerDescription() const;
  // The layout policies see; an empty mode means the environment's own.
  PolicyLayout calcPolicyLayout(const std::string& observation_mode = "") const;
  std::vector<std::string> listObjects(const std::string& split) const;

  // Starts an episode on `object_id` (rebuilding the scene only when the
  // object changes) with randomization from `seed`. Identical arguments give
  // identical episodes, whatever ran before.
  void reset(const std::string& object_id, uint64_t seed);
  // Validates (size, finite), clips to [-1, 1], runs frame_skip control
  // steps, then computes reward, success and the next observation.
  StepResult step(const Eigen::VectorXd& action);

  const Eigen::VectorXd& getObservation() const { return observation_; }
  // The visual part of the observation (empty in state mode), computed
  // with the state vector at every reset and step.
  const VisualObservation& getVisualObservation() const { return visual_; }
  const std::string& getObservationMode() const { return options_.observation_mode; }
  // Renders every camera at the current state (the visual modes do this at
  // each step; `render` and third-person videos call it in any mode, and
  // only then create the renderer). One entry per options.cameras, plus
  // `extra` cameras fixed in the world, in that order.
  const std::vector<CameraImages>& renderCameras(
      const std::vector<std::pair<CameraSpec, Pose>>& extra = {});
  // Per visual of the scene: bit m set when it belongs to mask m.
  const std::vector<std::uint64_t>& getVisualMasks() const { return visual_masks_; }
  // The renderer of the current scene, created on first use.
  SceneRenderer& updRenderer();
  // World pose of camera `index` of options.cameras at the current state.
  Pose calcCameraPose(std::size_t index) const;
  const std::vector<CameraMount>& getCameras() const { return options_.cameras; }
  const EnvironmentOptions& getOptions() const { return options_; }
  // The world-frame points of the first `count` of `images` (pixels that
  // hit something), with color and the task's masks: the cloud that the
  // pointcloud mode subsamples.
  void fusePointCloud(const std::vector<CameraImages>& images, std::size_t count,
                      PointCloud& out) const;
  // Bit m set when `pixel` of `image` shows a visual of mask m.
  std::uint64_t calcPixelMasks(const CameraImages& image, std::size_t pixel) const;
  uint32_t getElapsedSteps() const { return elapsed_steps_; }
  const std::string& getObjectId() const { return object_id_; }
  uint64_t getSeed() const { return seed_; }
  const Scene& getScene() const;
  Scene& updScene();

 private:
  void buildScene(const std::string& object_id);
  // The options' per-body settings, on a scene the task has just built.
  void applySceneOptions(const std::string& object_id);
  std::string describeEpisode() const;
  // Resolves options_.cameras on a freshly built scene.
  void resolveCameras();
  // The visual observation of the current state (visual modes only).
  void observeVisual();

  const PluginRegistry& registry_;
  EnvironmentOptions options_;
  std::string environment_id_;
  std::vector<std::string> fixed_objects_;  // empty: every object of the task
  std::unique_ptr<TaskInstance> task_;
  TaskDescription description_;  // task_'s, with the timing overrides
  std::unique_ptr<Scene> scene_;
  std::unique_ptr<SceneBridge> bridge_;
  std::unique_ptr<ControllerInstance> controller_;
  std::optional<SceneState> initial_state_;
  int robot_ = -1;
  std::vector<int> actuated_joints_;
  std::vector<DriveCommand> drives_;  // the controller writes, the scene reads
  std::string object_id_;
  bool scene_built_ = false;
  uint64_t seed_ = 0;
  uint32_t elapsed_steps_ = 0;
  Eigen::VectorXd observation_;
  Eigen::VectorXd clipped_action_;
  // Visual modes. The renderer reads scene_, so it goes first.
  std::vector<std::uint64_t> visual_masks_;
  std::vector<int> camera_links_;  // per camera: link id, -1 root, -2 world
  std::vector<int> camera_articulations_;
  std::unique_ptr<SceneRenderer> renderer_;
  std::vector<CameraImages> images_;
  PointCloud raw_points_;
  VisualObservation visual_;
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
