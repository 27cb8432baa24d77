// The mobile_panda controller on the real robots (assets/robots/), through a
// real Environment with real Simbody physics. The task is the test fixture
// RobotTestbed-v0 (tests/fixtures/fixture_robot_testbed.cpp): the robot
// alone, initial configuration from its YAML, every joint actuated.
#include <manibench/environment.hpp>
#include <manibench/sdk/numbers.hpp>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "test_registry.hpp"

namespace manibench {
namespace {

using sdk::kPi;
constexpr double kArmMax = 3.14;  // rad/s at action 1 (ManiSkill)
constexpr int kArm = 4;           // first arm action and first arm joint (root_x, root_y, root_yaw, lift first)

// The build tree's plugins plus the testbed task, which lives outside the
// default search path.
const PluginRegistry& getRegistry() { return testing::getRobotTestbedRegistry(); }

EnvironmentOptions makeOptions(const std::string& robot, std::optional<uint32_t> frame_skip = {}) {
  EnvironmentOptions options;
  options.task_config = "robot: " + robot;
  options.frame_skip = frame_skip;
  return options;
}

struct Testbed {
  Environment env;
  int robot;
  explicit Testbed(EnvironmentOptions options)
      : env(getRegistry(), "RobotTestbed-v0", std::move(options)),
        robot(env.getScene().findArticulation("robot")) {
    env.reset("0", 0);
  }
  Eigen::VectorXd q() const { return env.getScene().getJointPositions(robot); }
  Eigen::VectorXd qdot() const { return env.getScene().getJointVelocities(robot); }
  int joint(const std::string& name) const { return env.getScene().findJoint(robot, name); }
  Eigen::VectorXd zero() const { return Eigen::VectorXd::Zero(env.getControllerDescription().action_dim); }
};

TEST(MobilePandaController, ActionLayouts) {
  Testbed single(makeOptions("single"));
  const ControllerDescription& c = single.env.getControllerDescription();
  EXPECT_EQ(c.name, "mobile_panda");
  ASSERT_EQ(c.action_dim, 12u);  // base 2 + yaw + lift + 7 arm + 1 gripper
  EXPECT_EQ(c.action_segments.front().name, "base_forward");
  EXPECT_EQ(c.action_segments[kArm].name, "right_panda_joint1");
  EXPECT_EQ(c.action_segments.back().name, "right_gripper");
  EXPECT_TRUE(c.flags & MB_CONTROLLER_BALANCE_PASSIVE_FORCES);

  Testbed dual(makeOptions("dual"));
  const ControllerDescription& d = dual.env.getControllerDescription();
  ASSERT_EQ(d.action_dim, 20u);
  EXPECT_EQ(d.action_segments[11].name, "right_gripper");
  EXPECT_EQ(d.action_segments[12].name, "left_panda_joint1");
  EXPECT_EQ(d.action_segments[19].name, "left_gripper");
}

TEST(MobilePandaController, SwappingTheControllerChangesTheLayoutWithoutRebuilding) {
  EnvironmentOptions options = makeOptions("single");
  options.controller = "joint_velocity";
  Testbed t(options);
  EXPECT_EQ(t.env.getControllerDescription().name, "joint_velocity");
  EXPECT_EQ(t.env.getControllerDescription().action_dim, 13u);  // one per joint
  EXPECT_NO_THROW(t.env.step(t.zero()));
}

TEST(MobilePandaController, MissingJointsAreNamed) {
  EnvironmentOptions options;
  options.controller = "mobile_panda";
  try {
    Environment env(getRegistry(), "Reach-v0", options);
    FAIL() << "mobile_panda accepted a robot without a base";
  } catch (const std::exception& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("root_x"), std::string::npos) << message;
    EXPECT_NE(message.find("lift"), std::string::npos) << message;
    EXPECT_NE(message.find("right_panda_joint1"), std::string::npos) << message;
  }
}

TEST(MobilePandaController, HoldsStillUnderGravity) {
  Testbed t(makeOptions("dual"));
  const Eigen::VectorXd q0 = t.q();
  for (int i = 0; i < 200; ++i) t.env.step(t.zero());  // 10 s
  const Eigen::VectorXd drift = (t.q() - q0).cwiseAbs();
  for (const std::string side : {"right", "left"})
    for (int j = 1; j <= 7; ++j) {
      const std::string name = side + "_panda_joint" + std::to_string(j);
      EXPECT_LT(drift[t.joint(name)], 1e-3) << name;
    }
  EXPECT_LT(drift[t.joint("lift")], 1e-3);
}

TEST(MobilePandaController, ArmJointVelocityStepResponse) {
  Testbed t(makeOptions("single", 1));  // one env step = one control step
  for (int j = 0; j < 7; ++j) {
    t.env.reset("0", 0);
    const int joint = t.joint("right_panda_joint" + std::to_string(j + 1));
    Eigen::VectorXd action = t.zero();
    action[kArm + j] = 1.0 / kArmMax;  // 1 rad/s
    int steps = 0;
    while (t.qdot()[joint] < 0.95 && steps < 50) {
      t.env.step(action);
      ++steps;
    }
    // Issue 4: 95% within 5 control steps. The damping drive's time
    // constant is the carried inertia / damping; with ManiSkill's 100 the
    // shoulder joints need 6, 11 and 6 steps, so the controller defaults to
    // arm_damping 300 (measured: 3, 4, 3, 3, 2, 2, 2).
    EXPECT_LE(steps, 5) << "control steps to 95% on joint " << j + 1;
    std::printf("joint %d: %d control steps to 95%%\n", j + 1, steps);
    for (int step = 0; step < 10; ++step) t.env.step(action);
    EXPECT_NEAR(t.qdot()[joint], 1.0, 0.05) << "joint " << j + 1 << " steady state";
  }
}

TEST(MobilePandaController, ArmJointStopsAtItsLimit) {
  Testbed t(makeOptions("single"));
  const int joint = t.joint("right_panda_joint4");  // from -1.5 to the upper limit -0.0698
  const double upper = t.env.getScene().getJoints(t.robot)[joint].upper;
  Eigen::VectorXd action = t.zero();
  action[kArm + 3] = 1.0;
  for (int i = 0; i < 20; ++i) t.env.step(action);  // 1 s at 3.14 rad/s
  EXPECT_NEAR(t.q()[joint], upper, 0.01);
  EXPECT_LT(t.q()[joint], upper + 0.005);
  EXPECT_LT(std::abs(t.qdot()[joint]), 0.05);
}

TEST(MobilePandaController, BaseVelocityIsEgocentric) {
  Testbed t(makeOptions("single"));
  const int x = t.joint("root_x"), y = t.joint("root_y"), yaw = t.joint("root_yaw");
  Eigen::VectorXd action = t.zero();
  action[2] = 0.25;  // about 0.785 rad/s
  while (t.q()[yaw] < kPi / 2 - 0.05 && t.env.getElapsedSteps() < 100) t.env.step(action);
  for (int i = 0; i < 4; ++i) t.env.step(t.zero());
  ASSERT_NEAR(t.q()[yaw], kPi / 2, 0.1);
  const Eigen::VectorXd q0 = t.q();
  action = t.zero();
  action[0] = 1.0;  // forward, 0.5 m/s
  for (int i = 0; i < 10; ++i) t.env.step(action);  // 0.5 s
  const double dx = t.q()[x] - q0[x], dy = t.q()[y] - q0[y];
  EXPECT_GT(dy, 0.2) << "dx " << dx;
  EXPECT_LT(std::abs(dx), 0.15 * dy);
}

TEST(MobilePandaController, GripperReachesItsTargets) {
  Testbed t(makeOptions("single"));
  const int f1 = t.joint("right_panda_finger_joint1"), f2 = t.joint("right_panda_finger_joint2");
  Eigen::VectorXd action = t.zero();
  for (double command : {1.0, -1.0, 0.0}) {
    action[11] = command;
    // 1 s: the fingers' drive (5000 N/m, 800 N s/m) settles with a time
    // constant of 0.16 s, within 0.1 mm after 1 s.
    for (int i = 0; i < 20; ++i) t.env.step(action);
    const double target = 0.02 * (command + 1.0);
    EXPECT_NEAR(t.q()[f1], target, 1e-3) << "command " << command;
    EXPECT_NEAR(t.q()[f2], target, 1e-3) << "command " << command;
  }
}

TEST(MobilePandaController, RejectsNaNActions) {
  Testbed t(makeOptions("single"));
  t.env.step(t.zero());
  Eigen::VectorXd bad = t.zero();
  bad[5] = std::nan("");
  testing::expectMentions(testing::catchMessage<InvalidAction>([&] { t.env.step(bad); }),
                          {"step 1", "action[5] is NaN"});
}

// Issue 4: the joint_position controller (chosen in the options, no
// rebuild) takes the robot to a target configuration within 1 mrad in 2 s.
TEST(JointPositionControllerOnTheRobot, ReachesATargetConfigurationWithin2s) {
  EnvironmentOptions options = makeOptions("single", 1);
  options.controller = "joint_position";
  // The base joints carry the whole robot (about 50 kg): with the default
  // damping 100 the kp 10 loop rings (damping ratio 0.2) for seconds.
  options.controller_config = "damping: 300";
  Testbed t(options);
  const auto& joints = t.env.getScene().getJoints(t.robot);
  ASSERT_EQ(t.env.getControllerDescription().action_dim, joints.size());
  // The arm moves by up to 0.5 rad; base, lift and fingers hold.
  Eigen::VectorXd target = t.q();
  const double offsets[7] = {0.3, -0.3, 0.2, 0.4, -0.3, -0.4, 0.5};
  for (int j = 0; j < 7; ++j) target[kArm + j] += offsets[j];
  Eigen::VectorXd action(target.size());
  for (const JointDescription& joint : joints) {
    const bool limited = std::isfinite(joint.lower) && std::isfinite(joint.upper);
    const double lower = limited ? joint.lower : -kPi, upper = limited ? joint.upper : kPi;
    action[joint.index] = 2 * (target[joint.index] - lower) / (upper - lower) - 1;
  }
  for (int i = 0; i < 200; ++i) t.env.step(action);  // 2 s
  const Eigen::VectorXd error = (t.q() - target).cwiseAbs();
  for (const JointDescription& joint : joints)
    EXPECT_LT(error[joint.index], 1e-3) << joint.name;
  std::printf("largest error after 2 s: %.2e (arm joints %.2e rad)\n", error.maxCoeff(),
              error.segment(kArm, 7).maxCoeff());
}

// assets/robots/*.yaml `actions:` (scripts/generate-robots) states every
// controller's layout; it must be the layout the controller describes.
TEST(RobotYaml, ActionLayoutsAreTheControllersOwn) {
  for (const std::string robot : {"single", "dual"})
    for (const std::string controller : {"mobile_panda", "mobile_panda_ee"}) {
      const YAML::Node yaml = YAML::LoadFile(std::string(MANIBENCH_TEST_SOURCE_DIR) +
                                             "/assets/robots/mobile_panda_" + robot + ".yaml");
      const YAML::Node actions = yaml["actions"][controller];
      EnvironmentOptions options = makeOptions(robot);
      options.controller = controller;
      Testbed t(options);
      const ControllerDescription& c = t.env.getControllerDescription();
      EXPECT_EQ(actions["dim"].as<uint32_t>(), c.action_dim) << robot << " " << controller;
      ASSERT_EQ(actions["layout"].size(), c.action_segments.size()) << robot << " " << controller;
      for (std::size_t i = 0; i < c.action_segments.size(); ++i) {
        EXPECT_EQ(actions["layout"][i]["name"].as<std::string>(), c.action_segments[i].name);
        EXPECT_EQ(actions["layout"][i]["size"].as<uint32_t>(), c.action_segments[i].size);
      }
    }
}

// Issue 4's "done": `manibench info` prints both robots' action layouts
// (the testbed task through MANIBENCH_PLUGIN_PATH, as docs/robot.md shows).
TEST(ManibenchInfo, PrintsBothRobotsActionLayouts) {
  const std::string path = std::string("MANIBENCH_PLUGIN_PATH=") + MANIBENCH_TEST_FIXTURE_DIR;
  struct Case {
    std::string robot, controller, dim, last;
  };
  for (const Case& c : {Case{"single", "mobile_panda", "action, 12 values", "[11, 12)    right_gripper"},
                        Case{"dual", "mobile_panda", "action, 20 values", "[19, 20)    left_gripper"},
                        Case{"single", "mobile_panda_ee", "action, 11 values", "[4, 7)      right_ee_linear"},
                        Case{"dual", "mobile_panda_ee", "action, 18 values", "[14, 17)    left_ee_angular"}}) {
    // The controller chosen by --controller, or as a configuration key.
    const std::vector<std::string> choice =
        c.controller == "mobile_panda" ? std::vector<std::string>{"--controller", c.controller}
                                       : std::vector<std::string>{"--set", "control.controller=" + c.controller};
    std::vector<std::string> arguments = {"info", "RobotTestbed-v0", "--set", "task.robot=" + c.robot};
    arguments.insert(arguments.end(), choice.begin(), choice.end());
    const testing::CommandResult r = testing::runCli(arguments, {path});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(c.dim + " in [-1, 1], controller '" + c.controller + "'"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(c.last), std::string::npos) << r.out;
  }
}

// --- mobile_panda_ee ------------------------------------------------------------

constexpr double kEeLinearMax = 0.5;  // m/s at action 1

EnvironmentOptions makeEeOptions(const std::string& robot, std::optional<uint32_t> frame_skip = {}) {
  EnvironmentOptions options = makeOptions(robot, frame_skip);
  options.controller = "mobile_panda_ee";
  return options;
}

// Link poses relative to the robot's base frame (base_link).
Eigen::Isometry3d getPoseInBase(const Testbed& t, const std::string& link) {
  const Scene& scene = t.env.getScene();
  auto isometry = [&](int id) {
    const Pose p = scene.getLinkPose(id);
    Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
    x.linear() = p.orientation.normalized().toRotationMatrix();
    x.translation() = p.position;
    return x;
  };
  return isometry(scene.findLink(t.robot, "base_link")).inverse() *
         isometry(scene.findLink(t.robot, link));
}

double calcAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

TEST(MobilePandaEeController, ActionLayouts) {
  Testbed single(makeEeOptions("single"));
  const ControllerDescription& c = single.env.getControllerDescription();
  EXPECT_EQ(c.name, "mobile_panda_ee");
  ASSERT_EQ(c.action_dim, 11u);
  std::vector<std::string> names;
  for (const auto& segment : c.action_segments) names.push_back(segment.name + ":" + std::to_string(segment.size));
  EXPECT_EQ(names, (std::vector<std::string>{"base_forward:1", "base_left:1", "base_yaw:1", "lift:1",
                                             "right_ee_linear:3", "right_ee_angular:3", "right_gripper:1"}));
  EXPECT_TRUE(c.flags & MB_CONTROLLER_BALANCE_PASSIVE_FORCES);

  Testbed dual(makeEeOptions("dual"));
  const ControllerDescription& d = dual.env.getControllerDescription();
  ASSERT_EQ(d.action_dim, 18u);
  ASSERT_EQ(d.action_segments.size(), 10u);
  EXPECT_EQ(d.action_segments[7].name, "left_ee_linear");
  EXPECT_EQ(d.action_segments[9].name, "left_gripper");
}

// A constant TCP velocity along base x, then z: 10 cm each, on a straight
// line (issue 4: less than 5 mm off it), orientation kept.
TEST(MobilePandaEeController, MovesTheTcpAlongStraightLines) {
  Testbed t(makeEeOptions("single", 1));  // one env step = one control step
  for (int axis : {0, 2}) {
    const Eigen::Isometry3d start = getPoseInBase(t, "right_panda_tcp");
    Eigen::VectorXd action = t.zero();
    action[kArm + axis] = 0.1 / kEeLinearMax;  // 0.1 m/s
    double deviation = 0;
    for (int step = 0; step < 130; ++step) {
      t.env.step(step < 100 ? action : t.zero());  // 1 s moving, 0.3 s settling
      const Eigen::Vector3d moved = getPoseInBase(t, "right_panda_tcp").translation() - start.translation();
      Eigen::Vector3d off = moved;
      off[axis] = 0;
      deviation = std::max(deviation, off.norm());
    }
    const Eigen::Isometry3d end = getPoseInBase(t, "right_panda_tcp");
    EXPECT_NEAR(end.translation()[axis] - start.translation()[axis], 0.10, 0.005) << "axis " << axis;
    EXPECT_LT(deviation, 0.005) << "axis " << axis;
    EXPECT_LT(calcAngle(start.linear(), end.linear()), 0.01) << "axis " << axis;
    std::printf("axis %d: moved %.5f m, max deviation from the line %.6f m, turned %.6f rad\n", axis,
                end.translation()[axis] - start.translation()[axis], deviation,
                calcAngle(start.linear(), end.linear()));
  }
}

TEST(MobilePandaEeController, ZeroActionHoldsTheTcpStill) {
  Testbed t(makeEeOptions("dual"));
  const Scene& scene = t.env.getScene();
  const int right = scene.findLink(t.robot, "right_panda_tcp"), left = scene.findLink(t.robot, "left_panda_tcp");
  const Pose r0 = scene.getLinkPose(right), l0 = scene.getLinkPose(left);
  for (int i = 0; i < 60; ++i) t.env.step(t.zero());  // 3 s
  EXPECT_LT((scene.getLinkPose(right).position - r0.position).norm(), 1e-3);
  EXPECT_LT((scene.getLinkPose(left).position - l0.position).norm(), 1e-3);
  EXPECT_LT(r0.orientation.angularDistance(scene.getLinkPose(right).orientation), 2e-3);
}

// The ee commands live in the base frame: after a quarter turn of the base
// (with the TCP carried along, its pose in the base frame kept), +x moves
// the TCP along the world's y.
TEST(MobilePandaEeController, CommandsAreInTheBaseFrame) {
  Testbed t(makeEeOptions("single"));
  const Eigen::Isometry3d in_base = getPoseInBase(t, "right_panda_tcp");
  Eigen::VectorXd action = t.zero();
  action[2] = 0.25;  // about 0.785 rad/s
  const int yaw = t.joint("root_yaw");
  while (t.q()[yaw] < kPi / 2 - 0.05 && t.env.getElapsedSteps() < 100) t.env.step(action);
  for (int i = 0; i < 4; ++i) t.env.step(t.zero());
  ASSERT_NEAR(t.q()[yaw], kPi / 2, 0.1);
  const Eigen::Isometry3d turned = getPoseInBase(t, "right_panda_tcp");
  EXPECT_LT((turned.translation() - in_base.translation()).norm(), 5e-3);
  const int tcp = t.env.getScene().findLink(t.robot, "right_panda_tcp");
  const Eigen::Vector3d p0 = t.env.getScene().getLinkPose(tcp).position;
  action = t.zero();
  action[kArm] = 0.2;  // 0.1 m/s along the base's x
  for (int i = 0; i < 10; ++i) t.env.step(action);  // 0.5 s
  for (int i = 0; i < 4; ++i) t.env.step(t.zero());
  const Eigen::Vector3d moved = t.env.getScene().getLinkPose(tcp).position - p0;
  const double along = std::cos(t.q()[yaw]) * moved.x() + std::sin(t.q()[yaw]) * moved.y();
  EXPECT_NEAR(along, 0.05, 0.005) << moved.transpose();
  EXPECT_GT(moved.y(), 0.045) << moved.transpose();
}

// The lift carries the arms: raising it with zero ee action raises the TCP
// with it (the arm solve does not fight the lift).
TEST(MobilePandaEeController, TheLiftCarriesTheTcp) {
  Testbed t(makeEeOptions("single"));
  const int lift = t.joint("lift");
  const Eigen::Isometry3d before = getPoseInBase(t, "right_panda_tcp");
  const double lift_before = t.q()[lift];
  Eigen::VectorXd action = t.zero();
  action[3] = 0.4;  // 0.2 m/s
  for (int i = 0; i < 10; ++i) t.env.step(action);  // 0.5 s
  for (int i = 0; i < 6; ++i) t.env.step(t.zero());
  const double raised = t.q()[lift] - lift_before;
  ASSERT_GT(raised, 0.08);
  const Eigen::Vector3d moved = getPoseInBase(t, "right_panda_tcp").translation() - before.translation();
  EXPECT_NEAR(moved.z(), raised, 2e-3) << moved.transpose();
  EXPECT_LT(moved.head<2>().norm(), 2e-3) << moved.transpose();
}

TEST(MobilePandaEeController, RejectsBadActionsNamingStepAndIndex) {
  Testbed t(makeEeOptions("single"));
  for (int i = 0; i < 3; ++i) t.env.step(t.zero());
  Eigen::VectorXd bad = t.zero();
  bad[8] = -INFINITY;
  testing::expectMentions(testing::catchMessage<InvalidAction>([&] { t.env.step(bad); }),
                          {"step 3", "action[8] is infinite"});
  try {
    t.env.step(Eigen::VectorXd::Zero(12));  // mobile_panda's size
    FAIL() << "a 12-value action was accepted";
  } catch (const InvalidAction& e) {
    EXPECT_NE(std::string(e.what()).find("'mobile_panda_ee' expects 11"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(t.env.step(t.zero()));
}

TEST(MobilePandaEeController, UnknownControllerNamesListTheRobotControllers) {
  EnvironmentOptions options = makeOptions("single");
  options.controller = "mobile_panda_eee";
  try {
    Testbed t(options);
    FAIL() << "an unknown controller was accepted";
  } catch (const std::exception& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("mobile_panda_eee"), std::string::npos) << message;
    EXPECT_NE(message.find("available: joint_position, joint_velocity, mobile_panda, mobile_panda_ee"),
              std::string::npos) << message;
  }
}

TEST(MobilePandaEeController, SameActionsGiveBitIdenticalTrajectories) {
  auto record = [] {
    Testbed t(makeEeOptions("dual"));
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> uniform(-0.2, 0.2);
    std::vector<Eigen::VectorXd> trajectory;
    for (int i = 0; i < 10; ++i) {
      Eigen::VectorXd action = t.zero();
      for (Eigen::Index k = 0; k < action.size(); ++k) action[k] = uniform(rng);
      t.env.step(action);
      trajectory.push_back(t.q());
    }
    return trajectory;
  };
  const std::vector<Eigen::VectorXd> a = record(), b = record();
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ(0, std::memcmp(a[i].data(), b[i].data(), sizeof(double) * a[i].size())) << "step " << i;
}

}  // namespace
}  // namespace manibench
