// Writing a task: derive from sdk::Task, describe the task in describe(),
// and register it:
//   MANIBENCH_REGISTER_TASK(MyTask, "MyTask-v0", "one line summary");
// MyTask is constructed from (const sdk::Config&) if it can be, else by
// default.
#pragma once

#include <manibench/sdk/common.hpp>
#include <manibench/sdk/registry.hpp>
#include <manibench/sdk/scene_view.hpp>
#include <manibench/sdk/state.hpp>

#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace manibench::sdk {

// What describe() returns. Required: `robot_articulation` (the name
// buildScene gives the robot's addUrdf* call) and `actuated_joints` (joints
// of that articulation, in action order): the environment refuses a scene
// without them, naming the articulation or joint. `observation` is what
// policies see in state mode (empty: nothing). Everything else has a
// working default; the host refuses, naming the field, success_conditions
// not ending with "success", a non-positive control_frequency, frame_skip
// or max_episode_steps, a segment beyond the observation, and an
// agent_state_dim that does not end a segment.
struct TaskSpec {
  std::vector<Segment> observation;  // the `state` observation, in order
  // Named success conditions; the last one must be "success".
  std::vector<std::string> success_conditions = {"success"};
  std::vector<std::string> masks;  // segmentation masks (B.3); none: no mask channels
  std::string robot_articulation;  // required: name buildScene gives the robot
  std::vector<std::string> actuated_joints;  // required: in action order
  std::string default_controller = "joint_velocity";
  std::string controller_config;  // YAML for the controller; empty: its defaults
  double control_frequency = 100;
  uint32_t frame_skip = 5;
  uint32_t max_episode_steps = 200;
  // The task's layer of the YAML configuration (see docs/configuration.md).
  std::string default_config;
  // How many leading values of `observation` (whole segments) are the
  // robot's own state, what the pointcloud and rgbd modes pass on in place
  // of the full state (which holds privileged object state). 0: all.
  uint32_t agent_state_dim = 0;
  // When > 0, `success` (the last condition) is satisfied only once the
  // condition the task returns last has held at this many consecutive env
  // steps (ManiSkill's "open and still for N steps"), and its value becomes
  // that count. The SDK counts, on the per-step contract of abi.h
  // (evaluate_success exactly once per env step, reset before the first),
  // so no task keeps such a counter itself.
  uint32_t success_hold_steps = 0;
  // ABI 1.6: names of the values Task::measureProgress returns, in order
  // (abi.h lists those the host interprets: reached, holding, progress,
  // blocked). Empty: the task says nothing of its progress.
  std::vector<std::string> progress_signals;
};

// One success condition's outcome: whether it holds, and the value behind
// it (a distance, an angle, a count) for reporting.
struct Condition {
  bool satisfied = false;
  double value = 0;
};

class Task {
 public:
  virtual ~Task() = default;
  virtual TaskSpec describe() const = 0;
  // Object ids of a split. Tasks without object instances have one object.
  virtual std::vector<std::string> listObjects(const std::string& split) const {
    if (split != "train" && split != "test")
      throw Error("unknown split '" + split + "' (use train or test)",
                  MB_INVALID_ARGUMENT);
    return {"0"};
  }
  virtual void buildScene(SceneView& scene, const std::string& object_id) = 0;
  virtual void reset(SceneView& scene, uint64_t seed) = 0;
  virtual void observe(const SceneView& scene,
                       Eigen::Map<Eigen::VectorXd> out) = 0;
  virtual double computeReward(const SceneView& scene,
                               Eigen::Map<const Eigen::VectorXd> action) = 0;
  // One entry per TaskSpec::success_conditions, in that order.
  virtual std::vector<Condition> evaluateSuccess(const SceneView& scene) = 0;
  // One value per TaskSpec::progress_signals, of the scene as it is (ABI
  // 1.6). Reads only: the host may call it between any two steps.
  virtual std::vector<double> measureProgress(const SceneView&) const { return {}; }
  // The category of an object of listObjects (ABI 1.8): a PartNet-Mobility
  // object's folder's name ("StorageFurniture"), "" for none.
  virtual std::string getObjectCategory(const std::string& /*object_id*/) const { return {}; }
};

namespace detail {

struct TaskHandle {
  std::unique_ptr<Task> task;
  TaskSpec spec;
  SegmentTable observation;
  StringTable conditions, masks, joints, progress;
  std::map<std::string, std::unique_ptr<StringTable>> objects;
  std::map<std::string, std::string> categories;  // by object id, as asked
  uint32_t held_steps = 0;  // TaskSpec::success_hold_steps' count

  TaskHandle(std::unique_ptr<Task> t, TaskSpec s)
      : task(std::move(t)),
        spec(std::move(s)),
        observation(spec.observation),
        conditions(spec.success_conditions),
        masks(spec.masks),
        joints(spec.actuated_joints),
        progress(spec.progress_signals) {
    if (spec.success_conditions.empty() || spec.success_conditions.back() != "success")
      throw Error("TaskSpec::success_conditions must end with \"success\"",
                  MB_INVALID_ARGUMENT);
  }
};

inline TaskHandle* asTask(mb_task* t) { return reinterpret_cast<TaskHandle*>(t); }

template <class T>
struct TaskTrampolines {
  static mb_status create(const char* config_yaml, mb_task** out, mb_error* err) {
    return guard(err, [&] {
      *out = nullptr;
      const Config config(config_yaml);
      std::unique_ptr<Task> task;
      if constexpr (std::is_constructible_v<T, const Config&>)
        task = std::make_unique<T>(config);
      else
        task = std::make_unique<T>();
      TaskSpec spec = task->describe();
      *out = reinterpret_cast<mb_task*>(new TaskHandle(std::move(task), std::move(spec)));
    });
  }
  static void destroy(mb_task* t) noexcept {
    try {
      delete asTask(t);
    } catch (...) {
    }
  }
  static mb_status getInfo(mb_task* t, mb_task_info* out, mb_error* err) {
    return guard(err, [&] {
      const TaskHandle& h = *asTask(t);
      mb_task_info info{};
      info.struct_size = sizeof(mb_task_info);
      info.observation_dim = h.observation.total();
      info.observation_segment_count = h.observation.count();
      info.observation_segments = h.observation.data();
      info.success_condition_count = h.conditions.count();
      info.success_conditions = h.conditions.data();
      info.mask_count = h.masks.count();
      info.masks = h.masks.data();
      info.robot_articulation = h.spec.robot_articulation.c_str();
      info.actuated_joint_count = h.joints.count();
      info.actuated_joints = h.joints.data();
      info.default_controller = h.spec.default_controller.c_str();
      info.controller_config = h.spec.controller_config.c_str();
      info.control_frequency = h.spec.control_frequency;
      info.frame_skip = h.spec.frame_skip;
      info.max_episode_steps = h.spec.max_episode_steps;
      info.default_config = h.spec.default_config.c_str();
      info.agent_state_dim = h.spec.agent_state_dim;
      info.progress_signal_count = h.progress.count();
      info.progress_signals = h.progress.data();
      writeOutputStruct(out, info);
    });
  }
  static mb_status listObjects(mb_task* t, const char* split,
                               const char* const** out_ids, uint32_t* out_count,
                               mb_error* err) {
    return guard(err, [&] {
      TaskHandle& h = *asTask(t);
      const std::string key = split ? split : "";
      auto& table = h.objects[key];
      if (!table) table = std::make_unique<StringTable>(h.task->listObjects(key));
      *out_ids = table->data();
      *out_count = table->count();
    });
  }
  static mb_status getObjectCategory(mb_task* t, const char* object_id, const char** out_category,
                                     mb_error* err) {
    return guard(err, [&] {
      TaskHandle& h = *asTask(t);
      const std::string id = object_id ? object_id : "";
      auto found = h.categories.find(id);
      if (found == h.categories.end()) found = h.categories.emplace(id, h.task->getObjectCategory(id)).first;
      *out_category = found->second.c_str();
    });
  }
  static mb_status buildScene(mb_task* t, const mb_scene_api* api, mb_scene* scene,
                              const char* object_id, mb_error* err) {
    return guard(err, [&] {
      SceneView view(api, scene);
      asTask(t)->task->buildScene(view, object_id ? object_id : "");
    });
  }
  static mb_status reset(mb_task* t, const mb_scene_api* api, mb_scene* scene,
                         uint64_t seed, mb_error* err) {
    return guard(err, [&] {
      SceneView view(api, scene);
      TaskHandle& h = *asTask(t);
      h.task->reset(view, seed);
      h.held_steps = 0;
    });
  }
  static mb_status observe(mb_task* t, const mb_scene_api* api, mb_scene* scene,
                           double* out, uint32_t dim, mb_error* err) {
    return guard(err, [&] {
      TaskHandle& h = *asTask(t);
      checkVectorSize("observation buffer", h.observation.total(), dim);
      const SceneView view(api, scene);
      h.task->observe(view, Eigen::Map<Eigen::VectorXd>(out, dim));
    });
  }
  static mb_status computeReward(mb_task* t, const mb_scene_api* api,
                                 mb_scene* scene, const double* action,
                                 uint32_t action_dim, double* out_reward,
                                 mb_error* err) {
    return guard(err, [&] {
      const SceneView view(api, scene);
      *out_reward = asTask(t)->task->computeReward(
          view, Eigen::Map<const Eigen::VectorXd>(action, action_dim));
    });
  }
  static mb_status evaluateSuccess(mb_task* t, const mb_scene_api* api,
                                   mb_scene* scene, uint8_t* out_flags,
                                   double* out_values, uint32_t count,
                                   mb_error* err) {
    return guard(err, [&] {
      TaskHandle& h = *asTask(t);
      checkVectorSize("success condition buffer", h.conditions.count(), count);
      const SceneView view(api, scene);
      const std::vector<Condition> result = h.task->evaluateSuccess(view);
      checkVectorSize("evaluateSuccess() result", count, result.size());
      for (uint32_t i = 0; i < count; ++i) {
        out_flags[i] = result[i].satisfied ? 1 : 0;
        out_values[i] = result[i].value;
      }
      if (h.spec.success_hold_steps > 0) {
        h.held_steps = result.back().satisfied ? h.held_steps + 1 : 0;
        out_flags[count - 1] = h.held_steps >= h.spec.success_hold_steps ? 1 : 0;
        out_values[count - 1] = double(h.held_steps);
      }
    });
  }

  static mb_status measureProgress(mb_task* t, const mb_scene_api* api, mb_scene* scene,
                                   double* out, uint32_t count, mb_error* err) {
    return guard(err, [&] {
      const TaskHandle& h = *asTask(t);
      checkVectorSize("progress buffer", h.progress.count(), count);
      const SceneView view(api, scene);
      const std::vector<double> values = h.task->measureProgress(view);
      checkVectorSize("measureProgress() result", count, values.size());
      std::copy(values.begin(), values.end(), out);
    });
  }

  // ABI 1.2: the hold count, then the task's Stateful part (state.hpp).
  static mb_status getState(mb_task* t, uint8_t* out, uint64_t capacity, uint64_t* out_size,
                            mb_error* err) {
    const TaskHandle& h = *asTask(t);
    return saveState(
        *h.task, [&](StateWriter& w) { w.write(h.held_steps); }, out, capacity, out_size, err);
  }
  static mb_status setState(mb_task* t, const uint8_t* data, uint64_t size, mb_error* err) {
    TaskHandle& h = *asTask(t);
    return restoreState(
        *h.task, [&](StateReader& r) { r.read(h.held_steps); }, data, size, err);
  }
};

template <class T>
bool registerTask(const char* name, const char* summary) {
  static_assert(std::is_base_of_v<Task, T>, "a task derives from manibench::sdk::Task");
  auto* d = newDescriptor<mb_task_descriptor>(MB_KIND_TASK, name, summary);
  d->create = &TaskTrampolines<T>::create;
  d->destroy = &TaskTrampolines<T>::destroy;
  d->get_info = &TaskTrampolines<T>::getInfo;
  d->list_objects = &TaskTrampolines<T>::listObjects;
  d->build_scene = &TaskTrampolines<T>::buildScene;
  d->reset = &TaskTrampolines<T>::reset;
  d->observe = &TaskTrampolines<T>::observe;
  d->compute_reward = &TaskTrampolines<T>::computeReward;
  d->evaluate_success = &TaskTrampolines<T>::evaluateSuccess;
  d->get_state = &TaskTrampolines<T>::getState;
  d->set_state = &TaskTrampolines<T>::setState;
  d->measure_progress = &TaskTrampolines<T>::measureProgress;
  d->get_object_category = &TaskTrampolines<T>::getObjectCategory;
  return true;
}

}  // namespace detail
}  // namespace manibench::sdk

#define MANIBENCH_REGISTER_TASK(Class, name, summary)                     \
  static const bool MANIBENCH_SDK_CONCAT(manibench_registered_task_,      \
                                         __COUNTER__) =                   \
      ::manibench::sdk::detail::registerTask<Class>(name, summary)
