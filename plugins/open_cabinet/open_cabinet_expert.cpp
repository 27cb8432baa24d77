// Scripted expert for OpenCabinetDoor-v0 / OpenCabinetDrawer-v0 over the
// mobile_panda_ee controller. Privileged: it reads the handle's grasp frame
// and the target joint from the state observation.
//
// The whole robot servos to one goal for the TCP: the base keeps the TCP
// goal at the offset from the base it had at the start (the canonical arm
// pose, comfortable for the arm) and faces the handle, the lift keeps the
// goal's height within the arm's reach, the arm closes the rest. Phases:
// pre-grasp 12 cm in front of the grip, grasp, close, pull (drawers along
// their axis, doors along the handle's arc: the goal leads the handle along
// its direction of motion, the grasp frame and the base turn with the door),
// hold. A handle that slips out while pulling is let go and grasped again.
#include "open_cabinet.hpp"

#include <manibench/kit/policy_math.hpp>

#include <algorithm>
#include <cmath>

namespace open_cabinet {

using manibench::kit::clipNorm;
using manibench::kit::MobilePandaSpeeds;
using manibench::kit::setBaseAction;
using manibench::kit::setEeAction;
using manibench::kit::getQuaternion;
using manibench::kit::getVector3;
using manibench::sdk::Error;
using manibench::sdk::Observation;
using manibench::sdk::PolicyContext;

namespace {

constexpr double kBaseSpeed = MobilePandaSpeeds::kBase;  // per unit action
constexpr double kEeSpeed = MobilePandaSpeeds::kEeLinear, kEeAngularSpeed = MobilePandaSpeeds::kEeAngular;
constexpr double kDoorLead = 0.02;  // m: how far the goal leads a door's handle


}  // namespace

OpenCabinetExpert::OpenCabinetExpert(const PolicyContext& context) : action_dim_(context.action.dim) {
  if (context.task_name != "OpenCabinetDoor-v0" && context.task_name != "OpenCabinetDrawer-v0")
    throw Error("open_cabinet_expert drives OpenCabinetDoor-v0 and OpenCabinetDrawer-v0, not '" + context.task_name + "'",
                MB_INVALID_ARGUMENT);
  if (context.observation_mode != "state" || context.observation.dim != ObservationLayout::kDim)
    throw Error("open_cabinet_expert needs the state observation (" + std::to_string(ObservationLayout::kDim) +
                    " values), got mode '" + context.observation_mode + "' with " +
                    std::to_string(context.observation.dim),
                MB_INVALID_ARGUMENT);
  const std::vector<std::pair<const char*, uint32_t>> wanted = {
      {"base_forward", 1}, {"base_left", 1}, {"base_yaw", 1}, {"lift", 1},
      {"right_ee_linear", 3}, {"right_ee_angular", 3}, {"right_gripper", 1}};
  for (const auto& [name, size] : wanted) {
    const manibench::sdk::SegmentInfo* s = context.action.find(name);
    if (s == nullptr || s->size != size)
      throw Error(std::string("open_cabinet_expert needs the mobile_panda_ee controller (action segment '") + name +
                      "' of size " + std::to_string(size) +
                      " is missing); run it with --controller mobile_panda_ee",
                  MB_INVALID_ARGUMENT);
  }
  base_ = context.action.get("base_forward").offset;
  if (context.action.get("base_left").offset != base_ + 1 || context.action.get("base_yaw").offset != base_ + 2 ||
      context.action.get("lift").offset != base_ + 3)
    throw Error("open_cabinet_expert: base_forward, base_left, base_yaw, lift must be consecutive", MB_INVALID_ARGUMENT);
  ee_linear_ = context.action.get("right_ee_linear").offset;
  ee_angular_ = context.action.get("right_ee_angular").offset;
  gripper_ = context.action.get("right_gripper").offset;
}

void OpenCabinetExpert::reset(uint64_t) {
  phase_ = Phase::kApproach;
  phase_steps_ = 0;
  nominal_ready_ = false;
}

Eigen::VectorXd OpenCabinetExpert::act(const Observation& observation) {
  using L = ObservationLayout;
  const Eigen::VectorXd s = observation.state;
  const Eigen::Vector2d base(s[L::kBasePosition], s[L::kBasePosition + 1]);
  const double yaw = s[L::kBaseYaw];
  const double lift = s[L::kJointPositions + 3];
  const Eigen::Matrix3d base_rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d tcp = getVector3(s, L::kTcpPose);
  const Eigen::Quaterniond tcp_q = getQuaternion(s, L::kTcpPose + 3);
  const Eigen::Vector3d handle = getVector3(s, L::kHandlePose);
  const Eigen::Matrix3d hr = getQuaternion(s, L::kHandlePose + 3).toRotationMatrix();
  const Eigen::Vector3d hx = hr.col(0), hy = hr.col(1), hz = hr.col(2);
  const bool door = s[L::kTargetJointType] < 0.5;
  const double q = s[L::kTargetJoint], lower = s[L::kTargetJoint + 2], upper = s[L::kTargetJoint + 3];
  const double open_fraction = (q - lower) / (upper - lower);
  const Eigen::Vector3d axis = getVector3(s, L::kJointAxis), origin = getVector3(s, L::kJointOrigin);
  const double fingers = s[L::kJointPositions + 11] + s[L::kJointPositions + 12];  // opening, m

  if (!nominal_ready_) {  // the canonical arm pose's TCP, relative to the base
    const Eigen::Vector3d offset = base_rotation.transpose() * (tcp - Eigen::Vector3d(base.x(), base.y(), 0));
    nominal_offset_ = Eigen::Vector2d(offset.x(), offset.y());
    nominal_height_ = tcp.z() - lift;
    nominal_ready_ = true;
  }

  // The phase's TCP goal and gripper.
  ++phase_steps_;
  auto next = [this](Phase p) {
    phase_ = p;
    phase_steps_ = 0;
  };
  Eigen::Vector3d goal = handle;
  double gripper = 1.0;
  double lead_speed = 0.0;  // m/s along the motion while pulling
  Eigen::Vector3d motion = door ? axis.cross(handle - origin) : axis;
  motion = motion.norm() > 1e-9 ? Eigen::Vector3d(motion.normalized()) : Eigen::Vector3d(hx);
  const Eigen::Matrix3d grasp_rotation = (Eigen::Matrix3d() << hz, hy, -hx).finished();
  const Eigen::AngleAxisd orientation_error(grasp_rotation * tcp_q.toRotationMatrix().transpose());
  const double angle_error = std::abs(orientation_error.angle());
  switch (phase_) {
    case Phase::kApproach:
    case Phase::kPreGrasp: {
      goal = handle + 0.12 * hx;
      if (phase_ == Phase::kPreGrasp && phase_steps_ < 5) {  // after a slip: open in place first
        goal = tcp;
        break;
      }
      const double error = (goal - tcp).norm();
      if ((error < 0.025 && angle_error < 0.1) || (phase_steps_ > 90 && error < 0.04)) next(Phase::kGrasp);
      break;
    }
    case Phase::kGrasp: {
      goal = handle + 0.005 * hx;
      if ((goal - tcp).norm() < 0.01 || phase_steps_ > 20) next(Phase::kClose);
      break;
    }
    case Phase::kClose:
      gripper = -1.0;
      if (phase_steps_ > 5) next(Phase::kPull);
      break;
    case Phase::kPull: {
      gripper = -1.0;
      // ramp up: breaking the joint's friction loose at full speed tears
      // the handle out of the fingers
      lead_speed = std::min(door ? door_speed_ : 0.18, 0.05 + 0.02 * phase_steps_);
      // Drawers: the goal leads the handle. Doors: a short lead with a stiff
      // gain, so that the pull never exceeds what the fingers hold by
      // friction (a heavily damped door then just opens slower).
      goal = handle + (door ? kDoorLead : lead_speed / 5.0) * motion;
      const bool empty = fingers < 0.004;  // closed on nothing: the handle slipped out
      if (open_fraction > 0.94) {
        next(Phase::kHold);
      } else if ((empty || (handle - tcp).norm() > 0.05) && phase_steps_ > 3) {
        next(Phase::kPreGrasp);  // let go and grasp again
      }
      break;
    }
    case Phase::kHold:
      gripper = -1.0;
      break;
  }

  // Base: keep the goal at the nominal offset from the base.
  const bool holding = phase_ == Phase::kClose || phase_ == Phase::kPull || phase_ == Phase::kHold;
  // Facing the handle; while a door turns, the base turns with it (the
  // arm alone runs out of wrist range), compensated in the arm below.
  const double yaw_goal = std::atan2(-hx.y(), -hx.x());
  const Eigen::Matrix2d goal_rotation = Eigen::Rotation2Dd(yaw_goal).toRotationMatrix();
  const Eigen::Vector2d base_goal = goal.head<2>() - goal_rotation * nominal_offset_;
  Eigen::Vector2d base_velocity = 3.0 * (base_goal - base);
  const double qdot = s[L::kTargetJoint + 1];
  const Eigen::Vector3d handle_velocity = door ? Eigen::Vector3d(qdot * axis.cross(handle - origin)) : Eigen::Vector3d(qdot * axis);
  if (phase_ == Phase::kPull)
    base_velocity = base_follow_ * (base_velocity + (door ? handle_velocity.head<2>() : Eigen::Vector2d(lead_speed * motion.head<2>())));
  // Where the arm alone falls short (reach, joint limits), the base helps.
  base_velocity += 1.5 * (goal - tcp).head<2>();
  if (phase_ == Phase::kHold || phase_ == Phase::kClose) base_velocity.setZero();
  base_velocity = clipNorm(base_velocity, kBaseSpeed);
  const Eigen::Vector2d base_local = Eigen::Rotation2Dd(-yaw).toRotationMatrix() * base_velocity;
  double yaw_rate = 2.0 * std::remainder(yaw_goal - yaw, 2 * M_PI);
  if (phase_ == Phase::kPull) yaw_rate *= yaw_follow_;
  if (phase_ == Phase::kHold || phase_ == Phase::kClose) yaw_rate = 0.0;
  yaw_rate = std::clamp(yaw_rate, -1.0, 1.0);
  // Lift: the goal's height at the arm's nominal height.
  const double lift_goal = std::clamp(goal.z() - nominal_height_, 0.0, 1.5);
  const double lift_rate = holding ? 0.0 : 3.0 * (lift_goal - lift);
  // Arm: the rest of the way, in the base frame.
  const double gain = phase_ == Phase::kPull && door ? door_speed_ / kDoorLead : 5.0;
  Eigen::Vector3d tcp_velocity = clipNorm(gain * (goal - tcp), kEeSpeed);
  if (phase_ == Phase::kHold) tcp_velocity.setZero();
  Eigen::Vector3d arm_velocity = tcp_velocity;
  // The arm's command is relative to the moving base: take out what the
  // base's own motion does to the TCP.
  const Eigen::Vector3d lever = tcp - Eigen::Vector3d(base.x(), base.y(), tcp.z());
  arm_velocity -= Eigen::Vector3d(base_velocity.x(), base_velocity.y(), 0) +
                  Eigen::Vector3d(0, 0, yaw_rate).cross(lever);
  Eigen::Vector3d angular = 4.0 * orientation_error.angle() * orientation_error.axis();
  angular.z() -= yaw_rate;  // the base turns the hand too
  if (phase_ == Phase::kPull && door) angular += axis * qdot;  // turn with the door
  angular = clipNorm(angular, kEeAngularSpeed);

  Eigen::VectorXd action = Eigen::VectorXd::Zero(action_dim_);
  setBaseAction(action, base_, base_local, yaw_rate, lift_rate);
  setEeAction(action, ee_linear_, ee_angular_, base_rotation, arm_velocity, angular);
  action[gripper_] = gripper;
  return action;
}

}  // namespace open_cabinet
