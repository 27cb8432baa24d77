#include "reach.hpp"

#include <cmath>
#include <sstream>

namespace reach {
namespace {

// Object ids: eight train arms, four longer test arms.
const NumberedIds kIds{{0, 8}, {8, 4}};

// Rod inertia about its centre, for a link of `mass` and `length` along x.
std::string inertialXml(double mass, double length) {
  const double across = mass * length * length / 12.0;
  std::ostringstream xml;
  xml << "<inertial><origin xyz=\"" << length / 2 << " 0 0\"/><mass value=\"" << mass
      << "\"/><inertia ixx=\"1e-4\" ixy=\"0\" ixz=\"0\" iyy=\"" << across
      << "\" iyz=\"0\" izz=\"" << across << "\"/></inertial>";
  return xml.str();
}

std::string visualXml(double length) {
  std::ostringstream xml;
  xml << "<visual><origin xyz=\"" << length / 2 << " 0 0\"/><geometry><box size=\"" << length
      << " 0.04 0.04\"/></geometry></visual>";
  return xml.str();
}

// Both joints rotate about +y: the arm moves in the world x-z plane.
std::string makeArmUrdf(const ArmGeometry& g) {
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n<robot name=\"reach_arm\">\n"
      << "<link name=\"pedestal\"><inertial><mass value=\"5\"/>"
         "<inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial></link>\n"
      << "<link name=\"upper_arm\">" << inertialXml(1.0, g.upper_length)
      << visualXml(g.upper_length) << "</link>\n"
      << "<link name=\"forearm\">" << inertialXml(0.6, g.fore_length) << visualXml(g.fore_length)
      << "</link>\n"
      << "<link name=\"fingertip\"/>\n"
      << "<joint name=\"shoulder\" type=\"revolute\"><parent link=\"pedestal\"/>"
         "<child link=\"upper_arm\"/><origin xyz=\"0 0 0\"/><axis xyz=\"0 1 0\"/>"
         "<limit lower=\"-3.1\" upper=\"3.1\" velocity=\"2.0\" effort=\"60\"/>"
         "<dynamics damping=\"0.05\" friction=\"0.0\"/></joint>\n"
      << "<joint name=\"elbow\" type=\"revolute\"><parent link=\"upper_arm\"/>"
         "<child link=\"forearm\"/><origin xyz=\""
      << g.upper_length
      << " 0 0\"/><axis xyz=\"0 1 0\"/>"
         "<limit lower=\"-2.6\" upper=\"2.6\" velocity=\"2.0\" effort=\"30\"/>"
         "<dynamics damping=\"0.05\" friction=\"0.0\"/></joint>\n"
      << "<joint name=\"tip_mount\" type=\"fixed\"><parent link=\"forearm\"/>"
         "<child link=\"fingertip\"/><origin xyz=\""
      << g.fore_length << " 0 0\"/></joint>\n"
      << "</robot>\n";
  return xml.str();
}

}  // namespace

ArmGeometry getArmGeometry(const std::string& object_id) {
  const bool test = kIds.requireTest(object_id, "Reach object");
  const int id = *NumberedIds::parse(object_id);
  if (!test)  // train: upper 0.35-0.45 m, forearm 0.25-0.31 m
    return {0.35 + 0.1 * (id % 4) / 3.0, 0.25 + 0.02 * (id / 4) * 3.0};
  // test: longer arms than any train object (0.50-0.55 m / 0.33-0.36 m)
  const int k = id - kIds.test.first;
  return {0.50 + 0.05 * (k % 2), 0.33 + 0.03 * (k / 2)};
}

ReachTask::ReachTask(const Config& config)
    : reach_tolerance_(config.get<double>("reach_tolerance", 0.03)),
      static_speed_(config.get<double>("static_speed", 0.05)),
      hold_steps_(config.get<uint32_t>("hold_steps", 5)) {
  config.requireKnownKeys({"reach_tolerance", "static_speed", "hold_steps"}, "Reach: task");
  if (!(reach_tolerance_ > 0) || !(static_speed_ > 0))
    throw Error("Reach: reach_tolerance and static_speed must be positive", MB_INVALID_ARGUMENT);
}

sdk::TaskSpec ReachTask::describe() const {
  sdk::TaskSpec spec;
  spec.observation = {
      {"joint_positions", 2, "shoulder, elbow (rad)"},
      {"joint_velocities", 2, "shoulder, elbow (rad/s)"},
      {"tip_position", 3, "fingertip, world frame (m)"},
      {"target_position", 3, "target point, world frame (m)"},
      {"link_lengths", 2, "upper arm, forearm (m): the object's parameters"},
      {"shoulder_position", 3, "shoulder joint, world frame (m)"},
  };
  spec.success_conditions = {"reached", "static", "success"};
  spec.success_hold_steps = hold_steps_;
  spec.masks = {"robot"};
  spec.robot_articulation = "arm";
  spec.actuated_joints = {"shoulder", "elbow"};
  spec.default_controller = "joint_velocity";
  spec.control_frequency = 100;
  spec.frame_skip = 5;
  spec.max_episode_steps = 100;
  // Reach's layer of the YAML configuration (docs/configuration.md): the
  // solver it is tuned for, and a camera that sees the whole arm from the side.
  spec.default_config = R"(physics:
  integrator: implicit_euler   # stiff velocity drives: implicit, fixed steps
  implicit_step: 2.0e-3
cameras:
  - name: side
    pose: {position: [0, -2.0, 0.8], rpy: [0, 0, 1.5707963267948966]}
    width: 320
    height: 240
)";
  return spec;
}

std::vector<std::string> ReachTask::listObjects(const std::string& split) const { return kIds.list(split); }

void ReachTask::buildScene(SceneView& scene, const std::string& object_id) {
  geometry_ = getArmGeometry(object_id);
  Pose root;
  root.position = kShoulder;
  scene.addGround(0.0);
  robot_ = scene.addUrdfString(makeArmUrdf(geometry_), "", "arm", root, /*fixed_base=*/true);
  scene.addArticulationToMask(0, robot_);  // the "robot" mask of describe()
  tip_ = scene.findLink(robot_, "fingertip");
}

void ReachTask::reset(SceneView& scene, uint64_t seed) {
  // sdk::Random, not std::mt19937_64 with a std::uniform_real_distribution
  // (whose output the standard leaves to the library): the same seed gives
  // the same episode with libstdc++ and libc++.
  sdk::Random rng(seed);
  const double l1 = geometry_.upper_length, l2 = geometry_.fore_length;
  // A target the arm can reach without touching its joint limits.
  const double radius = rng.uniform(std::abs(l1 - l2) + 0.2, l1 + l2 - 0.05);
  const double angle = rng.uniform(-0.5, 1.5);  // below and in front of the shoulder
  target_ = kShoulder + Eigen::Vector3d(radius * std::cos(angle), 0.0, -radius * std::sin(angle));
  const double shoulder = rng.uniform(-0.3, 0.3);
  const double elbow = rng.uniform(-0.3, 0.3);
  Eigen::VectorXd q(2);
  q << shoulder, elbow;
  scene.setJointPositions(robot_, q);
  scene.setJointVelocities(robot_, Eigen::VectorXd::Zero(2));
}

void ReachTask::observe(const SceneView& scene, Eigen::Map<Eigen::VectorXd> out) {
  using L = ObservationLayout;
  out.segment<2>(L::kJointPositions) = scene.getJointPositions(robot_);
  out.segment<2>(L::kJointVelocities) = scene.getJointVelocities(robot_);
  out.segment<3>(L::kTip) = scene.getLinkPose(tip_).position;
  out.segment<3>(L::kTarget) = target_;
  out.segment<2>(L::kLinkLengths) << geometry_.upper_length, geometry_.fore_length;
  out.segment<3>(L::kShoulder) = kShoulder;
}

double ReachTask::computeReward(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) {
  const double distance = (scene.getLinkPose(tip_).position - target_).norm();
  const double speed = scene.getLinkTwist(tip_).linear.norm();
  // Approach stage: closer is better. Near the target, a bonus that exceeds
  // any approach reward, minus a speed penalty to settle.
  if (distance > reach_tolerance_) return -distance;
  return 1.0 - std::min(speed, 1.0);
}

std::vector<sdk::Condition> ReachTask::evaluateSuccess(const SceneView& scene) {
  const double distance = (scene.getLinkPose(tip_).position - target_).norm();
  const double speed = scene.getLinkTwist(tip_).linear.norm();
  const bool reached = distance <= reach_tolerance_;
  const bool still = speed <= static_speed_;
  // `success` once both have held for hold_steps steps (TaskSpec::success_hold_steps).
  return {{reached, distance}, {still, speed}, {reached && still, 0.0}};
}

}  // namespace reach
