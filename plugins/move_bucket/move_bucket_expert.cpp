// Scripted expert for MoveBucket-v0 over the mobile_panda_ee controller.
// Privileged: it reads the bucket's pose and rim and the platform from the
// state observation.
//
// A forklift: the base faces the bucket with its y axis along the bucket's
// grip axis (the bucket frame's y, where every bucket has a flat face and
// the bail never lies), the arms hold both TCPs pointing down over the rim
// on either side, the lift does the vertical travel. Phases: approach (base
// to its grasp pose, arms to the pre-grasp 8 cm above the rim, fingers
// open), descend onto the rim, squeeze, lift 0.25 m, carry (the base
// drives the held bucket over the platform's centre), lower until the
// bucket rests on the platform, release, retreat upwards.
#include "move_bucket.hpp"

#include <manibench/kit/policy_math.hpp>

#include <algorithm>
#include <cmath>

namespace move_bucket {
namespace {

constexpr double kBaseSpeed = MobilePandaSpeeds::kBase;  // per unit action
constexpr double kEeSpeed = MobilePandaSpeeds::kEeLinear, kEeAngularSpeed = MobilePandaSpeeds::kEeAngular;
constexpr double kReach = 0.55;        // m: bucket centre ahead of the base while gripping
constexpr double kShoulderDrop = 0.2;  // m: TCP below the arm's first joint while gripping
constexpr double kShoulderAboveLift = 0.1315 + 0.2885;  // first joint above the lift's zero (docs/robot.md)
constexpr double kPreGraspHeight = 0.08;  // above the rim
constexpr double kGripDepth = 0.013;      // TCP below the rim top (pads 4 mm below it)
constexpr double kLiftBy = 0.25;          // the platform is 0.2 m tall
constexpr double kCarrySpeed = 0.4, kCarryAcceleration = 0.6;  // m/s, m/s^2

// TCP orientation pointing down with the fingers opening along `across`
// (horizontal): z = -world z, y = across, x = y cross z.
Eigen::Matrix3d pointingDown(const Eigen::Vector3d& across) {
  Eigen::Matrix3d r;
  r.col(2) = -Eigen::Vector3d::UnitZ();
  r.col(1) = across;
  r.col(0) = r.col(1).cross(r.col(2));
  return r;
}

}  // namespace

MoveBucketExpert::MoveBucketExpert(const sdk::PolicyContext& context)
    : Expert(context, "move_bucket_expert", {"MoveBucket-v0"}, ObservationLayout::kDim, 2) {}

void MoveBucketExpert::reset(uint64_t seed) {
  Expert::reset(seed);
  carry_speed_ = 0;
  settled_steps_ = 0;
}

Eigen::VectorXd MoveBucketExpert::act(const sdk::Observation& observation) {
  using L = ObservationLayout;
  const Eigen::VectorXd& s = observation.state;
  const mobile_panda::AgentOffsets::Reading robot = agent_.read(s);
  const std::vector<Eigen::Vector3d>& tcp = robot.tcp;
  const std::vector<Eigen::Matrix3d>& tcp_rotation = robot.tcp_rotation;
  const Eigen::Vector3d bucket = getVector3(s, L::kBucketPose);
  const Eigen::Matrix3d bucket_rotation = getQuaternion(s, L::kBucketPose + 3).toRotationMatrix();
  const Eigen::Vector3d bucket_velocity = getVector3(s, L::kBucketVelocity);
  const Eigen::Vector3d platform = getVector3(s, L::kPlatformPose);
  const double platform_top = platform.z() + s[L::kPlatformHalfSize + 2];
  const double rim_height = s[L::kBucketRim], grip_y = (s[L::kBucketRim + 1] + s[L::kBucketRim + 2]) / 2;
  constexpr double dt = 0.05;  // one env step

  ++phase_steps_;

  // The grip axis: the bucket's y in the plane. At the start the base's y
  // axis is put along it, whichever sign turns the base less; each arm's
  // fingers open along it, whichever sign turns the hand less.
  Eigen::Vector2d grip_axis = (bucket_rotation * Eigen::Vector3d::UnitY()).head<2>();
  grip_axis = grip_axis.norm() > 1e-6 ? Eigen::Vector2d(grip_axis.normalized()) : Eigen::Vector2d(0, 1);
  if (phase_ == Phase::kApproach && phase_steps_ == 1) {
    const double yaw_a = std::atan2(grip_axis.y(), grip_axis.x()) - kPi / 2;
    grip_side_ = std::abs(wrapAngle(yaw_a - robot.yaw)) <= kPi / 2 ? 1.0 : -1.0;
  }
  const Eigen::Vector2d across = grip_side_ * grip_axis;  // the base's +y at the grasp
  const Eigen::Vector3d across3(across.x(), across.y(), 0);
  const Eigen::Vector3d rim_centre = bucket + bucket_rotation * Eigen::Vector3d(0, 0, rim_height);

  // What this step commands: TCP goals (world) and orientations while
  // reaching, else the arms hold; base velocity (world), yaw rate, lift
  // rate, grippers.
  bool reaching = false;
  std::array<Eigen::Vector3d, 2> goal = {tcp[0], tcp[1]};
  Eigen::Vector2d base_velocity = Eigen::Vector2d::Zero();
  double yaw_rate = 0, lift_rate = 0, gripper = 1.0;
  const double side[2] = {-1.0, 1.0};  // right arm on the base's -y side
  auto rimGoal = [&](double height) {
    for (std::size_t a = 0; a < 2; ++a)
      goal[a] = rim_centre + side[a] * grip_y * across3 + Eigen::Vector3d(0, 0, height);
  };
  // Base and lift to the grasp pose: the bucket kReach ahead, the
  // grippers kShoulderDrop below the arms' first joints.
  auto approach = [&](double tcp_height) {
    const double yaw_goal = std::atan2(across.y(), across.x()) - kPi / 2;
    const Eigen::Vector2d forward(std::cos(yaw_goal), std::sin(yaw_goal));
    base_velocity = clipNorm(Eigen::Vector2d(2.0 * (bucket.head<2>() - kReach * forward - robot.base)), kBaseSpeed);
    yaw_rate = std::clamp(2.5 * wrapAngle(yaw_goal - robot.yaw), -1.5, 1.5);
    const double lift_goal = std::clamp(tcp_height + kShoulderDrop - kShoulderAboveLift, 0.0, 1.5);
    lift_rate = std::clamp(3.0 * (lift_goal - robot.lift), -0.4, 0.4);
    return (bucket.head<2>() - kReach * forward - robot.base).norm() + 0.3 * std::abs(wrapAngle(yaw_goal - robot.yaw));
  };
  auto tcpError = [&] { return std::max((goal[0] - tcp[0]).norm(), (goal[1] - tcp[1]).norm()); };

  switch (phase_) {
    case Phase::kApproach: {
      reaching = true;
      rimGoal(kPreGraspHeight);
      const double base_error = approach(rim_centre.z() + kPreGraspHeight);
      if ((base_error < 0.02 && tcpError() < 0.015) || (phase_steps_ > 80 && tcpError() < 0.03)) enter(Phase::kDescend);
      break;
    }
    case Phase::kDescend:
      reaching = true;
      rimGoal(-kGripDepth);
      approach(rim_centre.z() + kPreGraspHeight);
      lift_rate = 0;
      if (tcpError() < 0.003 || phase_steps_ > 25) enter(Phase::kSqueeze);
      break;
    case Phase::kSqueeze:
      reaching = true;
      rimGoal(-kGripDepth);
      gripper = -1.0;
      if (phase_steps_ >= 8) {
        grasp_lift_ = robot.lift;
        held_yaw_ = robot.yaw;
        enter(Phase::kLift);
      }
      break;
    case Phase::kLift:
      gripper = -1.0;
      lift_rate = std::clamp(3.0 * (grasp_lift_ + kLiftBy - robot.lift), -0.3, 0.3);
      if (robot.lift > grasp_lift_ + kLiftBy - 0.02 || phase_steps_ > 30) enter(Phase::kCarry);
      break;
    case Phase::kCarry: {
      gripper = -1.0;
      lift_rate = std::clamp(3.0 * (grasp_lift_ + kLiftBy - robot.lift), -0.3, 0.3);
      const Eigen::Vector2d error = platform.head<2>() - bucket.head<2>();
      const double distance = error.norm();
      const double wanted = std::min(kCarrySpeed, std::sqrt(2 * kCarryAcceleration * std::max(distance - 0.005, 0.0)));
      carry_speed_ = std::min(wanted, carry_speed_ + kCarryAcceleration * dt);
      base_velocity = distance > 1e-6 ? Eigen::Vector2d(carry_speed_ * error / distance) : Eigen::Vector2d::Zero();
      yaw_rate = std::clamp(2.5 * wrapAngle(held_yaw_ - robot.yaw), -0.5, 0.5);
      if (distance < 0.015 && bucket_velocity.head<2>().norm() < 0.05) enter(Phase::kLower);
      break;
    }
    case Phase::kLower: {
      gripper = -1.0;
      const double clearance = bucket.z() - platform_top;
      lift_rate = -std::clamp(3.0 * (clearance + 0.01), 0.03, 0.25);
      settled_steps_ = clearance < 0.004 && std::abs(bucket_velocity.z()) < 0.02 ? settled_steps_ + 1 : 0;
      if (settled_steps_ >= 2) enter(Phase::kRelease);
      break;
    }
    case Phase::kRelease:
      gripper = 1.0;
      if (phase_steps_ >= 6) enter(Phase::kRetreat);
      break;
    case Phase::kRetreat:
      gripper = 1.0;
      lift_rate = phase_steps_ <= 8 ? 0.2 : 0.0;
      break;
  }

  // Arms: servo the TCPs to their goals, pointing down with the fingers
  // across the rim; the command is relative to the moving base, so take
  // out what the base, its turning and the lift do to the TCP.
  Eigen::VectorXd action = Eigen::VectorXd::Zero(action_.dim);
  for (std::size_t a = 0; a < 2; ++a) {
    Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
    if (reaching) {
      linear = clipNorm(Eigen::Vector3d(5.0 * (goal[a] - tcp[a])), kEeSpeed);
      const Eigen::AngleAxisd turn(pointingDown(finger_sign_[a] * across3) * tcp_rotation[a].transpose());
      angular = clipNorm(Eigen::Vector3d(4.0 * turn.angle() * turn.axis()), kEeAngularSpeed);
      const Eigen::Vector3d lever = tcp[a] - Eigen::Vector3d(robot.base.x(), robot.base.y(), tcp[a].z());
      linear -= Eigen::Vector3d(base_velocity.x(), base_velocity.y(), lift_rate) +
                Eigen::Vector3d(0, 0, yaw_rate).cross(lever);
      angular.z() -= yaw_rate;
    }
    if (phase_ == Phase::kRetreat && phase_steps_ <= 8) linear = Eigen::Vector3d(0, 0, 0.1);
    setEeAction(action, action_.arms[a].linear, action_.arms[a].angular, robot.base_rotation, linear, angular);
    action[action_.arms[a].gripper] = gripper;
  }
  const Eigen::Vector2d base_local = Eigen::Rotation2Dd(-robot.yaw).toRotationMatrix() * base_velocity;
  setBaseAction(action, action_.base, base_local, yaw_rate, lift_rate);
  return action;
}

}  // namespace move_bucket
