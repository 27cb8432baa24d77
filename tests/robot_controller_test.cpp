// The mobile_panda controller on the real robots (assets/robots/), through a
// real Environment with real Simbody physics. The task is the test fixture
// RobotTestbed-v0 (tests/fixtures/fixture_robot_testbed.cpp): the robot
// alone, initial configuration from its YAML, every joint actuated.
#include <manibench/environment.hpp>

#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"

namespace manibench {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kArmMax = 3.14;  // rad/s at action 1 (ManiSkill)
constexpr int kArm = 4;           // first arm action and first arm joint (root_x, root_y, root_yaw, lift first)

// The build tree's plugins plus the testbed task, which lives outside the
// default search path.
const PluginRegistry& getRegistry() {
  static PluginRegistry* registry = [] {
    auto* r = new PluginRegistry();
    r->loadDirectories({MANIBENCH_TEST_BUILD_PLUGIN_DIR});
    r->loadLibrary(std::string(MANIBENCH_TEST_FIXTURE_DIR) + "/libfixture_robot_testbed.so");
    return r;
  }();
  return *registry;
}

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
    // With ManiSkill's damping 100 the drive's time constant is I / 100: the
    // wrist (joints 4-7) meets the 5-step goal of issue 4, the shoulder
    // joints carry the whole arm's inertia and need up to 11 steps
    // (measured: 6, 11, 6, 5, 2, 2, 2). A faster shoulder needs a larger
    // arm_damping than ManiSkill's.
    EXPECT_LE(steps, j < 3 ? 12 : 5) << "control steps to 95% on joint " << j + 1;
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
    for (int i = 0; i < 10; ++i) t.env.step(action);  // 0.5 s
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
  try {
    t.env.step(bad);
    FAIL() << "a NaN action was accepted";
  } catch (const InvalidAction& e) {
    EXPECT_NE(std::string(e.what()).find("step 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("action[5] is NaN"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace manibench
