#include <manibench/environment.hpp>
#include <manibench/task_name.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

namespace manibench {

Environment::Environment(const PluginRegistry& registry, const std::string& environment_id,
                         EnvironmentOptions options)
    : registry_(registry), options_(std::move(options)), environment_id_(environment_id) {
  const TaskId id = resolveTaskId(registry_, environment_id);
  if (options_.control_frequency &&
      !(std::isfinite(*options_.control_frequency) && *options_.control_frequency > 0))
    throw std::invalid_argument("control frequency override must be a positive number of Hz, got " +
                                std::to_string(*options_.control_frequency));
  if (options_.frame_skip && *options_.frame_skip == 0)
    throw std::invalid_argument("frame skip override must be at least 1");
  if (options_.max_episode_steps && *options_.max_episode_steps == 0)
    throw std::invalid_argument("episode length override must be at least 1 step");
  const std::vector<std::string>& modes = getObservationModes();
  if (std::find(modes.begin(), modes.end(), options_.observation_mode) == modes.end())
    throw std::invalid_argument("unknown observation mode '" + options_.observation_mode +
                                "' (use state, pointcloud or rgbd)");
  const bool visual = options_.observation_mode != "state";
  if (visual && options_.cameras.empty())
    throw std::invalid_argument("observation mode '" + options_.observation_mode +
                                "' needs at least one camera, and the configuration's `cameras` "
                                "list is empty");
  std::set<std::string> camera_names;
  for (const CameraMount& camera : options_.cameras) {
    const std::string where = camera.source.empty() ? "camera '" + camera.spec.name + "'" : camera.source;
    if (!camera_names.insert(camera.spec.name).second)
      throw std::invalid_argument(where + ": duplicate camera name '" + camera.spec.name + "'");
    if (!camera.link.empty() && camera.articulation.empty())
      throw std::invalid_argument(where + ": camera '" + camera.spec.name + "' names link '" +
                                  camera.link + "' but no articulation");
    if (camera.spec.width < 1 || camera.spec.height < 1)
      throw std::invalid_argument(where + ": camera '" + camera.spec.name + "' has an empty image");
  }
  if (options_.observation_mode == "rgbd")
    for (const CameraMount& camera : options_.cameras) {
      const CameraSpec& first = options_.cameras.front().spec;
      if (camera.spec.width != first.width || camera.spec.height != first.height)
        throw std::invalid_argument(
            "observation mode 'rgbd' stacks the cameras' images, so they must be of one size: "
            "camera '" + first.name + "' is " + std::to_string(first.width) + "x" +
            std::to_string(first.height) + ", camera '" + camera.spec.name + "' is " +
            std::to_string(camera.spec.width) + "x" + std::to_string(camera.spec.height));
    }
  if (options_.pointcloud.masked_total > options_.pointcloud.total)
    throw std::invalid_argument("point cloud sampling: masked_total exceeds total");
  visual_.mode = options_.observation_mode;
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
  if (train.empty())
    throw PluginCallError("task '" + task.name + "' lists no train objects", MB_ERROR);
  buildScene(train.front());
}

Environment::~Environment() {
  // The controller and task may hold scene ids, the renderer reads the
  // scene: drop them before it.
  renderer_.reset();
  controller_.reset();
  bridge_.reset();
  scene_.reset();
}

const TaskDescription& Environment::getTaskDescription() const { return description_; }

const ControllerDescription& Environment::getControllerDescription() const {
  return controller_->getDescription();
}

PolicyLayout Environment::calcPolicyLayout(const std::string& observation_mode) const {
  PolicyLayout layout;
  layout.task_name = getTaskDescription().name;
  layout.observation_mode = observation_mode.empty() ? options_.observation_mode : observation_mode;
  layout.observation_dim = getTaskDescription().observation_dim;
  layout.observation_segments = getTaskDescription().observation_segments;
  if (layout.observation_mode != "state") {
    // Visual modes carry only the robot's own state (as ManiSkill's).
    layout.observation_dim = getTaskDescription().agent_state_dim;
    std::vector<SegmentDescription> agent;
    for (const SegmentDescription& s : layout.observation_segments)
      if (s.offset + s.size <= layout.observation_dim) agent.push_back(s);
    layout.observation_segments = std::move(agent);
  }
  layout.action_dim = getControllerDescription().action_dim;
  layout.action_segments = getControllerDescription().action_segments;
  return layout;
}

std::vector<std::string> Environment::listObjects(const std::string& split) const {
  if (!fixed_objects_.empty()) return fixed_objects_;
  return task_->listObjects(split);
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
  renderer_.reset();
  controller_.reset();
  bridge_.reset();
  scene_ = std::make_unique<Scene>(options_.physics);
  bridge_ = std::make_unique<SceneBridge>(*scene_);
  bridge_->setMaskNames(task.masks);
  scene_built_ = false;
  initial_state_.reset();

  bridge_->setBuilding(true);
  try {
    task_->buildScene(*bridge_, object_id);
  } catch (...) {
    bridge_->setBuilding(false);
    throw;
  }
  bridge_->setBuilding(false);
  visual_masks_ = bridge_->calcVisualMasks();
  applySceneOptions(object_id);
  resolveCameras();
  scene_->finalize();

  robot_ = scene_->findArticulation(task.robot_articulation);
  if (robot_ < 0)
    throw PluginCallError("task '" + task.name + "' names robot articulation '" +
                              task.robot_articulation + "', which its scene does not contain",
                          MB_ERROR);
  actuated_joints_.clear();
  std::vector<mb_joint_info> joints;
  const auto& robot_joints = scene_->getJoints(robot_);
  for (const std::string& name : task.actuated_joints) {
    const int index = scene_->findJoint(robot_, name);
    if (index < 0)
      throw PluginCallError("task '" + task.name + "' actuates joint '" + name +
                                "', which articulation '" + task.robot_articulation +
                                "' does not have",
                            MB_ERROR);
    actuated_joints_.push_back(index);
    const JointDescription& j = robot_joints[index];
    joints.push_back({j.name.c_str(), static_cast<uint32_t>(j.type), static_cast<uint32_t>(index),
                      j.lower, j.upper, j.velocity_limit, j.effort_limit});
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

namespace {
// Names the articulations a scene has, for errors about one it lacks.
std::string listArticulations(const Scene& scene) {
  std::string names;
  for (int i = 0; i < scene.getArticulationCount(); ++i)
    names += (names.empty() ? "'" : ", '") + scene.getArticulationName(i) + "'";
  return names.empty() ? "none" : names;
}
}  // namespace

void Environment::applySceneOptions(const std::string& object_id) {
  const std::string where = "task '" + description_.name + "', object '" + object_id + "'";
  auto findArticulation = [&](const std::string& name, const std::string& source) {
    const int articulation = scene_->findArticulation(name);
    if (articulation < 0)
      throw SceneError(source + ": the scene of " + where + " has no articulation '" + name +
                       "' (it has " + listArticulations(*scene_) + ")");
    return articulation;
  };
  if (options_.ground_material) scene_->setGroundMaterial(*options_.ground_material);
  for (const BodyContactMaterial& body : options_.contact_materials) {
    const int articulation = findArticulation(body.articulation, body.source);
    if (!body.link.empty() && scene_->findLink(articulation, body.link) < 0)
      throw SceneError(body.source + ": articulation '" + body.articulation + "' of " + where +
                       " has no link '" + body.link + "'");
    scene_->setContactMaterial(articulation, body.link, body.material);
  }
  for (const SelfCollisionSetting& setting : options_.self_collision)
    scene_->setSelfCollision(findArticulation(setting.articulation, setting.source), setting.enabled);
}

void Environment::resolveCameras() {
  camera_links_.clear();
  camera_articulations_.clear();
  for (const CameraMount& camera : options_.cameras) {
    const std::string where = (camera.source.empty() ? "" : camera.source + ": ") + "camera '" +
                              camera.spec.name + "'";
    if (camera.articulation.empty()) {
      camera_articulations_.push_back(-1);
      camera_links_.push_back(-2);
      continue;
    }
    const int articulation = scene_->findArticulation(camera.articulation);
    if (articulation < 0)
      throw SceneError(where + ": the scene of task '" + description_.name + "' has no articulation '" +
                       camera.articulation + "' (it has " + listArticulations(*scene_) + ")");
    int link = -1;
    if (!camera.link.empty()) {
      link = scene_->findLink(articulation, camera.link);
      if (link < 0)
        throw SceneError(where + ": articulation '" + camera.articulation + "' has no link '" +
                         camera.link + "'");
    }
    camera_articulations_.push_back(articulation);
    camera_links_.push_back(link);
  }
}

Pose Environment::calcCameraPose(std::size_t index) const {
  const CameraMount& camera = options_.cameras.at(index);
  const int link = camera_links_.at(index);
  if (link == -2) return camera.pose;
  const Pose mount = link >= 0 ? scene_->getLinkPose(link)
                               : scene_->getRootPose(camera_articulations_.at(index));
  return composePoses(mount, camera.pose);
}

SceneRenderer& Environment::updRenderer() {
  if (!scene_built_) throw std::logic_error("Environment::updRenderer() before the scene is built");
  if (!renderer_)
    renderer_ = std::make_unique<SceneRenderer>(*scene_, options_.lighting, options_.render);
  return *renderer_;
}

const std::vector<CameraImages>& Environment::renderCameras(
    const std::vector<std::pair<CameraSpec, Pose>>& extra) {
  SceneRenderer& renderer = updRenderer();
  const std::size_t n = options_.cameras.size();
  images_.resize(n + extra.size());
  for (std::size_t i = 0; i < n; ++i)
    renderer.render(options_.cameras[i].spec, calcCameraPose(i), images_[i]);
  for (std::size_t i = 0; i < extra.size(); ++i)
    renderer.render(extra[i].first, extra[i].second, images_[n + i]);
  return images_;
}

std::uint64_t Environment::calcPixelMasks(const CameraImages& image, std::size_t pixel) const {
  const int v = image.visual[pixel];
  return v >= 0 && std::size_t(v) < visual_masks_.size() ? visual_masks_[std::size_t(v)] : 0;
}

void Environment::fusePointCloud(const std::vector<CameraImages>& images, std::size_t count,
                                 PointCloud& out) const {
  const uint32_t k = static_cast<uint32_t>(description_.masks.size());
  out.clear();
  out.mask_count = k;
  std::vector<int> pixels;
  for (std::size_t i = 0; i < count && i < images.size(); ++i) {
    const CameraImages& image = images[i];
    const Eigen::Matrix3Xf points = calcCameraPoints(image, /*world=*/true, &pixels);
    for (Eigen::Index j = 0; j < points.cols(); ++j) {
      const std::size_t p = std::size_t(pixels[std::size_t(j)]);
      out.xyz.insert(out.xyz.end(), {points(0, j), points(1, j), points(2, j)});
      for (std::size_t c = 0; c < 3; ++c) out.rgb.push_back(image.rgba[4 * p + c] / 255.0f);
      const std::uint64_t bits = calcPixelMasks(image, p);
      for (uint32_t m = 0; m < k; ++m) out.masks.push_back((bits >> m) & 1u);
    }
  }
}

void Environment::observeVisual() {
  const std::string& mode = options_.observation_mode;
  if (mode == "state") return;
  // A renderer failure (EGL, a camera it refuses) ends the episode like a
  // diverged simulation, naming task, object, seed and step.
  const std::vector<CameraImages>* rendered = nullptr;
  try {
    rendered = &renderCameras();
  } catch (const RenderError& e) {
    throw EpisodeFailure(describeEpisode() + ": rendering the '" + mode +
                         "' observation failed: " + e.what());
  }
  const std::vector<CameraImages>& images = *rendered;
  const uint32_t k = static_cast<uint32_t>(description_.masks.size());
  visual_.mask_count = k;
  if (mode == "pointcloud") {
    fusePointCloud(images, images.size(), raw_points_);
    // Each step samples anew, yet (seed, step) fixes the sample.
    const uint64_t seed = seed_ * 0x9E3779B97F4A7C15ull + elapsed_steps_;
    visual_.points = samplePointCloud(raw_points_, options_.pointcloud, seed);
    return;
  }
  // rgbd: stack the cameras along the channel axis.
  const std::size_t cameras = images.size();
  const std::size_t h = std::size_t(images.front().height), w = std::size_t(images.front().width);
  visual_.camera_count = static_cast<uint32_t>(cameras);
  visual_.height = static_cast<uint32_t>(h);
  visual_.width = static_cast<uint32_t>(w);
  visual_.rgb.resize(h * w * 3 * cameras);
  visual_.depth.resize(h * w * cameras);
  visual_.masks.resize(h * w * k * cameras);
  for (std::size_t c = 0; c < cameras; ++c) {
    const CameraImages& image = images[c];
    for (std::size_t p = 0; p < h * w; ++p) {
      for (std::size_t ch = 0; ch < 3; ++ch)
        visual_.rgb[p * 3 * cameras + 3 * c + ch] = image.rgba[4 * p + ch] / 255.0f;
      visual_.depth[p * cameras + c] = image.depth[p];
      const std::uint64_t bits = calcPixelMasks(image, p);
      for (uint32_t m = 0; m < k; ++m)
        visual_.masks[p * k * cameras + k * c + m] = (bits >> m) & 1u;
    }
  }
}

void Environment::reset(const std::string& object_id, uint64_t seed) {
  if (!fixed_objects_.empty() &&
      std::find(fixed_objects_.begin(), fixed_objects_.end(), object_id) == fixed_objects_.end()) {
    std::string objects;
    for (const std::string& o : fixed_objects_) objects += (objects.empty() ? "" : ", ") + o;
    throw std::invalid_argument("environment " + environment_id_ + " is fixed to object(s) " +
                                objects + "; it cannot reset on object '" + object_id +
                                "' (use " + getTaskDescription().name + " for any object)");
  }
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
  task_->observe(*bridge_, observation_);
  if (options_.observation_mode != "state")
    observation_.conservativeResize(description_.agent_state_dim);
  observeVisual();
}

StepResult Environment::step(const Eigen::VectorXd& action) {
  if (!scene_built_) throw std::logic_error("Environment::step() before reset()");
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

  StepResult result;
  result.reward = task_->computeReward(*bridge_, clipped_action_);
  task_->evaluateSuccess(*bridge_, result.flags, result.values);
  result.success = result.flags.back() != 0;
  result.done = elapsed_steps_ >= task.max_episode_steps ||
                (options_.stop_on_success && result.success);
  task_->observe(*bridge_, observation_);
  if (options_.observation_mode != "state")
    observation_.conservativeResize(description_.agent_state_dim);
  observeVisual();
  if (!std::isfinite(result.reward))
    throw EpisodeFailure(describeEpisode() + ": task reward is not finite");
  return result;
}

EpisodeResult runEpisode(Environment& env, PolicyInstance& policy, const std::string& object_id,
                         uint64_t seed) {
  env.reset(object_id, seed);
  policy.reset(seed);
  EpisodeResult result;
  result.object_id = object_id;
  result.seed = seed;
  result.condition_names = env.getTaskDescription().success_conditions;
  Eigen::VectorXd action;
  for (;;) {
    try {
      policy.act(env.getObservation(), env.getElapsedSteps(), action,
                 env.getObservationMode() == "state" ? nullptr : &env.getVisualObservation());
    } catch (const PluginCallError& e) {
      throw PluginCallError("task '" + env.getTaskDescription().name + "', object '" + object_id +
                                "', seed " + std::to_string(seed) + ", step " +
                                std::to_string(env.getElapsedSteps()) + ": " + e.what(),
                            e.status());
    }
    const StepResult step = env.step(action);
    result.total_reward += step.reward;
    result.final_flags = step.flags;
    result.final_values = step.values;
    result.success = step.success;
    if (step.done) break;
  }
  result.steps = env.getElapsedSteps();
  return result;
}

}  // namespace manibench
