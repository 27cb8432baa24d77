// OpenCabinetDoor-v0 / OpenCabinetDrawer-v0: scene, reset, observation,
// staged reward and success.
#include "open_cabinet.hpp"

#include <algorithm>
#include <cmath>


namespace open_cabinet {
namespace {

enum Mask : uint32_t { kHandleMask = 0, kTargetLinkMask = 1, kRobotMask = 2 };

std::string taskName(TargetKind kind) {
  return kind == TargetKind::kDoor ? "OpenCabinetDoor" : "OpenCabinetDrawer";
}

// Distance from `p` to the segment centre +- half * axis.
double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& centre,
                         const Eigen::Vector3d& axis, double half) {
  const double s = std::clamp((p - centre).dot(axis), -half, half);
  return (p - (centre + s * axis)).norm();
}

}  // namespace

OpenCabinetTask::OpenCabinetTask(const Config& config, TargetKind kind)
    : kind_(kind),
      static_speed_(config.get<double>("static_speed", 0.1)),
      static_angular_speed_(config.get<double>("static_angular_speed", 1.0)),
      hold_steps_(config.get<uint32_t>("hold_steps", 10)),
      cabinets_(taskName(kind), "cabinet", readPartNetFolders(config, taskName(kind)),
                {[kind](const std::string& split) { return listGeneratedCabinets(kind, split); }, generateCabinet,
                 [facts = ObjectFacts(config, "open_cabinet")](const std::string& folder, const std::string& id) {
                   return loadPartNetCabinet(folder, id, facts);
                 },
                 [kind](const CabinetModel& cabinet) -> std::string {
                   if (!cabinet.getTargets(TargetKind::kDoor).empty() || !cabinet.getTargets(TargetKind::kDrawer).empty())
                     return "";
                   if (!cabinet.refused.empty()) return "no door or drawer it can open: " + cabinet.refused.front().second;
                   return "no door or drawer with a handle part (a visual or semantics.txt label naming 'handle')";
                 },
                 nullptr, [kind](const CabinetModel& cabinet) { return cabinet.getRefused(kind); }}) {
  config.requireKnownKeys(
      {"partnet_dir", "partnet_test_categories", "partnet_scale", "object_facts", "robot_dir", "static_speed",
       "static_angular_speed", "hold_steps"},
      taskName(kind) + ": task");
  if (!(static_speed_ > 0) || !(static_angular_speed_ > 0) || hold_steps_ == 0)
    throw Error(taskName(kind) + ": static_speed, static_angular_speed and hold_steps must be positive",
                MB_INVALID_ARGUMENT);
  robot_ = std::make_unique<mobile_panda::AgentState>(mobile_panda::readRobotDir(config),
                                                      "mobile_panda_single", taskName(kind), 1, kRobotDof);
}

sdk::TaskSpec OpenCabinetTask::describe() const {
  const char* what = kind_ == TargetKind::kDoor ? "door" : "drawer";
  // The robot's own state (what the pointcloud and rgbd modes pass on),
  // then the privileged object state.
  sdk::TaskSpec spec = robot_->describeTask();
  const std::vector<Segment> object = {
      {"target_link_pose", 7, std::string("the target ") + what + ": position, quaternion wxyz, world"},
      {"target_joint", 4, "its joint: q, qdot, lower, upper (rad or m)"},
      {"target_joint_type", 1, "0 revolute (door), 1 prismatic (drawer)"},
      {"target_joint_axis", 3, "world; q grows turning about / sliding along it"},
      {"target_joint_origin", 3, "a point on the joint axis, world (m)"},
      {"handle_pose", 7, "grasp frame of the handle (x out of the front, z along the grip), world"},
      {"handle_half_length", 1, "half the grip length (m)"},
      {"cabinet_center", 3, "centre of the cabinet's bounding box, world (m)"},
      {"handle_size", 3, "the handle's extent in its grasp frame: depth out of the front, width across the grip, "
                         "length along it (m)"},
  };
  spec.observation.insert(spec.observation.end(), object.begin(), object.end());
  spec.success_conditions = {"open_enough", "static", "success"};
  spec.success_hold_steps = hold_steps_;
  spec.progress_signals = {"reached", "holding", "progress", "blocked", "opened"};
  spec.masks = {"handle", "target_link", "robot"};
  // ManiSkill v1 friction: cabinet 1, finger pads 2; the robot's head cameras.
  spec.default_config = "physics:\n  contact:\n    bodies:\n"
                        "      - {articulation: cabinet, static_friction: 1.0, dynamic_friction: 1.0}\n" +
                        robot_->getFingerFrictionYaml() + robot_->getFacts().camera_yaml;
  return spec;
}

std::vector<std::string> OpenCabinetTask::listObjects(const std::string& split) const {
  std::vector<std::string> ids;
  for (const std::string& c : cabinets_.list(split))
    for (const TargetLink* t : cabinets_.get(c)->getTargets(kind_)) ids.push_back(c + "_" + t->link);
  return ids;
}

// The cabinet's ("45633" of "45633_link_1"): its folder's.
std::string OpenCabinetTask::getObjectCategory(const std::string& object_id) const {
  return cabinets_.getCategory(splitObjectId(object_id).first);
}

void OpenCabinetTask::buildScene(SceneView& scene, const std::string& object_id) {
  const auto [cabinet_id, link] = splitObjectId(object_id);
  cabinet_ = cabinets_.get(cabinet_id);
  target_ = nullptr;
  for (const TargetLink* t : cabinet_->getTargets(kind_))
    if (t->link == link) target_ = t;
  if (target_ == nullptr)
    throw Error(taskName(kind_) + ": cabinet " + cabinet_id + " has no " +
                    (kind_ == TargetKind::kDoor ? "door" : "drawer") + " with a handle named " + link,
                MB_NOT_FOUND);
  scene.addGround(0.0);
  robot_id_ = robot_->addTo(scene);
  Pose placement;
  placement.position = cabinet_->placement;
  cabinet_id_ = scene.addUrdfString(cabinet_->urdf, cabinet_->base_dir, "cabinet", placement, /*fixed_base=*/true);
  target_link_ = scene.findLink(cabinet_id_, target_->link);
  target_joint_ = scene.findJoint(cabinet_id_, target_->joint);
  const mb_joint_info info = scene.getJointInfo(cabinet_id_, target_joint_);
  lower_ = info.lower;
  upper_ = info.upper;
  if (!std::isfinite(lower_)) lower_ = 0;  // continuous joints: a quarter turn
  if (!std::isfinite(upper_)) upper_ = lower_ + kPi / 2;
  if (!(upper_ > lower_))
    throw Error(taskName(kind_) + ": joint " + target_->joint + " of cabinet " + cabinet_id + " has no range");
  cabinet_joint_count_ = scene.getJointCount(cabinet_id_);
  // Closed is each joint's lower limit (ManiSkill v1), 0 where it has none.
  closed_q_ = Eigen::VectorXd::Zero(cabinet_joint_count_);
  for (uint32_t j = 0; j < cabinet_joint_count_; ++j) {
    const double lower = scene.getJointInfo(cabinet_id_, j).lower;
    if (std::isfinite(lower)) closed_q_[j] = lower;
  }
  tcp_ = robot_->getTcps().front();
  scene.addLinkToMask(kHandleMask, cabinet_id_, target_link_, "handle");
  scene.addLinkToMask(kTargetLinkMask, cabinet_id_, target_link_);
  scene.addArticulationToMask(kRobotMask, robot_id_);
}

void OpenCabinetTask::reset(SceneView& scene, uint64_t seed) {
  Random rng(seed ^ 0x6f70656e5f636162ULL);
  // B.2 / ManiSkill v1: 1.6-1.8 m from the cabinet centre, at 0.9-1.1 pi
  // around it (in front), facing it with +-0.05 pi of heading noise.
  const Eigen::Vector3d centre = (cabinet_->lower + cabinet_->upper) / 2;
  const double distance = rng.uniform(1.6, 1.8);
  const double around = rng.uniform(0.9 * kPi, 1.1 * kPi);
  robot_->placeFacing(scene, rng, centre.head<2>(), distance, around, kPi);
  // every door and drawer closed, joint friction and damping drawn anew
  scene.setJointPositions(cabinet_id_, closed_q_);
  scene.setJointVelocities(cabinet_id_, Eigen::VectorXd::Zero(cabinet_joint_count_));
  for (uint32_t j = 0; j < cabinet_joint_count_; ++j) {
    const double friction = rng.uniform(0.05, 0.15);
    const double damping = rng.uniform(5.0, 20.0);
    scene.setJointDynamics(cabinet_id_, j, damping, friction);
  }
}

Pose OpenCabinetTask::calcHandlePose(const SceneView& scene) const {
  const Pose link = scene.getLinkPose(target_link_);
  Pose handle;
  handle.position = link.position + link.orientation * target_->handle_position;
  handle.orientation = link.orientation * Eigen::Quaterniond(target_->handle_rotation);
  return handle;
}

Eigen::Vector3d OpenCabinetTask::calcGripperPoint(const SceneView& scene) const {
  return scene.getLinkPose(tcp_).position;
}

void OpenCabinetTask::observe(const SceneView& scene, Eigen::Map<Eigen::VectorXd> out) {
  using L = ObservationLayout;
  robot_->observe(scene, out);
  const Pose link = scene.getLinkPose(target_link_);
  putPose(out, L::kTargetLinkPose, link);
  out.segment<4>(L::kTargetJoint) << scene.getJointPositions(cabinet_id_)[target_joint_],
      scene.getJointVelocities(cabinet_id_)[target_joint_], lower_, upper_;
  out[L::kTargetJointType] = target_->kind == TargetKind::kDoor ? 0.0 : 1.0;
  out.segment<3>(L::kJointAxis) = link.orientation * target_->axis;
  out.segment<3>(L::kJointOrigin) = link.position;
  putPose(out, L::kHandlePose, calcHandlePose(scene));
  out[L::kHandleHalfLength] = target_->handle_half_length;
  out.segment<3>(L::kCabinetCenter) = (cabinet_->lower + cabinet_->upper) / 2;
  out.segment<3>(L::kHandleSize) = target_->handle_size;
}

OpenCabinetTask::Measured OpenCabinetTask::measure(const SceneView& scene) const {
  Measured m;
  m.q = scene.getJointPositions(cabinet_id_)[target_joint_];
  m.qdot = scene.getJointVelocities(cabinet_id_)[target_joint_];
  m.open_fraction = (m.q - lower_) / (upper_ - lower_);
  const Pose handle = calcHandlePose(scene);
  m.handle_distance = distanceToSegment(calcGripperPoint(scene), handle.position,
                                        handle.orientation * Eigen::Vector3d::UnitZ(), target_->handle_half_length);
  const Twist twist = scene.getLinkTwist(target_link_);
  m.linear_speed = twist.linear.norm();
  m.angular_speed = twist.angular.norm();
  return m;
}

double OpenCabinetTask::computeReward(const SceneView& scene, Eigen::Map<const Eigen::VectorXd>) {
  const Measured m = measure(scene);
  return calcStagedReward(m.handle_distance, m.open_fraction, m.linear_speed, m.angular_speed);
}

std::vector<sdk::Condition> OpenCabinetTask::evaluateSuccess(const SceneView& scene) {
  const Measured m = measure(scene);
  const bool open = m.open_fraction >= kOpenFraction;
  const bool still = m.linear_speed <= static_speed_ && m.angular_speed <= static_angular_speed_;
  // `success` once both have held for hold_steps steps (TaskSpec::success_hold_steps).
  return {{open, m.open_fraction}, {still, m.linear_speed}, {open && still, 0.0}};
}

std::vector<double> OpenCabinetTask::measureProgress(const SceneView& scene) const {
  const Measured m = measure(scene);
  // 1 N: a touch, well under the fingers' 25-75 N squeeze and any push
  // that moves a damped door.
  constexpr double kTouch = 1.0;
  return {m.handle_distance < kContactDistance ? 1.0 : 0.0,
          robot_->isHolding(scene, target_link_, 0, kTouch) ? 1.0 : 0.0, m.open_fraction / kOpenFraction,
          robot_->calcBodyContactForce(scene) > kTouch ? 1.0 : 0.0, m.open_fraction};
}

}  // namespace open_cabinet
