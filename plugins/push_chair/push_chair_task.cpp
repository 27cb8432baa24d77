// PushChair-v0: scene, reset, observation, staged reward and success.
#include "push_chair.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>


namespace push_chair {
namespace {

constexpr const char* kTaskName = "PushChair";
enum Mask : uint32_t { kRobotMask = 0 };

// The target: a flat red disc on the ground, visual only (no collision),
// of the success radius; its top is 4 mm up so that the point cloud's
// ground removal (z <= 1 mm, supplement D.1) keeps it.
std::string makeTargetUrdf() {
  std::ostringstream x;
  x << "<?xml version=\"1.0\"?>\n<robot name=\"target\">\n  <link name=\"marker\">\n"
    << "    <visual name=\"target_disc\"><origin xyz=\"0 0 0.002\"/><geometry><cylinder radius=\"" << kTargetRadius
    << "\" length=\"0.004\"/></geometry><material name=\"target_red\"><color rgba=\"0.9 0.1 0.1 1\"/>"
    << "</material></visual>\n  </link>\n</robot>\n";
  return x.str();
}

double calcTilt(const Eigen::Quaterniond& q) {
  const double up = std::clamp((q * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0);
  return std::acos(up);
}

}  // namespace

// ---- the task ---------------------------------------------------------------------

PushChairTask::PushChairTask(const Config& config)
    : static_speed_(config.get<double>("static_speed", 0.1)),
      static_angular_speed_(config.get<double>("static_angular_speed", 0.2)),
      hold_steps_(config.get<uint32_t>("hold_steps", 10)),
      chairs_(kTaskName, "chair", readPartNetFolders(config, kTaskName),
              {listGeneratedChairs, [](const std::string& id) { return generateChair(id); },
               [facts = ObjectFacts(config, "push_chair")](const std::string& folder, const std::string& id) {
                 return loadPartNetChair(folder, id, facts.calcScale(id));
               },
               nullptr, nullptr, nullptr}) {
  config.requireKnownKeys(
      {"partnet_dir", "partnet_test_categories", "partnet_scale", "object_facts", "robot_dir", "static_speed",
       "static_angular_speed", "hold_steps"},
      "PushChair: task");
  if (!(static_speed_ > 0) || !(static_angular_speed_ > 0) || hold_steps_ == 0)
    throw Error("PushChair: static_speed, static_angular_speed and hold_steps must be positive", MB_INVALID_ARGUMENT);
  robot_ = std::make_unique<mobile_panda::AgentState>(mobile_panda::readRobotDir(config),
                                                      "mobile_panda_dual", kTaskName, 2, kRobotDof);
}

sdk::TaskSpec PushChairTask::describe() const {
  // The robot's own state (what the pointcloud and rgbd modes pass on),
  // then the privileged chair and target.
  sdk::TaskSpec spec = robot_->describeTask();
  const std::vector<Segment> object = {
      {"chair_pose", 7, "the chair's root link (star base, frame on the floor under the column): position, quaternion wxyz"},
      {"chair_velocity", 3, "root link origin, world (m/s)"},
      {"chair_angular_velocity", 3, "root link, world (rad/s)"},
      {"chair_joint_positions", kMaxChairJoints, "chair q in the scene's joint order, zero past its joints"},
      {"chair_joint_velocities", kMaxChairJoints, "chair qdot, zero past its joints"},
      {"seat_top", 3, "centre of the seat's top surface, world (m)"},
      {"target", 3, "the target point on the ground, world (m)"},
  };
  spec.observation.insert(spec.observation.end(), object.begin(), object.end());
  spec.success_conditions = {"close_to_target", "static", "upright", "success"};
  spec.progress_signals = {"reached", "progress", "fallen"};
  spec.success_hold_steps = hold_steps_;
  spec.masks = {"robot"};
  // ManiSkill v1: chair density 200 (links without <inertial>: PartNet
  // chairs), friction ground 0.5 (its default), chair 0.1, wheels 1.0,
  // finger pads 2.
  std::ostringstream config;
  config << "physics:\n  default_density: 200\n  contact:\n"
         << "    ground: {static_friction: 0.5, dynamic_friction: 0.5}\n    bodies:\n"
         << "      - {articulation: chair, static_friction: 0.1, dynamic_friction: 0.1}\n";
  // Every wheel, however many the chair has (procedural chairs: one per
  // leg; PartNet's: wheel_0.. from the loader).
  config << "      - {articulation: chair, link: \"wheel_*\", static_friction: 1.0, dynamic_friction: 1.0}\n";
  spec.default_config = config.str() + robot_->getFingerFrictionYaml() + robot_->getFacts().camera_yaml;
  return spec;
}

std::vector<std::string> PushChairTask::listObjects(const std::string& split) const { return chairs_.list(split); }

void PushChairTask::buildScene(SceneView& scene, const std::string& object_id) {
  chair_ = chairs_.get(object_id);
  scene.addGround(0.0);
  robot_id_ = robot_->addTo(scene);
  Pose placement;
  placement.position = Eigen::Vector3d(0, 0, chair_->root_height);
  chair_id_ = scene.addUrdfString(chair_->urdf, chair_->base_dir, "chair", placement, /*fixed_base=*/false);
  scene.addUrdfString(makeTargetUrdf(), "", "target", Pose(), /*fixed_base=*/true);
  if (scene.getJointCount(chair_id_) > kMaxChairJoints)
    throw Error("PushChair: chair " + object_id + " has " + std::to_string(scene.getJointCount(chair_id_)) +
                    " movable joints; the observation holds " + std::to_string(kMaxChairJoints),
                MB_INVALID_ARGUMENT);
  // Each joint's role (how reset randomizes it), by name in the scene's order.
  chair_joint_count_ = scene.getJointCount(chair_id_);
  joint_roles_.assign(chair_joint_count_, ChairJoint{});
  for (uint32_t j = 0; j < chair_joint_count_; ++j) {
    const std::string name = scene.getJointInfo(chair_id_, j).name;
    for (const ChairJoint& c : chair_->joints)
      if (c.name == name) joint_roles_[j] = c;
  }
  root_link_ = scene.findLink(chair_id_, chair_->root_link);
  surface_links_.clear();
  for (const LinkPoints& s : chair_->surface) surface_links_.push_back(scene.findLink(chair_id_, s.link));
  seat_link_ = scene.findLink(chair_id_, chair_->seat_link);
  scene.addArticulationToMask(kRobotMask, robot_id_);
}

void PushChairTask::reset(SceneView& scene, uint64_t seed) {
  Random rng(seed ^ 0x707573685f636872ULL);
  // ManiSkill v1: the chair 0.8-1.2 m from the target at a random bearing,
  // with a random yaw; the robot 0.8-1.2 m from the chair at a random
  // bearing, facing it with +-0.05 pi of heading noise.
  const double chair_distance = rng.uniform(0.8, 1.2);
  const double chair_bearing = rng.uniform(-kPi, kPi);
  const double chair_yaw = rng.uniform(-kPi, kPi);
  const Eigen::Vector2d chair_xy = target_.head<2>() + chair_distance * Eigen::Vector2d(std::cos(chair_bearing), std::sin(chair_bearing));
  start_distance_ = chair_distance;
  const double robot_distance = rng.uniform(0.8, 1.2);
  const double robot_bearing = rng.uniform(-kPi, kPi);
  robot_->placeFacing(scene, rng, chair_xy, robot_distance, robot_bearing, kPi);

  Pose pose;
  pose.position = Eigen::Vector3d(chair_xy.x(), chair_xy.y(), chair_->root_height);
  pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(chair_yaw, Eigen::Vector3d::UnitZ()));
  scene.setRootPose(chair_id_, pose);
  // Casters point anywhere (as a chair left standing); every other joint
  // at rest (backrest and armrests on their lower stops). Friction and
  // damping per joint (maniskill-v1-facts.md): the seat's swivel
  // U(0.05, 0.15) N m and U(5, 15) N m s; the other joints U(0, 0.1) N m
  // and U(0, 0.5), the casters' damping as N s/m where the floor pushes
  // (times lever^2: the wheel's radius, the swivel's trail). Taken as N m s
  // on 3 cm levers it would brake a wheel rolling at 0.3 m/s with 5-80 N,
  // more than its grip: the casters would skid and the chair tip over when
  // pushed at the seat (docs/tasks/push_chair.md).
  Eigen::VectorXd chair_q = Eigen::VectorXd::Zero(chair_joint_count_);
  for (uint32_t j = 0; j < chair_joint_count_; ++j) {
    const ChairJoint& joint = joint_roles_[j];
    if (joint.role == JointRole::kCasterSwivel) chair_q[j] = rng.uniform(-kPi, kPi);
    const bool seat = joint.role == JointRole::kSeat;
    const bool caster = joint.role == JointRole::kCasterSwivel || joint.role == JointRole::kWheel;
    const double friction = seat ? rng.uniform(0.05, 0.15) : rng.uniform(0.0, 0.1);
    double damping = seat ? rng.uniform(5.0, 15.0) : rng.uniform(0.0, 0.5);
    if (caster) damping *= joint.lever * joint.lever;
    scene.setJointDynamics(chair_id_, j, damping, friction);
  }
  scene.setJointPositions(chair_id_, chair_q);
  scene.setJointVelocities(chair_id_, Eigen::VectorXd::Zero(chair_joint_count_));
}

// Mean over the four finger pads of the distance to the nearest point of
// the chair's surface (ManiSkill: the end effectors to the chair's point
// cloud).
double PushChairTask::calcPadDistance(const SceneView& scene) const {
  const std::vector<Eigen::Vector3d> pads = robot_->calcPadPositions(scene);
  std::array<double, 4> best;
  best.fill(std::numeric_limits<double>::infinity());
  for (std::size_t l = 0; l < surface_links_.size(); ++l) {
    const Pose link = scene.getLinkPose(surface_links_[l]);
    const Eigen::Quaterniond inverse = link.orientation.conjugate();
    for (std::size_t k = 0; k < 4; ++k) {
      const Eigen::Vector3d local = inverse * (pads[k] - link.position);
      for (const Eigen::Vector3d& p : chair_->surface[l].points) best[k] = std::min(best[k], (p - local).squaredNorm());
    }
  }
  double sum = 0;
  for (const double b : best) sum += std::sqrt(b);
  return sum / 4;
}

void PushChairTask::observe(const SceneView& scene, Eigen::Map<Eigen::VectorXd> out) {
  using L = ObservationLayout;
  robot_->observe(scene, out);
  putPose(out, L::kChairPose, scene.getLinkPose(root_link_));
  const Twist twist = scene.getLinkTwist(root_link_);
  out.segment<3>(L::kChairVelocity) = twist.linear;
  out.segment<3>(L::kChairAngularVelocity) = twist.angular;
  out.segment<2 * kMaxChairJoints>(L::kChairJointPositions).setZero();
  out.segment(L::kChairJointPositions, chair_joint_count_) = scene.getJointPositions(chair_id_);
  out.segment(L::kChairJointVelocities, chair_joint_count_) = scene.getJointVelocities(chair_id_);
  const Pose seat = scene.getLinkPose(seat_link_);
  out.segment<3>(L::kSeatTop) = seat.position + seat.orientation * chair_->seat_top;
  out.segment<3>(L::kTarget) = target_;
}

RewardInput PushChairTask::measure(const SceneView& scene) const {
  RewardInput m;
  const Pose root = scene.getLinkPose(root_link_);
  const Twist twist = scene.getLinkTwist(root_link_);
  const Eigen::Vector2d to_target = target_.head<2>() - root.position.head<2>();
  m.target_distance = to_target.norm();
  m.speed = twist.linear.norm();
  m.angular_speed = twist.angular.norm();
  m.speed_to_target = m.target_distance > 1e-9 ? twist.linear.head<2>().dot(to_target / m.target_distance) : 0.0;
  m.tilt = calcTilt(root.orientation);
  m.is_static = m.speed <= static_speed_ && m.angular_speed <= static_angular_speed_;
  return m;
}

double PushChairTask::computeReward(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) {
  RewardInput m = measure(scene);
  m.ee_distance = calcPadDistance(scene);
  m.action_norm = action.norm();
  return calcStagedReward(m);
}

std::vector<sdk::Condition> PushChairTask::evaluateSuccess(const SceneView& scene) {
  const RewardInput m = measure(scene);
  const bool close = m.target_distance <= kTargetRadius;
  const bool upright = m.tilt < kUprightTilt;
  // `success` once all three have held for hold_steps steps (TaskSpec::success_hold_steps).
  return {{close, m.target_distance}, {m.is_static, m.speed}, {upright, m.tilt}, {close && m.is_static && upright, 0.0}};
}

std::vector<double> PushChairTask::measureProgress(const SceneView& scene) const {
  const RewardInput m = measure(scene);
  // The reward's second stage starts with the pads within 10 cm.
  constexpr double kReach = 0.1;
  const double way = std::max(start_distance_ - kTargetRadius, 1e-6);
  return {calcPadDistance(scene) < kReach ? 1.0 : 0.0, (start_distance_ - m.target_distance) / way,
          m.tilt >= kUprightTilt ? 1.0 : 0.0};
}

}  // namespace push_chair
