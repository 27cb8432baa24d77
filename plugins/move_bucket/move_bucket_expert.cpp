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

using manibench::kit::clipNorm;
using manibench::kit::MobilePandaSpeeds;
using manibench::kit::setBaseAction;
using manibench::kit::setEeAction;
using manibench::kit::getQuaternion;
using manibench::kit::getVector3;
using manibench::kit::wrapAngle;
using manibench::sdk::Error;
using manibench::sdk::kPi;
using manibench::sdk::Observation;
using manibench::sdk::PolicyContext;

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

MoveBucketExpert::MoveBucketExpert(const PolicyContext& context) : action_dim_(context.action.dim) {
  if (context.task_name != "MoveBucket-v0")
    throw Error("move_bucket_expert drives MoveBucket-v0, not '" + context.task_name + "'", MB_INVALID_ARGUMENT);
  if (context.observation_mode != "state" || context.observation.dim != ObservationLayout::kDim)
    throw Error("move_bucket_expert needs the state observation (" + std::to_string(ObservationLayout::kDim) +
                    " values), got mode '" + context.observation_mode + "' with " +
                    std::to_string(context.observation.dim),
                MB_INVALID_ARGUMENT);
  const std::vector<std::pair<std::string, uint32_t>> wanted = {
      {"base_forward", 1},     {"base_left", 1},       {"base_yaw", 1},       {"lift", 1},
      {"right_ee_linear", 3},  {"right_ee_angular", 3}, {"right_gripper", 1}, {"left_ee_linear", 3},
      {"left_ee_angular", 3},  {"left_gripper", 1}};
  for (const auto& [name, size] : wanted) {
    const manibench::sdk::SegmentInfo* s = context.action.find(name);
    if (s == nullptr || s->size != size)
      throw Error("move_bucket_expert needs the mobile_panda_ee controller on the dual-arm robot (action segment '" +
                      name + "' of size " + std::to_string(size) + " is missing); run it with --controller "
                      "mobile_panda_ee",
                  MB_INVALID_ARGUMENT);
  }
  base_ = context.action.get("base_forward").offset;
  if (context.action.get("base_left").offset != base_ + 1 || context.action.get("base_yaw").offset != base_ + 2 ||
      context.action.get("lift").offset != base_ + 3)
    throw Error("move_bucket_expert: base_forward, base_left, base_yaw, lift must be consecutive", MB_INVALID_ARGUMENT);
  int i = 0;
  for (const char* side : {"right", "left"}) {
    ee_linear_[std::size_t(i)] = context.action.get(std::string(side) + "_ee_linear").offset;
    ee_angular_[std::size_t(i)] = context.action.get(std::string(side) + "_ee_angular").offset;
    gripper_[std::size_t(i)] = context.action.get(std::string(side) + "_gripper").offset;
    ++i;
  }
}

void MoveBucketExpert::reset(uint64_t) {
  phase_ = Phase::kApproach;
  phase_steps_ = 0;
  carry_speed_ = 0;
  settled_steps_ = 0;
}

Eigen::VectorXd MoveBucketExpert::act(const Observation& observation) {
  using L = ObservationLayout;
  const Eigen::VectorXd& s = observation.state;
  const Eigen::Vector2d base(s[L::kBasePosition], s[L::kBasePosition + 1]);
  const double yaw = s[L::kBaseYaw];
  const double lift = s[L::kJointPositions + 3];
  const Eigen::Matrix3d base_rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const std::array<Eigen::Vector3d, 2> tcp = {getVector3(s, L::kRightTcpPose), getVector3(s, L::kLeftTcpPose)};
  const std::array<Eigen::Matrix3d, 2> tcp_rotation = {getQuaternion(s, L::kRightTcpPose + 3).toRotationMatrix(),
                                                       getQuaternion(s, L::kLeftTcpPose + 3).toRotationMatrix()};
  const Eigen::Vector3d bucket = getVector3(s, L::kBucketPose);
  const Eigen::Matrix3d bucket_rotation = getQuaternion(s, L::kBucketPose + 3).toRotationMatrix();
  const Eigen::Vector3d bucket_velocity = getVector3(s, L::kBucketVelocity);
  const Eigen::Vector3d platform = getVector3(s, L::kPlatformPose);
  const double platform_top = platform.z() + s[L::kPlatformHalfSize + 2];
  const double rim_height = s[L::kBucketRim], grip_y = (s[L::kBucketRim + 1] + s[L::kBucketRim + 2]) / 2;
  constexpr double dt = 0.05;  // one env step

  ++phase_steps_;
  auto next = [this](Phase p) {
    phase_ = p;
    phase_steps_ = 0;
  };

  // The grip axis: the bucket's y in the plane. At the start the base's y
  // axis is put along it, whichever sign turns the base less; each arm's
  // fingers open along it, whichever sign turns the hand less.
  Eigen::Vector2d grip_axis = (bucket_rotation * Eigen::Vector3d::UnitY()).head<2>();
  grip_axis = grip_axis.norm() > 1e-6 ? Eigen::Vector2d(grip_axis.normalized()) : Eigen::Vector2d(0, 1);
  if (phase_ == Phase::kApproach && phase_steps_ == 1) {
    const double yaw_a = std::atan2(grip_axis.y(), grip_axis.x()) - kPi / 2;
    grip_side_ = std::abs(wrapAngle(yaw_a - yaw)) <= kPi / 2 ? 1.0 : -1.0;
  }
  const Eigen::Vector2d across = grip_side_ * grip_axis;  // the base's +y at the grasp
  const Eigen::Vector3d across3(across.x(), across.y(), 0);
  const Eigen::Vector3d rim_centre = bucket + bucket_rotation * Eigen::Vector3d(0, 0, rim_height);

  // What this step commands: TCP goals (world) and orientations while
  // reaching, else the arms hold; base velocity (world), yaw rate, lift
  // rate, grippers.
  bool reaching = false;
  std::array<Eigen::Vector3d, 2> goal = tcp;
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
    base_velocity = clipNorm(Eigen::Vector2d(2.0 * (bucket.head<2>() - kReach * forward - base)), kBaseSpeed);
    yaw_rate = std::clamp(2.5 * wrapAngle(yaw_goal - yaw), -1.5, 1.5);
    const double lift_goal = std::clamp(tcp_height + kShoulderDrop - kShoulderAboveLift, 0.0, 1.5);
    lift_rate = std::clamp(3.0 * (lift_goal - lift), -0.4, 0.4);
    return (bucket.head<2>() - kReach * forward - base).norm() + 0.3 * std::abs(wrapAngle(yaw_goal - yaw));
  };
  auto tcpError = [&] { return std::max((goal[0] - tcp[0]).norm(), (goal[1] - tcp[1]).norm()); };

  switch (phase_) {
    case Phase::kApproach: {
      reaching = true;
      rimGoal(kPreGraspHeight);
      const double base_error = approach(rim_centre.z() + kPreGraspHeight);
      if ((base_error < 0.02 && tcpError() < 0.015) || (phase_steps_ > 80 && tcpError() < 0.03)) next(Phase::kDescend);
      break;
    }
    case Phase::kDescend:
      reaching = true;
      rimGoal(-kGripDepth);
      approach(rim_centre.z() + kPreGraspHeight);
      lift_rate = 0;
      if (tcpError() < 0.003 || phase_steps_ > 25) next(Phase::kSqueeze);
      break;
    case Phase::kSqueeze:
      reaching = true;
      rimGoal(-kGripDepth);
      gripper = -1.0;
      if (phase_steps_ >= 8) {
        grasp_lift_ = lift;
        held_yaw_ = yaw;
        next(Phase::kLift);
      }
      break;
    case Phase::kLift:
      gripper = -1.0;
      lift_rate = std::clamp(3.0 * (grasp_lift_ + kLiftBy - lift), -0.3, 0.3);
      if (lift > grasp_lift_ + kLiftBy - 0.02 || phase_steps_ > 30) next(Phase::kCarry);
      break;
    case Phase::kCarry: {
      gripper = -1.0;
      lift_rate = std::clamp(3.0 * (grasp_lift_ + kLiftBy - lift), -0.3, 0.3);
      const Eigen::Vector2d error = platform.head<2>() - bucket.head<2>();
      const double distance = error.norm();
      const double wanted = std::min(kCarrySpeed, std::sqrt(2 * kCarryAcceleration * std::max(distance - 0.005, 0.0)));
      carry_speed_ = std::min(wanted, carry_speed_ + kCarryAcceleration * dt);
      base_velocity = distance > 1e-6 ? Eigen::Vector2d(carry_speed_ * error / distance) : Eigen::Vector2d::Zero();
      yaw_rate = std::clamp(2.5 * wrapAngle(held_yaw_ - yaw), -0.5, 0.5);
      if (distance < 0.015 && bucket_velocity.head<2>().norm() < 0.05) next(Phase::kLower);
      break;
    }
    case Phase::kLower: {
      gripper = -1.0;
      const double clearance = bucket.z() - platform_top;
      lift_rate = -std::clamp(3.0 * (clearance + 0.01), 0.03, 0.25);
      settled_steps_ = clearance < 0.004 && std::abs(bucket_velocity.z()) < 0.02 ? settled_steps_ + 1 : 0;
      if (settled_steps_ >= 2) next(Phase::kRelease);
      break;
    }
    case Phase::kRelease:
      gripper = 1.0;
      if (phase_steps_ >= 6) next(Phase::kRetreat);
      break;
    case Phase::kRetreat:
      gripper = 1.0;
      lift_rate = phase_steps_ <= 8 ? 0.2 : 0.0;
      break;
  }

  // Arms: servo the TCPs to their goals, pointing down with the fingers
  // across the rim; the command is relative to the moving base, so take
  // out what the base, its turning and the lift do to the TCP.
  Eigen::VectorXd action = Eigen::VectorXd::Zero(action_dim_);
  for (std::size_t a = 0; a < 2; ++a) {
    Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
    if (reaching) {
      linear = clipNorm(Eigen::Vector3d(5.0 * (goal[a] - tcp[a])), kEeSpeed);
      const Eigen::AngleAxisd turn(pointingDown(finger_sign_[a] * across3) * tcp_rotation[a].transpose());
      angular = clipNorm(Eigen::Vector3d(4.0 * turn.angle() * turn.axis()), kEeAngularSpeed);
      const Eigen::Vector3d lever = tcp[a] - Eigen::Vector3d(base.x(), base.y(), tcp[a].z());
      linear -= Eigen::Vector3d(base_velocity.x(), base_velocity.y(), lift_rate) +
                Eigen::Vector3d(0, 0, yaw_rate).cross(lever);
      angular.z() -= yaw_rate;
    }
    if (phase_ == Phase::kRetreat && phase_steps_ <= 8) linear = Eigen::Vector3d(0, 0, 0.1);
    setEeAction(action, ee_linear_[a], ee_angular_[a], base_rotation, linear, angular);
    action[gripper_[a]] = gripper;
  }
  const Eigen::Vector2d base_local = Eigen::Rotation2Dd(-yaw).toRotationMatrix() * base_velocity;
  setBaseAction(action, base_, base_local, yaw_rate, lift_rate);
  return action;
}

}  // namespace move_bucket
