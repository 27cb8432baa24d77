#include <manibench/environment.hpp>
#include <manibench/sdk/state.hpp>
#include <manibench/stopwatch.hpp>
#include <manibench/task_name.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <stdexcept>
#include <string>

namespace manibench {

Environment::Environment(const PluginRegistry& registry, const std::string& environment_id,
                         EnvironmentOptions options)
    : registry_(registry), options_(std::move(options)), environment_id_(environment_id) {
  const TaskId id = resolveTaskId(registry_, environment_id);
  validateEnvironmentOptions(options_);
  visual_.mode = options_.observation.mode;
  task_ = std::make_unique<TaskInstance>(registry_, id.task, options_.task_config);
  description_ = task_->getDescription();
  if (options_.control_frequency) description_.control_frequency = *options_.control_frequency;
  if (options_.frame_skip) description_.frame_skip = *options_.frame_skip;
  if (options_.max_episode_steps) description_.max_episode_steps = *options_.max_episode_steps;
  const TaskDescription& task = description_;
  const std::string controller =
      options_.controller.empty() ? task.default_controller : options_.controller;
  // Fail before any physics if the controller does not exist.
  registry_.getEntry(PluginKind::Controller, controller);
  // Build the first (train or fixed) object's scene now, so that the action
  // layout (which depends on the robot's joints) is known before the first
  // reset.
  const std::vector<std::string> train = task_->listObjects("train");
  if (id.isFixed()) {
    fixed_objects_ = selectFixedObjects(id, train, task_->listObjects("test"));
    buildScene(fixed_objects_.front());
    return;
  }
  // The first object that builds, train first: a user's PartNet folder may
  // hold test objects only (the test split still runs), and an object whose
  // files the scene refuses is skipped with a warning (listObjects leaves
  // it out from then on).
  std::vector<std::string> candidates = train;
  if (candidates.empty()) candidates = task_->listObjects("test");
  if (candidates.empty())
    throw PluginCallError("task '" + task.name + "' lists no objects in either split", MB_ERROR);
  for (const std::string& object : candidates) {
    try {
      buildScene(object);
      return;
    } catch (const ObjectLoadError& e) {
      skipped_objects_[object] = e.what();
      std::cerr << "manibench: warning: " << task.name << ": skipping object " << object << ": " << e.what()
                << "\n";
    }
  }
  throw PluginCallError("task '" + task.name + "': none of its " + std::to_string(candidates.size()) +
                            " objects builds (the first's reason: " + skipped_objects_.begin()->second + ")",
                        MB_INVALID_ARGUMENT);
}

void Environment::loadObject(const std::string& object_id) { buildScene(object_id); }

Environment::~Environment() {
  // The controller and task may hold scene ids, the observer's renderer
  // reads the scene: drop them before it.
  observer_.reset();
  controller_.reset();
  bridge_.reset();
  scene_.reset();
}

const TaskDescription& Environment::getTaskDescription() const { return description_; }

const ControllerDescription& Environment::getControllerDescription() const {
  return controller_->getDescription();
}

PolicyLayout Environment::calcPolicyLayout(std::optional<ObservationMode> mode) const {
  PolicyLayout layout;
  layout.task_name = getTaskDescription().name;
  layout.observation_mode = mode.value_or(options_.observation.mode);
  layout.observation_dim = getTaskDescription().observation_dim;
  layout.observation_segments = getTaskDescription().observation_segments;
  if (isVisualMode(layout.observation_mode)) {
    // Visual modes carry only the robot's own state (as ManiSkill's).
    layout.observation_dim = getTaskDescription().agent_state_dim;
    std::vector<sdk::Segment> agent;
    for (const sdk::Segment& s : layout.observation_segments)
      if (s.offset + s.size <= layout.observation_dim) agent.push_back(s);
    layout.observation_segments = std::move(agent);
  }
  layout.action_dim = getControllerDescription().action_dim;
  layout.action_segments = getControllerDescription().action_segments;
  return layout;
}

std::vector<std::string> Environment::listObjects(const std::string& split) const {
  if (!fixed_objects_.empty()) return fixed_objects_;
  std::vector<std::string> ids = task_->listObjects(split);
  ids.erase(std::remove_if(ids.begin(), ids.end(), [this](const std::string& o) { return skipped_objects_.count(o) > 0; }),
            ids.end());
  return ids;
}

const Scene& Environment::getScene() const {
  if (!scene_) throw std::logic_error("Environment::getScene() before the first reset()");
  return *scene_;
}
Scene& Environment::updScene() {
  if (!scene_) throw std::logic_error("Environment::updScene() before the first reset()");
  return *scene_;
}

std::string Environment::describeEpisode() const {
  return "task '" + getTaskDescription().name + "', object '" + object_id_ + "', seed " +
         std::to_string(seed_) + ", step " + std::to_string(elapsed_steps_);
}

void Environment::buildScene(const std::string& object_id) {
  const TaskDescription& task = description_;
  observer_.reset();
  controller_.reset();
  bridge_.reset();
  episode_started_ = false;
  scene_ = std::make_unique<Scene>(options_.physics);
  masks_ = std::make_unique<SegmentationMasks>(task.masks);
  bridge_ = std::make_unique<SceneBridge>(*scene_, masks_.get());
  scene_built_ = false;
  initial_state_.reset();

  bridge_->setBuilding(true);
  try {
    task_->buildScene(*bridge_, object_id);
  } catch (const PluginCallError& e) {
    bridge_->setBuilding(false);
    throw ObjectLoadError(e.what(), e.status());
  } catch (...) {
    bridge_->setBuilding(false);
    throw;
  }
  bridge_->setBuilding(false);
  applySceneOptions(object_id);
  observer_ = std::make_unique<VisualObserver>(*scene_, options_.observation, *masks_, task.name);
  scene_->finalize();

  robot_ = scene_->findArticulation(task.robot_articulation);
  if (robot_ < 0)
    throw PluginCallError("task '" + task.name + "' names robot articulation '" +
                              task.robot_articulation + "', which its scene does not contain",
                          MB_ERROR);
  actuated_joints_.clear();
  std::vector<mb_joint_info> joints;
  const std::vector<JointDescription>& robot_joints = scene_->getJoints(robot_);
  for (const std::string& name : task.actuated_joints) {
    const int index = scene_->findJoint(robot_, name);
    if (index < 0)
      throw PluginCallError("task '" + task.name + "' actuates joint '" + name +
                                "', which articulation '" + task.robot_articulation +
                                "' does not have",
                            MB_ERROR);
    actuated_joints_.push_back(index);
    joints.push_back(makeJointInfo(robot_joints[index], robot_joints[index].name.c_str()));
  }
  mb_controller_context context{};
  context.struct_size = sizeof(context);
  context.articulation = robot_;
  context.joint_count = static_cast<uint32_t>(joints.size());
  context.joints = joints.data();
  context.control_frequency = task.control_frequency;
  const std::string controller_name =
      options_.controller.empty() ? task.default_controller : options_.controller;
  const std::string controller_config =
      options_.controller_config.empty() ? task.controller_config : options_.controller_config;
  controller_ = std::make_unique<ControllerInstance>(registry_, controller_name,
                                                     controller_config, context);
  const bool balance =
      (controller_->getDescription().flags & MB_CONTROLLER_BALANCE_PASSIVE_FORCES) != 0;
  scene_->setPassiveForceBalancing(robot_, actuated_joints_, balance);
  drives_.assign(actuated_joints_.size(), DriveCommand{});

  initial_state_ = scene_->saveState();
  object_id_ = object_id;
  scene_built_ = true;
}

void Environment::applySceneOptions(const std::string& object_id) {
  const std::string where = "task '" + description_.name + "', object '" + object_id + "'";
  auto findArticulation = [&](const std::string& name, const std::string& source) {
    const int articulation = scene_->findArticulation(name);
    if (articulation < 0)
      throw SceneError(source + ": the scene of " + where + " has no articulation '" + name +
                       "' (it has " + describeArticulations(*scene_) + ")");
    return articulation;
  };
  if (options_.ground_material) scene_->setGroundMaterial(*options_.ground_material);
  for (const BodyContactMaterial& body : options_.contact_materials) {
    const int articulation = findArticulation(body.articulation, body.source);
    // "NAME*": every link whose name starts with NAME, none included (a
    // family's objects differ in how many wheels they have; the task's
    // materials are written before any object is known).
    if (!body.link.empty() && body.link.back() == '*') {
      const std::string prefix = body.link.substr(0, body.link.size() - 1);
      for (const int link : scene_->listLinks(articulation))
        if (scene_->getLinkName(link).compare(0, prefix.size(), prefix) == 0)
          scene_->setContactMaterial(articulation, scene_->getLinkName(link), body.material);
      continue;
    }
    if (!body.link.empty() && scene_->findLink(articulation, body.link) < 0)
      throw SceneError(body.source + ": articulation '" + body.articulation + "' of " + where +
                       " has no link '" + body.link + "'");
    scene_->setContactMaterial(articulation, body.link, body.material);
  }
  for (const SelfCollisionSetting& setting : options_.self_collision)
    scene_->setSelfCollision(findArticulation(setting.articulation, setting.source), setting.enabled);
}

void Environment::observe() {
  const Clock::time_point start = Clock::now();
  task_->observe(*bridge_, observation_);
  stage_times_.task += secondsSince(start);
  if (isVisualMode(options_.observation.mode))
    observation_.conservativeResize(description_.agent_state_dim);
  // A renderer failure (EGL, a camera it refuses) ends the episode like a
  // diverged simulation, naming task, object, seed and step.
  try {
    observer_->observe(calcSampleSeed(), visual_);
  } catch (const RenderError& e) {
    throw EpisodeFailure(describeEpisode() + ": rendering the '" +
                         toString(options_.observation.mode) + "' observation failed: " + e.what());
  }
}

void Environment::reset(const std::string& object_id, uint64_t seed) {
  startEpisode(object_id, seed);
  observe();
  episode_started_ = true;
}

void Environment::startEpisode(const std::string& object_id, uint64_t seed) {
  if (!fixed_objects_.empty() &&
      std::find(fixed_objects_.begin(), fixed_objects_.end(), object_id) == fixed_objects_.end()) {
    std::string objects;
    for (const std::string& o : fixed_objects_) objects += (objects.empty() ? "" : ", ") + o;
    throw InvalidArgument("environment " + environment_id_ + " is fixed to object(s) " +
                                objects + "; it cannot reset on object '" + object_id +
                                "' (use " + getTaskDescription().name + " for any object)");
  }
  episode_started_ = false;
  if (!scene_built_ || object_id != object_id_) buildScene(object_id);
  // Every episode starts from the freshly built state, so its trajectory
  // depends only on (object, seed, actions), never on earlier episodes.
  scene_->restoreState(*initial_state_);
  seed_ = seed;
  elapsed_steps_ = 0;
  bridge_->setStateChangesAllowed(true);
  try {
    task_->reset(*bridge_, seed);
    controller_->reset(*bridge_);
  } catch (...) {
    bridge_->setStateChangesAllowed(false);
    throw;
  }
  bridge_->setStateChangesAllowed(false);
  drives_.assign(actuated_joints_.size(), DriveCommand{});
  scene_->setDriveCommands(robot_, actuated_joints_, drives_);
}

StepResult Environment::step(const Eigen::VectorXd& action) {
  // The per-step contract (abi.h): the task and controller were reset.
  if (!episode_started_) throw std::logic_error("Environment::step() before reset()");
  const TaskDescription& task = description_;
  const uint32_t action_dim = controller_->getDescription().action_dim;
  if (action.size() != Eigen::Index(action_dim))
    throw InvalidAction(describeEpisode() + ": the action has " + std::to_string(action.size()) +
                        " values, the controller '" + controller_->getDescription().name +
                        "' expects " + std::to_string(action_dim));
  for (Eigen::Index i = 0; i < action.size(); ++i)
    if (!std::isfinite(action[i]))
      throw InvalidAction(describeEpisode() + ": action[" + std::to_string(i) + "] is " +
                          (std::isnan(action[i]) ? "NaN" : "infinite"));
  clipped_action_ = action.cwiseMax(-1.0).cwiseMin(1.0);

  const double dt = 1.0 / task.control_frequency;
  Clock::time_point start = Clock::now();
  try {
    for (uint32_t k = 0; k < task.frame_skip; ++k) {
      controller_->compute(*bridge_, clipped_action_, drives_);
      scene_->setDriveCommands(robot_, actuated_joints_, drives_);
      scene_->advance(dt);
    }
  } catch (const SimulationDiverged& e) {
    throw EpisodeFailure(describeEpisode() + ": simulation diverged: " + e.what());
  }
  ++elapsed_steps_;
  stage_times_.physics += secondsSince(start);

  start = Clock::now();
  StepResult result;
  result.reward = task_->computeReward(*bridge_, clipped_action_);
  if (!std::isfinite(result.reward))
    throw EpisodeFailure(describeEpisode() + ": task reward is not finite");
  task_->evaluateSuccess(*bridge_, result.flags, result.values);
  result.success = result.flags.back() != 0;
  result.terminated = options_.stop_on_success && result.success;
  result.truncated = elapsed_steps_ >= task.max_episode_steps;
  stage_times_.task += secondsSince(start);
  observe();
  return result;
}

Eigen::VectorXd Environment::getBaseAction(uint32_t dim) {
  if (!episode_started_) throw std::logic_error("Environment::getBaseAction() before reset()");
  return controller_->getBaseAction(dim);
}

// --- episode state blobs ---------------------------------------------------------

namespace {

// Version 1, host byte order: "MBEN", version, task, object, seed, step,
// then the scene's, the controller's (with its name) and the task's bytes,
// each with its length.
constexpr char kStateMagic[4] = {'M', 'B', 'E', 'N'};
constexpr uint32_t kStateVersion = 1;

void writeBlob(sdk::StateWriter& out, const std::vector<uint8_t>& bytes) {
  out.write<uint64_t>(bytes.size());
  out.writeBytes(bytes.data(), bytes.size());
}

std::vector<uint8_t> readBlob(sdk::StateReader& in) {
  const uint64_t size = in.read<uint64_t>();
  if (size > in.getRemaining())
    throw InvalidArgument("a part of " + std::to_string(size) + " bytes where " +
                                std::to_string(in.getRemaining()) + " are left");
  std::vector<uint8_t> bytes(size);
  in.readBytes(bytes.data(), bytes.size());
  return bytes;
}

Environment::StateHeader readHeader(sdk::StateReader& in) {
  char magic[4];
  in.readBytes(magic, sizeof magic);
  if (std::memcmp(magic, kStateMagic, sizeof magic) != 0)
    throw InvalidArgument("not a manibench environment state (no MBEN header)");
  Environment::StateHeader header;
  header.version = in.read<uint32_t>();
  if (header.version != kStateVersion)
    throw InvalidArgument("environment state version " + std::to_string(header.version) +
                                ", this build reads version " + std::to_string(kStateVersion));
  in.read(header.task);
  in.read(header.object_id);
  in.read(header.seed);
  in.read(header.step);
  return header;
}

// A blob's parts.
struct StateParts {
  Environment::StateHeader header;
  std::vector<uint8_t> scene, controller_state, task;
  std::string controller;
};

StateParts splitState(const std::vector<uint8_t>& blob, const std::string& task) {
  StateParts parts;
  try {
    sdk::StateReader in(blob.data(), blob.size());
    parts.header = readHeader(in);
    if (parts.header.task != task)
      throw InvalidArgument("a state of task '" + parts.header.task +
                                  "', this environment is '" + task + "'");
    parts.scene = readBlob(in);
    in.read(parts.controller);
    parts.controller_state = readBlob(in);
    parts.task = readBlob(in);
    if (!in.atEnd())
      throw InvalidArgument(std::to_string(in.getRemaining()) + " bytes left over");
  } catch (const sdk::Error& e) {
    throw InvalidArgument(std::string("environment state cut short: ") + e.what());
  }
  return parts;
}

std::string findBytesDifference(const char* what, const std::vector<uint8_t>& a,
                                const std::vector<uint8_t>& b) {
  if (a == b) return "";
  if (a.size() != b.size())
    return std::string(what) + ": " + std::to_string(a.size()) + " vs " + std::to_string(b.size()) + " bytes";
  std::size_t i = 0;
  while (a[i] == b[i]) ++i;
  return std::string(what) + ": byte " + std::to_string(i) + " of " + std::to_string(a.size()) + " differs";
}

// The scenes of two blobs; `scene` (of `object_id`, may be null) names the
// first difference where the blobs are of its object.
std::string findScenePartDifference(const StateParts& x, const StateParts& y, const Scene* scene,
                                    const std::string& object_id) {
  if (x.scene == y.scene) return "";
  // The scene decodes only into a scene of its object.
  if (x.header.object_id == object_id && scene) return "scene " + scene->findStateDifference(x.scene, y.scene);
  return findBytesDifference("scene", x.scene, y.scene);
}

}  // namespace

std::vector<double> Environment::measureProgress() {
  if (!episode_started_)
    throw std::logic_error("Environment::measureProgress() before reset(): no episode to measure");
  return task_->measureProgress(*bridge_);
}

std::vector<uint8_t> Environment::saveState() {
  if (!episode_started_)
    throw std::logic_error("Environment::saveState() before reset(): no episode to save");
  sdk::StateWriter out;
  out.writeBytes(kStateMagic, sizeof kStateMagic);
  out.write(kStateVersion);
  out.write(description_.name);
  out.write(object_id_);
  out.write(seed_);
  out.write(elapsed_steps_);
  writeBlob(out, scene_->encodeState(scene_->saveState()));
  out.write(controller_->getDescription().name);
  writeBlob(out, controller_->saveState());
  writeBlob(out, task_->saveState());
  return out.bytes();
}

Environment::StateHeader Environment::readStateHeader(const std::vector<uint8_t>& blob) {
  try {
    sdk::StateReader in(blob.data(), blob.size());
    return readHeader(in);
  } catch (const sdk::Error& e) {
    throw InvalidArgument(std::string("environment state cut short: ") + e.what());
  }
}

std::string Environment::findSceneDifference(const std::vector<uint8_t>& a,
                                             const std::vector<uint8_t>& b) const {
  const StateParts x = splitState(a, description_.name), y = splitState(b, description_.name);
  if (x.header.object_id != y.header.object_id) return "object '" + x.header.object_id + "' vs '" + y.header.object_id + "'";
  if (x.header.seed != y.header.seed) return "seed " + std::to_string(x.header.seed) + " vs " + std::to_string(y.header.seed);
  return findScenePartDifference(x, y, scene_.get(), object_id_);
}

std::string Environment::findStateDifference(const std::vector<uint8_t>& a,
                                             const std::vector<uint8_t>& b) const {
  if (a == b) return "";
  const StateParts x = splitState(a, description_.name), y = splitState(b, description_.name);
  if (x.header.object_id != y.header.object_id) return "object '" + x.header.object_id + "' vs '" + y.header.object_id + "'";
  if (x.header.seed != y.header.seed) return "seed " + std::to_string(x.header.seed) + " vs " + std::to_string(y.header.seed);
  if (x.header.step != y.header.step) return "step " + std::to_string(x.header.step) + " vs " + std::to_string(y.header.step);
  if (const std::string d = findScenePartDifference(x, y, scene_.get(), object_id_); !d.empty()) return d;
  if (x.controller != y.controller) return "controller '" + x.controller + "' vs '" + y.controller + "'";
  if (const std::string d = findBytesDifference("controller state", x.controller_state, y.controller_state); !d.empty())
    return d;
  return findBytesDifference("task state", x.task, y.task);
}

void Environment::restoreState(const std::vector<uint8_t>& blob) {
  const StateParts parts = splitState(blob, description_.name);
  const StateHeader& header = parts.header;
  const std::vector<uint8_t>& scene_bytes = parts.scene;
  const std::vector<uint8_t>& controller_bytes = parts.controller_state;
  const std::vector<uint8_t>& task_bytes = parts.task;
  const std::string& controller = parts.controller;
  if (controller != controller_->getDescription().name)
    throw InvalidArgument("a state of controller '" + controller +
                                "', this environment drives '" +
                                controller_->getDescription().name + "'");
  // A reset from the blob's seed makes every choice the episode's reset
  // made (the task's randomization, its target, the controller's links);
  // the bytes then give what changed since.
  startEpisode(header.object_id, header.seed);
  try {
    scene_->restoreState(scene_->decodeState(scene_bytes.data(), scene_bytes.size()));
  } catch (const SceneError& e) {
    throw InvalidArgument(e.what());
  }
  controller_->restoreState(controller_bytes);
  task_->restoreState(task_bytes);
  elapsed_steps_ = header.step;
  observe();
  episode_started_ = true;
}

}  // namespace manibench
