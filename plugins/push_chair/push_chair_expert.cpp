// Scripted expert for PushChair-v0 over the mobile_panda_ee controller
// (dual arm). Privileged: it reads the chair's pose, speed and seat and the
// target from the state observation.
//
// The two hands are a rigid paddle in front of the robot: each arm holds
// its TCP at a fixed place in the base frame (ahead of the body, one each
// side of the middle, at the height of the seat cushion) and keeps the
// orientation it started with; the base and the lift do the rest. Phases:
// approach (round the chair at a safe radius, hands above the seat, to the
// side away from the target; the hands go down to the cushion for the last
// stretch), push (along the line
// from the chair to the target, re-aimed every step at the chair's current
// position, slowing down as the chair nears the target so that it coasts
// to a stop there), release (back away and wait while the chair settles).
#include "push_chair.hpp"

#include <manibench/kit/policy_math.hpp>

#include <algorithm>
#include <cmath>

namespace push_chair {

using manibench::kit::clipNorm;
using manibench::kit::MobilePandaSpeeds;
using manibench::kit::setBaseAction;
using manibench::kit::setEeAction;
using manibench::kit::getQuaternion;
using manibench::kit::getVector3;
using manibench::sdk::Error;
using manibench::sdk::Observation;
using manibench::sdk::PolicyContext;
using manibench::sdk::kPi;

namespace {

constexpr double kBaseSpeed = MobilePandaSpeeds::kBase;  // per unit action
constexpr double kEeSpeed = MobilePandaSpeeds::kEeLinear, kEeAngularSpeed = MobilePandaSpeeds::kEeAngular;
constexpr double kHandForward = 0.55;   // m: TCPs ahead of the base centre
constexpr double kHandSide = 0.28;      // m: each TCP off the base's middle line
constexpr double kBelowSeatTop = 0.04;  // m: the hands' height under the cushion's top
constexpr double kOrbitRadius = kHandForward + 0.45;  // m: base to chair centre while going round it (hands 0.45 m off)
constexpr double kOrbitHandRise = 0.22;  // m: hands above their push height while going round (clear of legs and seat)
constexpr double kOrbitSpeed = 0.7;    // m/s round the chair
constexpr double kPushSpeed = 0.5;      // m/s at most
constexpr double kPushGain = 1.2;       // 1/s: push speed per m of the chair's distance to go
constexpr double kStopLead = 0.05;      // m: the chair coasts about this far after the push ends
constexpr double kReleaseDistance = 0.06;  // m: push ends with the chair this close to the target
constexpr double kRetryDistance = 0.11;    // m: a chair that stopped farther is pushed again

Eigen::Vector2d unit(double angle) { return {std::cos(angle), std::sin(angle)}; }

}  // namespace

PushChairExpert::PushChairExpert(const PolicyContext& context) : action_dim_(context.action.dim) {
  if (context.task_name != "PushChair-v0")
    throw Error("push_chair_expert drives PushChair-v0, not '" + context.task_name + "'", MB_INVALID_ARGUMENT);
  if (context.observation_mode != "state" || context.observation.dim != ObservationLayout::kDim)
    throw Error("push_chair_expert needs the state observation (" + std::to_string(ObservationLayout::kDim) +
                    " values), got mode '" + context.observation_mode + "' with " +
                    std::to_string(context.observation.dim),
                MB_INVALID_ARGUMENT);
  const std::vector<std::pair<const char*, uint32_t>> wanted = {
      {"base_forward", 1},    {"base_left", 1},       {"base_yaw", 1},        {"lift", 1},
      {"right_ee_linear", 3}, {"right_ee_angular", 3}, {"right_gripper", 1}, {"left_ee_linear", 3},
      {"left_ee_angular", 3}, {"left_gripper", 1}};
  for (const auto& [name, size] : wanted) {
    const manibench::sdk::SegmentInfo* s = context.action.find(name);
    if (s == nullptr || s->size != size)
      throw Error(std::string("push_chair_expert needs the dual-arm mobile_panda_ee controller (action segment '") +
                      name + "' of size " + std::to_string(size) +
                      " is missing); run it with --controller mobile_panda_ee",
                  MB_INVALID_ARGUMENT);
  }
  base_ = context.action.get("base_forward").offset;
  if (context.action.get("base_left").offset != base_ + 1 || context.action.get("base_yaw").offset != base_ + 2 ||
      context.action.get("lift").offset != base_ + 3)
    throw Error("push_chair_expert: base_forward, base_left, base_yaw, lift must be consecutive", MB_INVALID_ARGUMENT);
  const char* sides[2] = {"right", "left"};
  for (int a = 0; a < 2; ++a) {
    ee_linear_[a] = context.action.get(std::string(sides[a]) + "_ee_linear").offset;
    ee_angular_[a] = context.action.get(std::string(sides[a]) + "_ee_angular").offset;
    gripper_[a] = context.action.get(std::string(sides[a]) + "_gripper").offset;
  }
}

void PushChairExpert::reset(uint64_t) {
  phase_ = Phase::kApproach;
  phase_steps_ = 0;
  nominal_ready_ = false;
  orbit_sign_ = 0;
  orbiting_ = false;
}

Eigen::VectorXd PushChairExpert::act(const Observation& observation) {
  using L = ObservationLayout;
  const Eigen::VectorXd s = observation.state;
  const Eigen::Vector2d base(s[L::kBasePosition], s[L::kBasePosition + 1]);
  const double yaw = s[L::kBaseYaw];
  const double lift = s[L::kJointPositions + 3];
  const Eigen::Matrix3d base_rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const std::array<Eigen::Vector3d, 2> tcp = {getVector3(s, L::kRightTcpPose), getVector3(s, L::kLeftTcpPose)};
  const std::array<Eigen::Quaterniond, 2> tcp_q = {getQuaternion(s, L::kRightTcpPose + 3), getQuaternion(s, L::kLeftTcpPose + 3)};
  const Eigen::Vector2d chair = s.segment<2>(L::kChairPose);
  const Eigen::Vector2d chair_velocity = s.segment<2>(L::kChairVelocity);
  const Eigen::Vector2d target = s.segment<2>(L::kTarget);
  const double seat_top = s[L::kSeatTop + 2];

  if (!nominal_ready_) {  // the hands' starting orientation (relative to the base) and height above the lift
    for (int a = 0; a < 2; ++a) nominal_rotation_[a] = base_rotation.transpose() * tcp_q[a].toRotationMatrix();
    nominal_height_ = 0.5 * (tcp[0].z() + tcp[1].z()) - lift;
    nominal_ready_ = true;
  }
  ++phase_steps_;
  auto next = [this](Phase p) {
    phase_ = p;
    phase_steps_ = 0;
  };

  // The push line: from the chair to the target.
  const Eigen::Vector2d to_target = target - chair;
  const double distance = to_target.norm();
  const Eigen::Vector2d d = distance > 1e-6 ? Eigen::Vector2d(to_target / distance) : unit(yaw);
  const Eigen::Vector2d side(-d.y(), d.x());
  const double hand_height = seat_top - kBelowSeatTop;

  // Where the hands go: ahead of the base, right arm to the right.
  std::array<Eigen::Vector3d, 2> hand_goal;
  for (int a = 0; a < 2; ++a)
    hand_goal[a] = Eigen::Vector3d(base.x(), base.y(), hand_height + (orbiting_ ? kOrbitHandRise : 0.0)) +
                   base_rotation * Eigen::Vector3d(kHandForward, a == 0 ? -kHandSide : kHandSide, 0);

  Eigen::Vector2d base_velocity = Eigen::Vector2d::Zero();
  double yaw_goal = std::atan2(d.y(), d.x());
  switch (phase_) {
    case Phase::kApproach: {
      // Round the chair to the staging point behind it (seen from the
      // target), on a circle that keeps the hands clear of it, turned 45
      // degrees towards the way round: the base moves diagonally in its own
      // frame, where both its axes add up to 0.7 m/s.
      const Eigen::Vector2d from_chair = base - chair;
      const double here = std::atan2(from_chair.y(), from_chair.x());
      const double staging = std::atan2(-d.y(), -d.x());
      const double to_go = std::remainder(staging - here, 2 * kPi);
      if (orbit_sign_ == 0) orbit_sign_ = to_go >= 0 ? 1 : -1;
      const Eigen::Vector2d look = chair - base;
      yaw_goal = std::atan2(look.y(), look.x());
      orbiting_ = std::abs(to_go) > 0.35;
      if (orbiting_) {
        const int way = std::abs(to_go) > 2.8 ? orbit_sign_ : (to_go >= 0 ? 1 : -1);
        const Eigen::Vector2d radial = unit(here), tangent = way * Eigen::Vector2d(-radial.y(), radial.x());
        base_velocity = kOrbitSpeed * tangent + 3.0 * (kOrbitRadius - from_chair.norm()) * radial;
        yaw_goal += way * kPi / 4;
      } else {
        const Eigen::Vector2d goal = chair - kOrbitRadius * d;
        base_velocity = 3.0 * (goal - base);
        const double yaw_error = std::abs(std::remainder(yaw_goal - yaw, 2 * kPi));
        // (the hands' height is what the lift and arm reach: only where
        // they are in the plane counts)
        const double hand_error =
            std::max((tcp[0] - hand_goal[0]).head<2>().norm(), (tcp[1] - hand_goal[1]).head<2>().norm());
        if (((goal - base).norm() < 0.12 && yaw_error < 0.2 && hand_error < 0.1) || phase_steps_ > 100)
          next(Phase::kPush);
      }
      break;
    }
    case Phase::kPush: {
      orbiting_ = false;
      // Along the push line at a speed that falls with the distance still
      // to go; sideways back onto the line through the chair's centre.
      const double speed = std::clamp(kPushGain * (distance - kStopLead), 0.0, kPushSpeed);
      const Eigen::Vector2d offset = base - chair;
      base_velocity = speed * d - 2.0 * offset.dot(side) * side;
      // Close to the target the line turns quickly with the chair's
      // sideways drift: hold the heading and line there.
      if (distance < 0.3) {
        yaw_goal = yaw;
        base_velocity = speed * unit(yaw);
      }
      if (distance < kReleaseDistance || (distance < 0.09 && chair_velocity.dot(d) < 0.02 && phase_steps_ > 10) ||
          offset.dot(d) > 0)
        next(Phase::kRelease);
      break;
    }
    case Phase::kRelease:
      // Back off a little, then stay; a chair that stopped short (or
      // drifted off) is pushed again from where it is now.
      if (phase_steps_ <= 6) base_velocity = -0.25 * unit(yaw);
      yaw_goal = yaw;
      if (phase_steps_ > 6 && distance > kRetryDistance && chair_velocity.norm() < 0.05) {
        next(Phase::kApproach);
        orbit_sign_ = 0;
      }
      break;
  }
  // Each base axis runs at up to kBaseSpeed: scale the command down as a whole.
  Eigen::Vector2d base_local = Eigen::Rotation2Dd(-yaw).toRotationMatrix() * base_velocity;
  base_local /= std::max(1.0, base_local.cwiseAbs().maxCoeff() / kBaseSpeed);
  base_velocity = Eigen::Rotation2Dd(yaw).toRotationMatrix() * base_local;
  double yaw_rate = std::clamp(3.0 * std::remainder(yaw_goal - yaw, 2 * kPi), -2.0, 2.0);
  if (phase_ == Phase::kRelease) yaw_rate = 0;

  // Lift: the hands at the cushion, the arms at their starting height above it.
  const double lift_goal = std::clamp(hand_height - nominal_height_, 0.0, 1.5);
  const double lift_rate = 3.0 * (lift_goal - lift);

  Eigen::VectorXd action = Eigen::VectorXd::Zero(action_dim_);
  setBaseAction(action, base_, base_local, yaw_rate, lift_rate);
  for (int a = 0; a < 2; ++a) {
    Eigen::Vector3d velocity = clipNorm(5.0 * (hand_goal[a] - tcp[a]), kEeSpeed);
    // The command is relative to the moving base and lift: take out what
    // they do to the TCP.
    const Eigen::Vector3d lever = tcp[a] - Eigen::Vector3d(base.x(), base.y(), tcp[a].z());
    velocity -= Eigen::Vector3d(base_velocity.x(), base_velocity.y(), lift_rate) +
                Eigen::Vector3d(0, 0, yaw_rate).cross(lever);
    const Eigen::AngleAxisd error(base_rotation * nominal_rotation_[a] * tcp_q[a].toRotationMatrix().transpose());
    Eigen::Vector3d angular = clipNorm(4.0 * error.angle() * error.axis(), kEeAngularSpeed);
    angular.z() -= yaw_rate;
    setEeAction(action, ee_linear_[a], ee_angular_[a], base_rotation, velocity, angular);
    action[gripper_[a]] = -1.0;  // closed: a compact fist
  }
  return action;
}

}  // namespace push_chair
