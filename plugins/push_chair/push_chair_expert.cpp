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

struct PushChairExpert::View {
  mobile_panda::AgentOffsets::Reading robot;
  std::array<Eigen::Vector3d, 2> tcp;
  Eigen::Vector2d chair, chair_velocity;
  // The push line: from the chair to the target.
  double distance = 0;        // the chair's to the target
  Eigen::Vector2d d, side;    // along the line, and across it
  double hand_height = 0;     // the hands' when pushing
  // Where the hands go: ahead of the base, right arm to the right (higher
  // while the last step went round the chair).
  std::array<Eigen::Vector3d, 2> hand_goal;
};

struct PushChairExpert::Command {
  Eigen::Vector2d base_velocity = Eigen::Vector2d::Zero();  // world
  double yaw_goal = 0;
};

PushChairExpert::View PushChairExpert::read(const sdk::Observation& observation) const {
  using L = ObservationLayout;
  const Eigen::VectorXd s = observation.state;
  View v;
  v.robot = agent_.read(s);
  v.tcp = {v.robot.tcp[0], v.robot.tcp[1]};
  v.chair = s.segment<2>(L::kChairPose);
  v.chair_velocity = s.segment<2>(L::kChairVelocity);
  const Eigen::Vector2d target = s.segment<2>(L::kTarget);
  const double seat_top = s[L::kSeatTop + 2];
  const Eigen::Vector2d to_target = target - v.chair;
  v.distance = to_target.norm();
  v.d = v.distance > 1e-6 ? Eigen::Vector2d(to_target / v.distance) : unit(v.robot.yaw);
  v.side = Eigen::Vector2d(-v.d.y(), v.d.x());
  v.hand_height = seat_top - kBelowSeatTop;
  for (int a = 0; a < 2; ++a)
    v.hand_goal[a] =
        Eigen::Vector3d(v.robot.base.x(), v.robot.base.y(), v.hand_height + (orbiting_ ? kOrbitHandRise : 0.0)) +
        v.robot.base_rotation * Eigen::Vector3d(kHandForward, a == 0 ? -kHandSide : kHandSide, 0);
  return v;
}

// Round the chair to the staging point behind it (seen from the target),
// on a circle that keeps the hands clear of it, turned 45 degrees towards
// the way round: the base moves diagonally in its own frame, where both
// its axes add up to 0.7 m/s.
void PushChairExpert::approach(const View& v, Command& c) {
  const Eigen::Vector2d from_chair = v.robot.base - v.chair;
  const double here = std::atan2(from_chair.y(), from_chair.x());
  const double staging = std::atan2(-v.d.y(), -v.d.x());
  const double to_go = std::remainder(staging - here, 2 * kPi);
  if (orbit_sign_ == 0) orbit_sign_ = to_go >= 0 ? 1 : -1;
  const Eigen::Vector2d look = v.chair - v.robot.base;
  c.yaw_goal = std::atan2(look.y(), look.x());
  orbiting_ = std::abs(to_go) > 0.35;
  if (orbiting_) {
    const int way = std::abs(to_go) > 2.8 ? orbit_sign_ : (to_go >= 0 ? 1 : -1);
    const Eigen::Vector2d radial = unit(here), tangent = way * Eigen::Vector2d(-radial.y(), radial.x());
    c.base_velocity = kOrbitSpeed * tangent + 3.0 * (kOrbitRadius - from_chair.norm()) * radial;
    c.yaw_goal += way * kPi / 4;
    return;
  }
  const Eigen::Vector2d goal = v.chair - kOrbitRadius * v.d;
  c.base_velocity = 3.0 * (goal - v.robot.base);
  const double yaw_error = std::abs(std::remainder(c.yaw_goal - v.robot.yaw, 2 * kPi));
  // (the hands' height is what the lift and arm reach: only where they
  // are in the plane counts)
  const double hand_error =
      std::max((v.tcp[0] - v.hand_goal[0]).head<2>().norm(), (v.tcp[1] - v.hand_goal[1]).head<2>().norm());
  if (((goal - v.robot.base).norm() < 0.12 && yaw_error < 0.2 && hand_error < 0.1) || phase_steps_ > 100)
    enter(Phase::kPush);
}

// Along the push line at a speed that falls with the distance still to
// go; sideways back onto the line through the chair's centre.
void PushChairExpert::push(const View& v, Command& c) {
  orbiting_ = false;
  const double speed = std::clamp(kPushGain * (v.distance - kStopLead), 0.0, kPushSpeed);
  const Eigen::Vector2d offset = v.robot.base - v.chair;
  c.base_velocity = speed * v.d - 2.0 * offset.dot(v.side) * v.side;
  // Close to the target the line turns quickly with the chair's sideways
  // drift: hold the heading and line there.
  if (v.distance < 0.3) {
    c.yaw_goal = v.robot.yaw;
    c.base_velocity = speed * unit(v.robot.yaw);
  }
  if (v.distance < kReleaseDistance || (v.distance < 0.09 && v.chair_velocity.dot(v.d) < 0.02 && phase_steps_ > 10) ||
      offset.dot(v.d) > 0)
    enter(Phase::kRelease);
}

// Back off a little, then stay; a chair that stopped short (or drifted
// off) is pushed again from where it is now.
void PushChairExpert::release(const View& v, Command& c) {
  if (phase_steps_ <= 6) c.base_velocity = -0.25 * unit(v.robot.yaw);
  c.yaw_goal = v.robot.yaw;
  if (phase_steps_ > 6 && v.distance > kRetryDistance && v.chair_velocity.norm() < 0.05) {
    enter(Phase::kApproach);
    orbit_sign_ = 0;
  }
}

Eigen::VectorXd PushChairExpert::calcAction(const View& v, const Command& c) const {
  const mobile_panda::AgentOffsets::Reading& robot = v.robot;
  // Each base axis runs at up to kBaseSpeed: scale the command down as a whole.
  Eigen::Vector2d base_local = Eigen::Rotation2Dd(-robot.yaw).toRotationMatrix() * c.base_velocity;
  base_local /= std::max(1.0, base_local.cwiseAbs().maxCoeff() / kBaseSpeed);
  const Eigen::Vector2d base_velocity = Eigen::Rotation2Dd(robot.yaw).toRotationMatrix() * base_local;
  double yaw_rate = std::clamp(3.0 * std::remainder(c.yaw_goal - robot.yaw, 2 * kPi), -2.0, 2.0);
  if (phase_ == Phase::kRelease) yaw_rate = 0;

  // Lift: the hands at the cushion, the arms at their starting height above it.
  const double lift_goal = std::clamp(v.hand_height - nominal_height_, 0.0, 1.5);
  const double lift_rate = 3.0 * (lift_goal - robot.lift);

  Eigen::VectorXd action = Eigen::VectorXd::Zero(action_.dim);
  setBaseAction(action, action_.base, base_local, yaw_rate, lift_rate);
  for (int a = 0; a < 2; ++a) {
    Eigen::Vector3d velocity = clipNorm(5.0 * (v.hand_goal[a] - v.tcp[a]), kEeSpeed);
    // The command is relative to the moving base and lift: take out what
    // they do to the TCP.
    const Eigen::Vector3d lever = v.tcp[a] - Eigen::Vector3d(robot.base.x(), robot.base.y(), v.tcp[a].z());
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

Eigen::VectorXd PushChairExpert::act(const sdk::Observation& observation) {
  const View v = read(observation);
  if (!nominal_ready_) {  // the hands' starting orientation (relative to the base) and height above the lift
    for (int a = 0; a < 2; ++a) nominal_rotation_[a] = v.robot.base_rotation.transpose() * v.robot.tcp_rotation[a];
    nominal_height_ = 0.5 * (v.tcp[0].z() + v.tcp[1].z()) - v.robot.lift;
    nominal_ready_ = true;
  }
  ++phase_steps_;
  Command c;
  c.yaw_goal = std::atan2(v.d.y(), v.d.x());
  switch (phase_) {
    case Phase::kApproach: approach(v, c); break;
    case Phase::kPush: push(v, c); break;
    case Phase::kRelease: release(v, c); break;
  }
  return calcAction(v, c);
}

}  // namespace push_chair
