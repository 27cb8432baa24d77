#include <manibench/environment.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace manibench {

Environment::Environment(const PluginRegistry& registry, const std::string& task_name,
                         EnvironmentOptions options)
    : registry_(registry), options_(std::move(options)) {
  if (options_.control_frequency &&
      !(std::isfinite(*options_.control_frequency) && *options_.control_frequency > 0))
    throw std::invalid_argument("control frequency override must be a positive number of Hz, got " +
                                std::to_string(*options_.control_frequency));
  if (options_.frame_skip && *options_.frame_skip == 0)
    throw std::invalid_argument("frame skip override must be at least 1");
  if (options_.max_episode_steps && *options_.max_episode_steps == 0)
    throw std::invalid_argument("episode length override must be at least 1 step");
  task_ = std::make_unique<TaskInstance>(registry_, task_name, options_.task_config);
  description_ = task_->getDescription();
  if (options_.control_frequency) description_.control_frequency = *options_.control_frequency;
  if (options_.frame_skip) description_.frame_skip = *options_.frame_skip;
  if (options_.max_episode_steps) description_.max_episode_steps = *options_.max_episode_steps;
  const TaskDescription& task = description_;
  const std::string controller =
      options_.controller.empty() ? task.default_controller : options_.controller;
  // Fail before any physics if the controller does not exist.
  registry_.getEntry(PluginKind::Controller, controller);
  // Build the first train object's scene now, so that the action layout
  // (which depends on the robot's joints) is known before the first reset.
  const std::vector<std::string> train = task_->listObjects("train");
  if (train.empty())
    throw PluginCallError("task '" + task.name + "' lists no train objects", MB_ERROR);
  buildScene(train.front());
}

Environment::~Environment() {
  // The controller and task may hold scene ids; drop them before the scene.
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
  layout.observation_mode = observation_mode;
  layout.observation_dim = getTaskDescription().observation_dim;
  layout.observation_segments = getTaskDescription().observation_segments;
  layout.action_dim = getControllerDescription().action_dim;
  layout.action_segments = getControllerDescription().action_segments;
  return layout;
}

std::vector<std::string> Environment::listObjects(const std::string& split) const {
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
  controller_.reset();
  bridge_.reset();
  scene_ = std::make_unique<Scene>(options_.physics);
  bridge_ = std::make_unique<SceneBridge>(*scene_);
  scene_built_ = false;
  initial_state_.reset();

  bridge_->setBuilding(true);
  task_->buildScene(*bridge_, object_id);
  bridge_->setBuilding(false);
  applySceneOptions(object_id);
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
  drives_.assign(actuated_joints_.size(), mb_drive_command{});

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

void Environment::reset(const std::string& object_id, uint64_t seed) {
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
  drives_.assign(actuated_joints_.size(), mb_drive_command{});
  scene_->setDriveCommands(robot_, actuated_joints_,
                           std::vector<DriveCommand>(actuated_joints_.size()));
  task_->observe(*bridge_, observation_);
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
  std::vector<DriveCommand> commands(drives_.size());
  try {
    for (uint32_t k = 0; k < task.frame_skip; ++k) {
      controller_->compute(*bridge_, clipped_action_, drives_);
      for (std::size_t j = 0; j < drives_.size(); ++j) {
        const mb_drive_command& d = drives_[j];
        commands[j] = {d.position_target, d.velocity_target, d.stiffness, d.damping, d.force};
      }
      scene_->setDriveCommands(robot_, actuated_joints_, commands);
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
      policy.act(env.getObservation(), env.getElapsedSteps(), action);
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
