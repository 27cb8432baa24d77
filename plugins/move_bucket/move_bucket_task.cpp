// MoveBucket-v0: scene (dual-arm robot, bucket, ball, platform), reset,
// observation, reward and success.
#include "move_bucket.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>


namespace move_bucket {
namespace {

constexpr uint32_t kRobotMask = 0;
constexpr const char* kTaskName = "MoveBucket";

std::string writeBallUrdf() {
  const double m = kDensity * 4.0 / 3.0 * kPi * std::pow(kBallRadius, 3);
  const double i = 0.4 * m * kBallRadius * kBallRadius;
  std::ostringstream x;
  x << "<?xml version=\"1.0\"?>\n<robot name=\"ball\">\n  <link name=\"ball\">\n    <inertial><mass value=\"" << m
    << "\"/><inertia ixx=\"" << i << "\" ixy=\"0\" ixz=\"0\" iyy=\"" << i << "\" iyz=\"0\" izz=\"" << i
    << "\"/></inertial>\n    <visual name=\"ball\"><geometry><sphere radius=\"" << kBallRadius
    << "\"/></geometry><material name=\"ball_cyan\"><color rgba=\"0 0.8 0.85 1\"/></material></visual>\n"
    << "    <collision name=\"ball\"><geometry><sphere radius=\"" << kBallRadius
    << "\"/></geometry></collision>\n  </link>\n</robot>\n";
  return x.str();
}

std::string writePlatformUrdf() {
  const Eigen::Vector3d& h = kPlatformHalfSize;
  std::ostringstream x;
  x << "<?xml version=\"1.0\"?>\n<robot name=\"platform\">\n  <link name=\"platform\">\n"
    << "    <inertial><mass value=\"10\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial>\n";
  const std::string g = "<geometry><box size=\"" + std::to_string(2 * h.x()) + " " + std::to_string(2 * h.y()) + " " +
                        std::to_string(2 * h.z()) + "\"/></geometry>";
  x << "    <visual name=\"platform\">" << g
    << "<material name=\"platform_white\"><color rgba=\"0.92 0.92 0.9 1\"/></material></visual>\n"
    << "    <collision name=\"platform\">" << g << "</collision>\n  </link>\n</robot>\n";
  return x.str();
}

}  // namespace

MoveBucketTask::MoveBucketTask(const Config& config)
    : cache_dir_(config.get<std::string>("cache_dir", "")),
      facts_(config, "move_bucket"),
      hold_steps_(config.get<uint32_t>("hold_steps", 10)),
      buckets_(kTaskName, "bucket", readPartNetFolders(config, kTaskName),
               {listGeneratedBuckets, [](const std::string& id) { return generateBucket(id); },
                [this](const std::string& folder, const std::string& id) {
                  return loadPartNetBucket(folder, id, facts_.calcScale(id), cache_dir_);
                },
                nullptr, [this](BucketModel& model) { writeMeshFiles(model, cache_dir_); }, nullptr}) {
  config.requireKnownKeys({"partnet_dir", "partnet_test_categories", "robot_dir", "cache_dir", "partnet_scale",
                           "object_facts", "hold_steps"},
                          "MoveBucket: task");
  if (hold_steps_ == 0) throw Error("MoveBucket: task.hold_steps must be positive", MB_INVALID_ARGUMENT);
  if (cache_dir_.empty()) cache_dir_ = getDefaultCacheRoot();
  // The observation layout (ObservationLayout) and the expert assume the
  // dual-arm robot's 22 joints and 88-value agent vector.
  robot_state_ = std::make_unique<mobile_panda::AgentState>(mobile_panda::readRobotDir(config),
                                                            "mobile_panda_dual", kTaskName, 2, kRobotDof);
}

sdk::TaskSpec MoveBucketTask::describe() const {
  sdk::TaskSpec spec = robot_state_->describeTask();
  const std::vector<Segment> objects = {
      {"bucket_pose", 7, "bucket frame (centre of the bottom's underside, z up): position, quaternion wxyz"},
      {"bucket_velocity", 3, "of the bucket frame's origin, world (m/s)"},
      {"bucket_ang_velocity", 3, "world (rad/s)"},
      {"bail_joint", 4, "the handle's joint: q, qdot, lower, upper (rad); zeros without a handle"},
      {"ball_position", 3, "ball centre, world (m)"},
      {"ball_velocity", 3, "world (m/s)"},
      {"platform_pose", 7, "centre of the target platform's box: position, quaternion wxyz"},
      {"platform_half_size", 3, "half extents of the platform's box (m)"},
      {"bucket_rim", 4, "rim height above the bucket frame; outer and inner half width along its y; outer half "
                        "width along its x (m)"},
  };
  spec.observation.insert(spec.observation.end(), objects.begin(), objects.end());
  spec.success_conditions = {"on_platform", "upright", "static", "ball_inside", "success"};
  spec.success_hold_steps = hold_steps_;
  spec.progress_signals = {"reached", "holding", "progress", "fallen"};
  spec.masks = {"robot"};
  // ManiSkill v1: bucket, ball and platform friction 0.5 (default 0.5), fingers 2.
  std::ostringstream config;
  config << "physics:\n  contact:\n    ground: {static_friction: 0.5, dynamic_friction: 0.5}\n    bodies:\n";
  for (const char* body : {"bucket", "ball", "platform"})
    config << "      - {articulation: " << body << ", static_friction: 0.5, dynamic_friction: 0.5}\n";
  spec.default_config = config.str() + robot_state_->getFingerFrictionYaml() + robot_state_->getFacts().camera_yaml;
  return spec;
}

std::vector<std::string> MoveBucketTask::listObjects(const std::string& split) const { return buckets_.list(split); }

void MoveBucketTask::buildScene(SceneView& scene, const std::string& object_id) {
  bucket_ = buckets_.get(object_id);
  scene.addGround(0.0);
  robot_ = robot_state_->addTo(scene);
  bucket_id_ = scene.addUrdfString(bucket_->urdf, bucket_->base_dir, "bucket", Pose(), /*fixed_base=*/false);
  body_link_ = scene.findLink(bucket_id_, bucket_->body_link);
  body_parts_ = {body_link_};
  if (!bucket_->body_parts.empty()) body_parts_.clear();
  for (const std::string& part : bucket_->body_parts) body_parts_.push_back(scene.findLink(bucket_id_, part));
  bucket_joint_count_ = scene.getJointCount(bucket_id_);
  bail_index_ = bucket_->bail_joint.empty() ? -1 : int(scene.findJoint(bucket_id_, bucket_->bail_joint));
  ball_id_ = scene.addUrdfString(writeBallUrdf(), "", "ball", Pose(), /*fixed_base=*/false);
  ball_link_ = scene.findLink(ball_id_, "ball");
  Pose platform;
  platform.position = platform_centre_;
  platform_id_ = scene.addUrdfString(writePlatformUrdf(), "", "platform", platform, /*fixed_base=*/true);
  scene.addArticulationToMask(kRobotMask, robot_);
}

void MoveBucketTask::reset(SceneView& scene, uint64_t seed) {
  Random rng(seed ^ 0x6d6f76655f62756bULL);
  // ManiSkill v1: the platform at the origin; the bucket 0.8-1.2 m from it
  // in any direction, any yaw; the robot 0.6-0.8 m from the bucket on its
  // far side (within 0.4 pi of straight away from the platform), facing
  // the bucket with +-0.05 pi of heading noise.
  const double distance = rng.uniform(0.8, 1.2);
  const double theta = rng.uniform(-kPi, kPi);
  const double yaw = rng.uniform(-kPi, kPi);
  Pose bucket;
  bucket.position = Eigen::Vector3d(platform_centre_.x() + distance * std::cos(theta),
                                    platform_centre_.y() + distance * std::sin(theta), 0.0);
  bucket.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  scene.setRootPose(bucket_id_, bucket);
  initial_height_ = bucket.position.z();
  initial_platform_distance_ = distance;
  const double robot_distance = rng.uniform(0.6, 0.8);
  const double around = theta + rng.uniform(-0.4 * kPi, 0.4 * kPi);
  robot_state_->placeFacing(scene, rng, bucket.position.head<2>(), robot_distance, around, -kPi);
  // The bail folded down on a random side, its joint friction and damping
  // drawn anew (a loose pivot: the 50 g wire must still fall).
  Eigen::VectorXd joints = Eigen::VectorXd::Zero(bucket_joint_count_);
  const bool left = rng.chance(0.5);
  const double friction = rng.uniform(0.0, 0.01), damping = rng.uniform(0.001, 0.01);
  if (bail_index_ >= 0) {
    joints[bail_index_] = left ? bucket_->bail_lower : bucket_->bail_upper;
    scene.setJointDynamics(bucket_id_, uint32_t(bail_index_), damping, friction);
  }
  if (bucket_joint_count_ > 0) {  // (the host refuses empty vectors)
    scene.setJointPositions(bucket_id_, joints);
    scene.setJointVelocities(bucket_id_, Eigen::VectorXd::Zero(bucket_joint_count_));
  }
  // The ball on the bucket's bottom, in the middle.
  Pose ball;
  ball.position = bucket.position + Eigen::Vector3d(0, 0, bucket_->floor_height + kBallRadius + 1e-3);
  scene.setRootPose(ball_id_, ball);
}

void MoveBucketTask::observe(const SceneView& scene, Eigen::Map<Eigen::VectorXd> out) {
  using L = ObservationLayout;
  robot_state_->observe(scene, out.head(L::kAgentDim));
  const Pose bucket = scene.getLinkPose(body_link_);
  const Twist twist = scene.getLinkTwist(body_link_);
  putPose(out, L::kBucketPose, bucket);
  out.segment<3>(L::kBucketVelocity) = twist.linear;
  out.segment<3>(L::kBucketAngularVelocity) = twist.angular;
  out.segment<4>(L::kBailJoint).setZero();
  if (bail_index_ >= 0)
    out.segment<4>(L::kBailJoint) << scene.getJointPositions(bucket_id_)[bail_index_],
        scene.getJointVelocities(bucket_id_)[bail_index_], bucket_->bail_lower, bucket_->bail_upper;
  out.segment<3>(L::kBallPosition) = scene.getLinkPose(ball_link_).position;
  out.segment<3>(L::kBallVelocity) = scene.getLinkTwist(ball_link_).linear;
  Pose platform;
  platform.position = platform_centre_;
  putPose(out, L::kPlatformPose, platform);
  out.segment<3>(L::kPlatformHalfSize) = kPlatformHalfSize;
  out.segment<4>(L::kBucketRim) << bucket_->rim_height, bucket_->rim_outer_y, bucket_->rim_inner_y,
      bucket_->rim_outer_x;
}

RewardInputs MoveBucketTask::measure(const SceneView& scene, double action_norm) const {
  RewardInputs in;
  const Pose bucket = scene.getLinkPose(body_link_);
  const Eigen::Matrix3d R = bucket.orientation.toRotationMatrix();
  const std::vector<Eigen::Vector3d> pads = robot_state_->calcPadPositions(scene);
  double total = 0;
  for (const Eigen::Vector3d& pad : pads) {
    const Eigen::Vector3d local = R.transpose() * (pad - bucket.position);
    double best = 1e300;
    for (const Eigen::Vector3d& p : bucket_->surface_points) best = std::min(best, (p - local).squaredNorm());
    total += std::sqrt(best);
  }
  in.gripper_distance = total / 4;
  const Eigen::Vector3d right = (pads[0] + pads[1]) / 2, left = (pads[2] + pads[3]) / 2;
  in.height_difference = std::abs((R.transpose() * (right - left)).z());
  const Eigen::Vector3d rim_centre = bucket.position + R * Eigen::Vector3d(0, 0, bucket_->rim_height);
  const Eigen::Vector3d v1 = right - rim_centre, v2 = left - rim_centre;
  const double norms = v1.norm() * v2.norm();
  in.opposition = norms > 1e-12 ? 1 - v1.dot(v2) / norms : 0.0;
  in.tilt = std::acos(std::clamp(R(2, 2), -1.0, 1.0));
  in.lift = bucket.position.z() - initial_height_;
  const Twist twist = scene.getLinkTwist(body_link_);
  in.speed = twist.linear.norm();
  in.angular_speed = twist.angular.norm();
  in.up_speed = twist.linear.z();
  const Eigen::Vector2d to_platform = platform_centre_.head<2>() - bucket.position.head<2>();
  in.platform_distance = to_platform.norm();
  in.speed_to_platform =
      in.platform_distance > 1e-9 ? twist.linear.head<2>().dot(to_platform / in.platform_distance) : 0.0;
  in.action_norm = action_norm;
  return in;
}

double MoveBucketTask::computeReward(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) {
  return calcStagedReward(measure(scene, action.norm()));
}

std::vector<sdk::Condition> MoveBucketTask::evaluateSuccess(const SceneView& scene) {
  const RewardInputs m = measure(scene, 0);
  const Pose bucket = scene.getLinkPose(body_link_);
  const double platform_top = platform_centre_.z() + kPlatformHalfSize.z();
  // B.4: on or above the platform (the root over it, not below its top)...
  const bool on = m.platform_distance <= RewardConstants::kOnPlatform && bucket.position.z() >= platform_top - 0.02;
  const bool upright = m.tilt < RewardConstants::kUpright;
  const bool still = m.speed <= RewardConstants::kStaticSpeed && m.angular_speed <= RewardConstants::kStaticAngularSpeed;
  // ... and the ball's centre inside the body's box (ManiSkill's test).
  const Eigen::Vector3d ball =
      bucket.orientation.inverse() * (scene.getLinkPose(ball_link_).position - bucket.position);
  const bool inside = (ball.array() > bucket_->lower.array()).all() && (ball.array() < bucket_->upper.array()).all();
  return {{on, m.platform_distance}, {upright, m.tilt}, {still, m.speed}, {inside, ball.z()},
          {on && upright && still && inside, 0.0}};
}

std::vector<double> MoveBucketTask::measureProgress(const SceneView& scene) const {
  const RewardInputs m = measure(scene, 0);
  // 1 N each finger: a touch, well under the grippers' squeeze.
  constexpr double kTouch = 1.0;
  auto holds = [&](std::size_t arm) {
    for (const mb_id part : body_parts_)
      if (robot_state_->isHolding(scene, part, arm, kTouch)) return true;
    return false;
  };
  const bool holding = holds(0) && holds(1);
  const double lift = std::clamp(m.lift / RewardConstants::kLiftHeight, 0.0, 1.0);
  const double way = std::max(initial_platform_distance_ - RewardConstants::kOnPlatform, 1e-6);
  const double carried = std::clamp((initial_platform_distance_ - m.platform_distance) / way, -1.0, 1.0);
  return {m.gripper_distance < RewardConstants::kNear ? 1.0 : 0.0, holding ? 1.0 : 0.0, 0.5 * lift + 0.5 * carried,
          m.tilt > RewardConstants::kTipped ? 1.0 : 0.0};
}

}  // namespace move_bucket
