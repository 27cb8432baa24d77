// An environment: one task plugin, its scene, and the controller that turns
// normalized actions into joint drives. One env step = frame_skip control
// steps of 1/control_frequency seconds each.
#pragma once

#include <manibench/environment_options.hpp>
#include <manibench/error.hpp>
#include <manibench/observation.hpp>
#include <manibench/plugin_instances.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/scene.hpp>
#include <manibench/scene_bridge.hpp>
#include <manibench/visual_observer.hpp>

#include <Eigen/Core>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace manibench {

// The action broke the contract (wrong size, NaN, infinity). The message
// names the episode's object and seed, the step and the index.
class InvalidAction : public Error {
 public:
  using Error::Error;
};

// Physics diverged or rendering failed during a reset or step; the message
// names the task, object, seed and step.
class EpisodeFailure : public Error {
 public:
  using Error::Error;
};

// What a step gives; the one place the episode's end is decided (the
// CLI, the evaluation kit, demonstrations and Python read it from here).
struct StepResult {
  double reward = 0;
  bool terminated = false;  // success, in an environment that stops on success
  bool truncated = false;   // the time limit: max_episode_steps steps taken
  bool success = false;   // the last condition
  std::vector<uint8_t> flags;   // one per success condition
  std::vector<double> values;   // one per success condition
  bool isDone() const { return terminated || truncated; }
};

// The task's build_scene refused an object: its files (a URDF the scene
// cannot load, a mesh that is not there). Environment's constructor skips
// such an object; a configuration error (a camera or material naming a
// link the scene lacks) is no object's fault and propagates as it was.
class ObjectLoadError : public PluginCallError {
 public:
  using PluginCallError::PluginCallError;
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
  // of them, and a reset on any other object throws InvalidArgument.
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
  // The layout policies see in `mode` (unset: the environment's own).
  PolicyLayout calcPolicyLayout(std::optional<ObservationMode> mode = std::nullopt) const;
  // The task's objects of `split`, less those whose scene failed to build
  // in this environment (getSkippedObjects).
  std::vector<std::string> listObjects(const std::string& split) const;
  // An object's category (a PartNet-Mobility object's folder's name), ""
  // where the task gives none.
  std::string getObjectCategory(const std::string& object_id) const { return task_->getObjectCategory(object_id); }
  // Objects whose scene could not be built, with the reason (the file and
  // element at fault). The constructor builds the first object that loads:
  // one unloadable object of a user's folder warns and is skipped, it never
  // makes the task unusable.
  const std::map<std::string, std::string>& getSkippedObjects() const { return skipped_objects_; }
  // Builds the scene of `object_id` anew (what reset() does when the object
  // changes), for `manibench objects --check`: throws what building throws.
  void loadObject(const std::string& object_id);

  // Starts an episode on `object_id` (rebuilding the scene only when the
  // object changes) with randomization from `seed`. Identical arguments give
  // identical episodes, whatever ran before.
  void reset(const std::string& object_id, uint64_t seed);
  // Validates (size, finite), clips to [-1, 1], runs frame_skip control
  // steps, then computes reward, success and the next observation: the
  // per-step contract of abi.h. Throws std::logic_error before reset().
  StepResult step(const Eigen::VectorXd& action);

  const Eigen::VectorXd& getObservation() const { return observation_; }
  // The visual part of the observation (mode State and empty in the state
  // mode), computed with the state vector at every reset and step.
  const VisualObservation& getVisualObservation() const { return visual_; }
  ObservationMode getObservationMode() const { return options_.observation.mode; }
  const EnvironmentOptions& getOptions() const { return options_; }

  // The whole episode state as one versioned blob (docs/demonstrations.md):
  // task, object, seed and step, the scene (positions, speeds, friction
  // anchors, drives), the controller's and the task's own state (ABI 1.2).
  // restoreState resets the blob's object from the blob's seed (so the
  // plugins choose again what their resets chose), then sets everything
  // else, and observes: the steps that follow are bit-identical to those
  // that followed the save (under implicit_euler; integrators with a step
  // history restart at each save, see Scene::saveState). Throws
  // InvalidArgument for a blob of another task, of an unknown
  // version, cut short, or made by another scene structure; PluginCallError
  // when a plugin cannot save or restore (built against ABI < 1.2).
  std::vector<uint8_t> saveState();
  void restoreState(const std::vector<uint8_t>& blob);
  // The task's progress signals now (ABI 1.6; names in the task
  // description's progress_signals, empty when it has none): how far the
  // episode has come, for telling why one failed (survey). Reads only.
  // Throws std::logic_error before reset().
  std::vector<double> measureProgress();
  // The task, object, seed and step a blob holds, without restoring it
  // (throws as restoreState for a blob that is not one).
  struct StateHeader {
    uint32_t version = 0;
    std::string task, object_id;
    uint64_t seed = 0;
    uint32_t step = 0;
  };
  static StateHeader readStateHeader(const std::vector<uint8_t>& blob);
  // The first difference between two blobs of this environment's task, for
  // people: a header field, the scene's (Scene::findStateDifference), the
  // controller's or the task's bytes; "" when they are identical.
  std::string findStateDifference(const std::vector<uint8_t>& a,
                                  const std::vector<uint8_t>& b) const;
  // As findStateDifference, of the object, seed and scene alone (not the
  // step, nor the controller's or the task's bytes): environments with
  // other controllers or frame_skip agree on it in the same physical state
  // (demos convert --controller checks its target with it).
  std::string findSceneDifference(const std::vector<uint8_t>& a,
                                  const std::vector<uint8_t>& b) const;
  // The cameras, masks and renderer of the current scene: `render`, videos
  // and tests render through it in any mode (only then is a renderer made).
  const VisualObserver& getObserver() const { return *observer_; }
  VisualObserver& updObserver() { return *observer_; }
  uint32_t getElapsedSteps() const { return elapsed_steps_; }
  // ABI 1.7: for a controller that is a layer over another
  // (getControllerDescription().base_controller), the base's action (`dim`
  // values) that its last control step produced; with frame_skip 1 it is
  // the whole last step's (demos convert --controller). Throws
  // PluginCallError for a controller that is no layer.
  Eigen::VectorXd getBaseAction(uint32_t dim);
  // Seconds spent so far in the parts of step() and reset() (manibench
  // bench's stage table): physics (controller and integrator) and the task
  // (reward, success, its state vector). Rendering and assembling the visual
  // observation are the observer's (VisualObserver::getTimes).
  struct StageTimes {
    double physics = 0, task = 0;
  };
  const StageTimes& getStageTimes() const { return stage_times_; }
  const std::string& getObjectId() const { return object_id_; }
  uint64_t getSeed() const { return seed_; }
  // The seed of this step's point-cloud sample: each step samples anew, yet
  // (seed, step) fixes the sample (the viewer's clouds draw the same).
  uint64_t calcSampleSeed() const { return seed_ * 0x9E3779B97F4A7C15ull + elapsed_steps_; }
  const Scene& getScene() const;
  Scene& updScene();

 private:
  void buildScene(const std::string& object_id);
  // reset() but the first observation: the scene of `object_id` in its
  // built state, the task's and controller's resets from `seed`.
  void startEpisode(const std::string& object_id, uint64_t seed);
  // The options' per-body settings, on a scene the task has just built.
  void applySceneOptions(const std::string& object_id);
  std::string describeEpisode() const;
  // The task's state vector (only the robot's part in the visual modes)
  // and the visual observation of the current state.
  void observe();

  const PluginRegistry& registry_;
  EnvironmentOptions options_;
  std::string environment_id_;
  std::vector<std::string> fixed_objects_;  // empty: every object of the task
  std::map<std::string, std::string> skipped_objects_;  // id -> why it does not build
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
  bool episode_started_ = false;  // reset() succeeded on the current scene
  uint64_t seed_ = 0;
  uint32_t elapsed_steps_ = 0;
  Eigen::VectorXd observation_;
  Eigen::VectorXd clipped_action_;
  // The observation module of the current scene, declared after the scene
  // it reads so that it goes first.
  std::unique_ptr<SegmentationMasks> masks_;
  std::unique_ptr<VisualObserver> observer_;
  VisualObservation visual_;
  StageTimes stage_times_;
};

}  // namespace manibench
