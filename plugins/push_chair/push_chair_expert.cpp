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

PushChairExpert::PushChairExpert(const sdk::PolicyContext& context)
    : Expert(context, "push_chair_expert", {"PushChair-v0"}, ObservationLayout::kDim, 2) {}

void PushChairExpert::reset(uint64_t seed) {
  Expert::reset(seed);
  nominal_ready_ = false;
  orbit_sign_ = 0;
  orbiting_ = false;
}

Eigen::VectorXd PushChairExpert::act(const sdk::Observation& observation) {
  using L = ObservationLayout;
  const Eigen::VectorXd s = observation.state;
  const mobile_panda::AgentOffsets::Reading robot = agent_.read(s);
  const std::array<Eigen::Vector3d, 2> tcp = {robot.tcp[0], robot.tcp[1]};
  const Eigen::Vector2d chair = s.segment<2>(L::kChairPose);
  const Eigen::Vector2d chair_velocity = s.segment<2>(L::kChairVelocity);
  const Eigen::Vector2d target = s.segment<2>(L::kTarget);
  const double seat_top = s[L::kSeatTop + 2];

  if (!nominal_ready_) {  // the hands' starting orientation (relative to the base) and height above the lift
    for (int a = 0; a < 2; ++a) nominal_rotation_[a] = robot.base_rotation.transpose() * robot.tcp_rotation[a];
    nominal_height_ = 0.5 * (tcp[0].z() + tcp[1].z()) - robot.lift;
    nominal_ready_ = true;
  }
  ++phase_steps_;

  // The push line: from the chair to the target.
  const Eigen::Vector2d to_target = target - chair;
  const double distance = to_target.norm();
  const Eigen::Vector2d d = distance > 1e-6 ? Eigen::Vector2d(to_target / distance) : unit(robot.yaw);
  const Eigen::Vector2d side(-d.y(), d.x());
  const double hand_height = seat_top - kBelowSeatTop;

  // Where the hands go: ahead of the base, right arm to the right.
  std::array<Eigen::Vector3d, 2> hand_goal;
  for (int a = 0; a < 2; ++a)
    hand_goal[a] = Eigen::Vector3d(robot.base.x(), robot.base.y(), hand_height + (orbiting_ ? kOrbitHandRise : 0.0)) +
                   robot.base_rotation * Eigen::Vector3d(kHandForward, a == 0 ? -kHandSide : kHandSide, 0);

  Eigen::Vector2d base_velocity = Eigen::Vector2d::Zero();
  double yaw_goal = std::atan2(d.y(), d.x());
  switch (phase_) {
    case Phase::kApproach: {
      // Round the chair to the staging point behind it (seen from the
      // target), on a circle that keeps the hands clear of it, turned 45
      // degrees towards the way round: the base moves diagonally in its own
      // frame, where both its axes add up to 0.7 m/s.
      const Eigen::Vector2d from_chair = robot.base - chair;
      const double here = std::atan2(from_chair.y(), from_chair.x());
      const double staging = std::atan2(-d.y(), -d.x());
      const double to_go = std::remainder(staging - here, 2 * kPi);
      if (orbit_sign_ == 0) orbit_sign_ = to_go >= 0 ? 1 : -1;
      const Eigen::Vector2d look = chair - robot.base;
      yaw_goal = std::atan2(look.y(), look.x());
      orbiting_ = std::abs(to_go) > 0.35;
      if (orbiting_) {
        const int way = std::abs(to_go) > 2.8 ? orbit_sign_ : (to_go >= 0 ? 1 : -1);
        const Eigen::Vector2d radial = unit(here), tangent = way * Eigen::Vector2d(-radial.y(), radial.x());
        base_velocity = kOrbitSpeed * tangent + 3.0 * (kOrbitRadius - from_chair.norm()) * radial;
        yaw_goal += way * kPi / 4;
      } else {
        const Eigen::Vector2d goal = chair - kOrbitRadius * d;
        base_velocity = 3.0 * (goal - robot.base);
        const double yaw_error = std::abs(std::remainder(yaw_goal - robot.yaw, 2 * kPi));
        // (the hands' height is what the lift and arm reach: only where
        // they are in the plane counts)
        const double hand_error =
            std::max((tcp[0] - hand_goal[0]).head<2>().norm(), (tcp[1] - hand_goal[1]).head<2>().norm());
        if (((goal - robot.base).norm() < 0.12 && yaw_error < 0.2 && hand_error < 0.1) || phase_steps_ > 100)
          enter(Phase::kPush);
      }
      break;
    }
    case Phase::kPush: {
      orbiting_ = false;
      // Along the push line at a speed that falls with the distance still
      // to go; sideways back onto the line through the chair's centre.
      const double speed = std::clamp(kPushGain * (distance - kStopLead), 0.0, kPushSpeed);
      const Eigen::Vector2d offset = robot.base - chair;
      base_velocity = speed * d - 2.0 * offset.dot(side) * side;
      // Close to the target the line turns quickly with the chair's
      // sideways drift: hold the heading and line there.
      if (distance < 0.3) {
        yaw_goal = robot.yaw;
        base_velocity = speed * unit(robot.yaw);
      }
      if (distance < kReleaseDistance || (distance < 0.09 && chair_velocity.dot(d) < 0.02 && phase_steps_ > 10) ||
          offset.dot(d) > 0)
        enter(Phase::kRelease);
      break;
    }
    case Phase::kRelease:
      // Back off a little, then stay; a chair that stopped short (or
      // drifted off) is pushed again from where it is now.
      if (phase_steps_ <= 6) base_velocity = -0.25 * unit(robot.yaw);
      yaw_goal = robot.yaw;
      if (phase_steps_ > 6 && distance > kRetryDistance && chair_velocity.norm() < 0.05) {
        enter(Phase::kApproach);
        orbit_sign_ = 0;
      }
      break;
  }
  // Each base axis runs at up to kBaseSpeed: scale the command down as a whole.
  Eigen::Vector2d base_local = Eigen::Rotation2Dd(-robot.yaw).toRotationMatrix() * base_velocity;
  base_local /= std::max(1.0, base_local.cwiseAbs().maxCoeff() / kBaseSpeed);
  base_velocity = Eigen::Rotation2Dd(robot.yaw).toRotationMatrix() * base_local;
  double yaw_rate = std::clamp(3.0 * std::remainder(yaw_goal - robot.yaw, 2 * kPi), -2.0, 2.0);
  if (phase_ == Phase::kRelease) yaw_rate = 0;

  // Lift: the hands at the cushion, the arms at their starting height above it.
  const double lift_goal = std::clamp(hand_height - nominal_height_, 0.0, 1.5);
  const double lift_rate = 3.0 * (lift_goal - robot.lift);

  Eigen::VectorXd action = Eigen::VectorXd::Zero(action_.dim);
  setBaseAction(action, action_.base, base_local, yaw_rate, lift_rate);
  for (int a = 0; a < 2; ++a) {
    Eigen::Vector3d velocity = clipNorm(5.0 * (hand_goal[a] - tcp[a]), kEeSpeed);
    // The command is relative to the moving base and lift: take out what
    // they do to the TCP.
    const Eigen::Vector3d lever = tcp[a] - Eigen::Vector3d(robot.base.x(), robot.base.y(), tcp[a].z());
    velocity -= Eigen::Vector3d(base_velocity.x(), base_velocity.y(), lift_rate) +
                Eigen::Vector3d(0, 0, yaw_rate).cross(lever);
    const Eigen::AngleAxisd error(robot.base_rotation * nominal_rotation_[a] * robot.tcp_rotation[a].transpose());
    Eigen::Vector3d angular = clipNorm(4.0 * error.angle() * error.axis(), kEeAngularSpeed);
    angular.z() -= yaw_rate;
    setEeAction(action, action_.arms[a].linear, action_.arms[a].angular, robot.base_rotation, velocity, angular);
    action[action_.arms[a].gripper] = -1.0;  // closed: a compact fist
  }
  return action;
}

}  // namespace push_chair
