#include <manibench/plugin_instances.hpp>

#include <array>
#include <cstring>

namespace manibench {
namespace {

constexpr std::size_t kErrorCapacity = 2048;

// Calls a plugin function with a fresh error buffer; a failure becomes a
// PluginCallError "<kind> '<name>' <call> failed: <plugin's message>".
template <class Fn, class... Args>
void callPlugin(const char* kind, const std::string& name, const char* call, Fn fn,
                Args... args) {
  char buffer[kErrorCapacity] = {0};
  mb_error err{buffer, sizeof(buffer)};
  const mb_status status = fn(args..., &err);
  if (status != MB_OK) {
    std::string message = std::string(kind) + " '" + name + "' " + call + " failed";
    message += buffer[0] ? std::string(": ") + buffer : " (status " + std::to_string(status) + ", no message)";
    throw PluginCallError(message, status);
  }
}

// ABI 1.2's get_state/set_state of a task or controller descriptor; an
// older plugin lacks them.
template <class Descriptor>
void requireStateCalls(const Descriptor& d, const char* kind, const std::string& name,
                       const std::string& library) {
  if (!MB_HAS_FIELD(Descriptor, set_state, d.header.struct_size) || !d.get_state || !d.set_state)
    throw PluginCallError(std::string(kind) + " '" + name + "' (" + library +
                              ") cannot save or restore its state: it was built against an "
                              "ABI older than 1.2, which adds get_state and set_state; "
                              "rebuild it against this SDK",
                          MB_UNSUPPORTED);
}

template <class Descriptor, class Handle>
std::vector<uint8_t> callGetState(const Descriptor& d, Handle* handle, const char* kind,
                                  const std::string& name, const std::string& library) {
  requireStateCalls(d, kind, name, library);
  std::vector<uint8_t> bytes(1024);
  uint64_t size = 0;
  callPlugin(kind, name, "get_state", d.get_state, handle, bytes.data(),
             uint64_t(bytes.size()), &size);
  if (size > bytes.size()) {  // asked again with room for it
    bytes.resize(size);
    callPlugin(kind, name, "get_state", d.get_state, handle, bytes.data(),
               uint64_t(bytes.size()), &size);
  }
  bytes.resize(size);
  return bytes;
}

template <class Descriptor, class Handle>
void callSetState(const Descriptor& d, Handle* handle, const char* kind, const std::string& name,
                  const std::string& library, const std::vector<uint8_t>& bytes) {
  requireStateCalls(d, kind, name, library);
  callPlugin(kind, name, "set_state", d.set_state, handle, bytes.data(), uint64_t(bytes.size()));
}

std::vector<sdk::Segment> toSegments(const mb_segment* segments, uint32_t count,
                                           uint32_t dim, const char* what,
                                           const std::string& owner) {
  std::vector<sdk::Segment> out;
  for (uint32_t i = 0; i < count; ++i) {
    const mb_segment& s = segments[i];
    if (s.offset + s.size > dim)
      throw PluginCallError(owner + ": " + what + " segment '" + (s.name ? s.name : "?") +
                                "' [" + std::to_string(s.offset) + ", " +
                                std::to_string(s.offset + s.size) + ") exceeds the dimension " +
                                std::to_string(dim),
                            MB_ERROR);
    out.push_back(sdk::Segment::fromC(s));
  }
  return out;
}

std::vector<std::string> toStrings(const char* const* strings, uint32_t count) {
  std::vector<std::string> out;
  for (uint32_t i = 0; i < count; ++i) out.push_back(strings && strings[i] ? strings[i] : "");
  return out;
}

std::vector<mb_segment> toCSegments(const std::vector<sdk::Segment>& segments) {
  std::vector<mb_segment> out;
  for (const sdk::Segment& s : segments) out.push_back(s.toC());
  return out;
}

// A plugin's info record through get_info, struct_size set first (a
// plugin older than this host fills only the fields it knows).
template <class Info, class Descriptor, class Handle>
Info fetchInfo(const char* kind, const std::string& name, const Descriptor& d, Handle* handle) {
  Info info{};
  info.struct_size = sizeof(info);
  callPlugin(kind, name, "get_info", d.get_info, handle, &info);
  return info;
}

// A task's description from its info record, checked: the host refuses,
// naming the task, what it cannot run. Fields of a plugin older than this
// host stay zero-initialized.
TaskDescription describeTask(const std::string& name, const mb_task_info& info) {
  TaskDescription d;
  d.name = name;
  d.observation_dim = info.observation_dim;
  d.observation_segments =
      toSegments(info.observation_segments, info.observation_segment_count,
                 info.observation_dim, "observation", "task '" + name + "'");
  d.success_conditions =
      toStrings(info.success_conditions, info.success_condition_count);
  if (d.success_conditions.empty() ||
      d.success_conditions.back() != "success")
    throw PluginCallError("task '" + name + "': its last success condition must be \"success\"",
                          MB_ERROR);
  d.masks = toStrings(info.masks, info.mask_count);
  d.robot_articulation = info.robot_articulation ? info.robot_articulation : "";
  d.actuated_joints = toStrings(info.actuated_joints, info.actuated_joint_count);
  d.default_controller = info.default_controller ? info.default_controller : "";
  d.controller_config = info.controller_config ? info.controller_config : "";
  d.control_frequency = info.control_frequency;
  d.frame_skip = info.frame_skip;
  d.max_episode_steps = info.max_episode_steps;
  if (MB_HAS_FIELD(mb_task_info, default_config, info.struct_size) && info.default_config)
    d.default_config = info.default_config;
  d.agent_state_dim = d.observation_dim;
  if (MB_HAS_FIELD(mb_task_info, agent_state_dim, info.struct_size) && info.agent_state_dim > 0) {
    bool on_boundary = false;
    for (const sdk::Segment& s : d.observation_segments)
      on_boundary = on_boundary || s.offset + s.size == info.agent_state_dim;
    if (info.agent_state_dim > info.observation_dim || !on_boundary)
      throw PluginCallError("task '" + name + "': agent_state_dim " +
                                std::to_string(info.agent_state_dim) +
                                " must end an observation segment within the " +
                                std::to_string(info.observation_dim) + " state values",
                            MB_ERROR);
    d.agent_state_dim = info.agent_state_dim;
  }
  if (MB_HAS_FIELD(mb_task_info, progress_signals, info.struct_size))
    d.progress_signals = toStrings(info.progress_signals, info.progress_signal_count);
  if (!(d.control_frequency > 0) || d.frame_skip == 0 ||
      d.max_episode_steps == 0)
    throw PluginCallError("task '" + name +
                              "': control_frequency, frame_skip and max_episode_steps must be positive",
                          MB_ERROR);
  return d;
}

}  // namespace

// ---- task --------------------------------------------------------------

TaskInstance::TaskInstance(const PluginRegistry& registry, const std::string& name,
                           const std::string& config_yaml)
    : descriptor_(&registry.getTask(name)) {
  library_path_ = registry.getLibraries()[registry.getEntry(PluginKind::Task, name).library].path;
  callPlugin("task", name, "create", descriptor_->create, config_yaml.c_str(), &handle_);
  if (handle_ == nullptr) throw PluginCallError("task '" + name + "' create returned no task", MB_ERROR);

  try {
    const auto info = fetchInfo<mb_task_info>("task", name, *descriptor_, handle_);
    description_ = describeTask(name, info);
  } catch (...) {
    descriptor_->destroy(handle_);
    throw;
  }
}

TaskInstance::~TaskInstance() {
  if (handle_) descriptor_->destroy(handle_);
}

std::vector<std::string> TaskInstance::listObjects(const std::string& split) const {
  const char* const* ids = nullptr;
  uint32_t count = 0;
  callPlugin("task", description_.name, "list_objects", descriptor_->list_objects, handle_,
             split.c_str(), &ids, &count);
  return toStrings(ids, count);
}

std::string TaskInstance::getObjectCategory(const std::string& object_id) const {
  if (!MB_HAS_FIELD(mb_task_descriptor, get_object_category, descriptor_->header.struct_size) ||
      !descriptor_->get_object_category)
    return {};
  const char* category = nullptr;
  callPlugin("task", description_.name, "get_object_category", descriptor_->get_object_category, handle_,
             object_id.c_str(), &category);
  return category ? category : "";
}

void TaskInstance::buildScene(SceneBridge& scene, const std::string& object_id) {
  callPlugin("task", description_.name, "build_scene", descriptor_->build_scene, handle_,
             SceneBridge::getApi(), scene.getHandle(), object_id.c_str());
}

void TaskInstance::reset(SceneBridge& scene, uint64_t seed) {
  callPlugin("task", description_.name, "reset", descriptor_->reset, handle_,
             SceneBridge::getApi(), scene.getHandle(), seed);
}

std::vector<double> TaskInstance::measureProgress(SceneBridge& scene) {
  std::vector<double> values(description_.progress_signals.size());
  if (values.empty()) return values;
  if (!MB_HAS_FIELD(mb_task_descriptor, measure_progress, descriptor_->header.struct_size) ||
      !descriptor_->measure_progress)
    throw PluginCallError("task '" + description_.name + "' names progress signals but has no measure_progress",
                          MB_ERROR);
  callPlugin("task", description_.name, "measure_progress", descriptor_->measure_progress, handle_,
             SceneBridge::getApi(), scene.getHandle(), values.data(), static_cast<uint32_t>(values.size()));
  return values;
}

void TaskInstance::observe(SceneBridge& scene, Eigen::VectorXd& out) {
  out.resize(description_.observation_dim);
  callPlugin("task", description_.name, "observe", descriptor_->observe, handle_,
             SceneBridge::getApi(), scene.getHandle(), out.data(),
             static_cast<uint32_t>(out.size()));
}

double TaskInstance::computeReward(SceneBridge& scene, const Eigen::VectorXd& action) {
  double reward = 0;
  callPlugin("task", description_.name, "compute_reward", descriptor_->compute_reward, handle_,
             SceneBridge::getApi(), scene.getHandle(), action.data(),
             static_cast<uint32_t>(action.size()), &reward);
  return reward;
}

void TaskInstance::evaluateSuccess(SceneBridge& scene, std::vector<uint8_t>& flags,
                                   std::vector<double>& values) {
  const std::size_t n = description_.success_conditions.size();
  flags.assign(n, 0);
  values.assign(n, 0.0);
  callPlugin("task", description_.name, "evaluate_success", descriptor_->evaluate_success,
             handle_, SceneBridge::getApi(), scene.getHandle(), flags.data(), values.data(),
             static_cast<uint32_t>(n));
}

std::vector<uint8_t> TaskInstance::saveState() {
  return callGetState(*descriptor_, handle_, "task", description_.name, library_path_);
}

void TaskInstance::restoreState(const std::vector<uint8_t>& bytes) {
  callSetState(*descriptor_, handle_, "task", description_.name, library_path_, bytes);
}

// ---- controller ----------------------------------------------------------

ControllerInstance::ControllerInstance(const PluginRegistry& registry, const std::string& name,
                                       const std::string& config_yaml,
                                       const mb_controller_context& context)
    : descriptor_(&registry.getController(name)),
      library_path_(
          registry.getLibraries()[registry.getEntry(PluginKind::Controller, name).library].path) {
  callPlugin("controller", name, "create", descriptor_->create, config_yaml.c_str(), &context,
             &handle_);
  if (handle_ == nullptr)
    throw PluginCallError("controller '" + name + "' create returned no controller", MB_ERROR);
  try {
    const auto info = fetchInfo<mb_controller_info>("controller", name, *descriptor_, handle_);
    description_.name = name;
    description_.action_dim = info.action_dim;
    description_.action_segments = toSegments(info.action_segments, info.action_segment_count,
                                              info.action_dim, "action", "controller '" + name + "'");
    description_.flags = info.flags;
    // A plugin older than ABI 1.7 ends its info before base_controller.
    if (MB_HAS_FIELD(mb_controller_info, base_controller, info.struct_size) && info.base_controller)
      description_.base_controller = info.base_controller;
  } catch (...) {
    descriptor_->destroy(handle_);
    throw;
  }
}

ControllerInstance::~ControllerInstance() {
  if (handle_) descriptor_->destroy(handle_);
}

void ControllerInstance::reset(SceneBridge& scene) {
  callPlugin("controller", description_.name, "reset", descriptor_->reset, handle_,
             SceneBridge::getApi(), scene.getHandle());
}

void ControllerInstance::compute(SceneBridge& scene, const Eigen::VectorXd& action,
                                 std::vector<DriveCommand>& drives) {
  callPlugin("controller", description_.name, "compute", descriptor_->compute, handle_,
             SceneBridge::getApi(), scene.getHandle(), action.data(),
             static_cast<uint32_t>(action.size()), drives.data(),
             static_cast<uint32_t>(drives.size()));
}

std::vector<uint8_t> ControllerInstance::saveState() {
  return callGetState(*descriptor_, handle_, "controller", description_.name, library_path_);
}

void ControllerInstance::restoreState(const std::vector<uint8_t>& bytes) {
  callSetState(*descriptor_, handle_, "controller", description_.name, library_path_, bytes);
}

Eigen::VectorXd ControllerInstance::getBaseAction(uint32_t dim) {
  if (description_.base_controller.empty() ||
      !MB_HAS_FIELD(mb_controller_descriptor, get_base_action, descriptor_->header.struct_size) ||
      !descriptor_->get_base_action)
    throw PluginCallError("controller '" + description_.name + "' (" + library_path_ +
                              ") is no layer over another controller (ABI 1.7 base_controller and "
                              "get_base_action)",
                          MB_UNSUPPORTED);
  Eigen::VectorXd action(dim);
  callPlugin("controller", description_.name, "get_base_action", descriptor_->get_base_action, handle_,
             action.data(), dim);
  return action;
}

// ---- policy ----------------------------------------------------------------

PolicyInstance::PolicyInstance(const PluginRegistry& registry, const std::string& name,
                               const std::string& config_yaml, const PolicyLayout& layout)
    : descriptor_(&registry.getPolicy(name)), name_(name), action_dim_(layout.action_dim) {
  library_path_ =
      registry.getLibraries()[registry.getEntry(PluginKind::Policy, name).library].path;
  const std::vector<mb_segment> observation = toCSegments(layout.observation_segments);
  const std::vector<mb_segment> action = toCSegments(layout.action_segments);
  mb_policy_context context{};
  context.struct_size = sizeof(context);
  context.task_name = layout.task_name.c_str();
  context.observation_mode = toString(layout.observation_mode);
  context.observation_dim = layout.observation_dim;
  context.observation_segment_count = static_cast<uint32_t>(observation.size());
  context.observation_segments = observation.data();
  context.action_dim = layout.action_dim;
  context.action_segment_count = static_cast<uint32_t>(action.size());
  context.action_segments = action.data();
  callPlugin("policy", name, "create", descriptor_->create, config_yaml.c_str(), &context,
             &handle_);
  if (handle_ == nullptr) throw PluginCallError("policy '" + name + "' create returned no policy", MB_ERROR);
}

PolicyInstance::~PolicyInstance() {
  if (handle_) descriptor_->destroy(handle_);
}

void PolicyInstance::reset(const PolicyEpisode& episode) {
  // A policy built against ABI 1.0-1.4 ends before reset_episode.
  if (MB_HAS_FIELD(mb_policy_descriptor, reset_episode, descriptor_->header.struct_size) &&
      descriptor_->reset_episode) {
    mb_episode_info info{};
    info.struct_size = sizeof(info);
    info.task_name = episode.task_name.c_str();
    info.object_id = episode.object_id.c_str();
    info.seed = episode.seed;
    callPlugin("policy", name_, "reset_episode", descriptor_->reset_episode, handle_, &info);
    return;
  }
  callPlugin("policy", name_, "reset", descriptor_->reset, handle_, episode.seed);
}

void PolicyInstance::act(const Eigen::VectorXd& observation, uint32_t step,
                         Eigen::VectorXd& action, const VisualObservation& visual) {
  const mb_observation obs = makeObservationView(observation, step, visual, rgb_floats_);
  action.setZero(action_dim_);
  callPlugin("policy", name_, "act", descriptor_->act, handle_, &obs, action.data(),
             static_cast<uint32_t>(action.size()));
}

mb_observation makeObservationView(const Eigen::VectorXd& state, uint32_t step,
                                   const VisualObservation& visual, std::vector<float>& rgb_floats) {
  mb_observation obs = makeObservationView(state, step, visual);
  if (visual.mode == ObservationMode::Rgbd && visual.rgb.empty() && !visual.rgb_bytes.empty()) {
    // A table of the 256 quotients: a division per value took 0.6 ms per
    // rgbd step (230,400 values), as long as the whole assembly; the table
    // 0.25-0.3 ms (manibench bench --set observation.rgb_dtype=uint8).
    static const std::array<float, 256> kUnit = [] {
      std::array<float, 256> table{};
      for (std::size_t b = 0; b < table.size(); ++b) table[b] = float(b) / 255.0f;
      return table;
    }();
    rgb_floats.resize(visual.rgb_bytes.size());
    for (std::size_t i = 0; i < rgb_floats.size(); ++i) rgb_floats[i] = kUnit[visual.rgb_bytes[i]];
    obs.image_rgb = rgb_floats.data();
  }
  return obs;
}

mb_observation makeObservationView(const Eigen::VectorXd& state, uint32_t step,
                                   const VisualObservation& visual) {
  mb_observation obs{};
  obs.struct_size = sizeof(obs);
  obs.state = state.data();
  obs.state_dim = static_cast<uint32_t>(state.size());
  obs.step = step;
  switch (visual.mode) {
    case ObservationMode::State:
      break;
    case ObservationMode::PointCloud:
      obs.mask_count = visual.mask_count;
      obs.point_count = static_cast<uint32_t>(visual.points.size());
      obs.points_xyz = visual.points.xyz.data();
      obs.points_rgb = visual.points.rgb.data();
      obs.points_mask = visual.points.masks.data();
      break;
    case ObservationMode::Rgbd:
      obs.mask_count = visual.mask_count;
      obs.camera_count = visual.camera_count;
      obs.image_height = visual.height;
      obs.image_width = visual.width;
      obs.image_rgb = visual.rgb.data();
      obs.image_depth = visual.depth.data();
      obs.image_masks = visual.masks.data();
      break;
  }
  return obs;
}

}  // namespace manibench
