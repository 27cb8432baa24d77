// ABI 1.7's layers: mobile_panda_ee reports the mobile_panda action that
// makes its drives, and that action, stepped by mobile_panda from the same
// state, makes the same physics bit for bit. Also the normalisation that
// keeps the round trip exact (controllers/mobile_panda_common.hpp).
// The controllers' own header first: it brings the SDK's Eigen checks.
#include "mobile_panda_common.hpp"

#include <manibench/environment.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "test_registry.hpp"

namespace manibench {
namespace {

using controllers::normalizeVelocity;

// The number of doubles between a and b (same sign, finite).
int64_t countUlps(double a, double b) {
  int64_t x, y;
  std::memcpy(&x, &a, sizeof x);
  std::memcpy(&y, &b, sizeof y);
  return x > y ? x - y : y - x;
}

TEST(NormalizeVelocity, DenormalisesToTheVelocityBitForBitOrWithinOneUlp) {
  // Uniform joint velocities, and those of [1.57, 2) rad/s where a * 3.14
  // steps over doubles; other arm_max_velocity settings too.
  for (const double max : {3.14, 2.5, 0.7}) {
    std::mt19937_64 random(53);
    std::uniform_real_distribution<double> any(-max, max), skipped(max / 2, max * 0.64);
    int exact = 0, one_ulp = 0, division_exact = 0, samples = 0;
    for (int i = 0; i < 200000; ++i) {
      const double v = i % 2 ? any(random) : skipped(random);
      const double a = normalizeVelocity(v, max);
      ASSERT_LE(std::abs(a), 1.0);
      const int64_t ulps = countUlps(a * max, v);
      ASSERT_LE(ulps, 1) << "velocity " << v << ", max " << max;
      exact += ulps == 0;
      one_ulp += ulps == 1;
      division_exact += (v / max) * max == v;
      ++samples;
    }
    // Never worse than the quotient alone; where no a is exact, 1 ulp off.
    EXPECT_GE(exact, division_exact);
    EXPECT_EQ(exact + one_ulp, samples);
    EXPECT_GT(one_ulp, 0);  // the round trip is not exact by itself
    std::printf("[ measured ] max %g: %d velocities, %d exact (the quotient alone: %d), %d at 1 ulp\n", max,
                samples, exact, division_exact, one_ulp);
  }
  // The limit stays inside [-1, 1].
  EXPECT_EQ(normalizeVelocity(3.14, 3.14), 1.0);
  EXPECT_EQ(normalizeVelocity(-3.14, 3.14), -1.0);
  EXPECT_EQ(normalizeVelocity(std::nextafter(3.14, 4.0), 3.14), 1.0);
  EXPECT_EQ(normalizeVelocity(0.0, 3.14), 0.0);
}

EnvironmentOptions makeOptions(const std::string& controller) {
  EnvironmentOptions options;
  options.task_config = "robot: single";
  options.controller = controller;
  options.frame_skip = 1u;
  return options;
}

TEST(ControllerLayer, TheEeControllerIsALayerOverMobilePanda) {
  const PluginRegistry& registry = testing::getRobotTestbedRegistry();
  Environment ee(registry, "RobotTestbed-v0", makeOptions("mobile_panda_ee"));
  Environment joints(registry, "RobotTestbed-v0", makeOptions("mobile_panda"));
  EXPECT_EQ(ee.getControllerDescription().base_controller, "mobile_panda");
  EXPECT_EQ(joints.getControllerDescription().base_controller, "");
  ee.reset("0", 4);
  joints.reset("0", 4);
  const uint32_t dim = joints.getControllerDescription().action_dim;
  // Before its first compute a layer has no action to report; a controller
  // that is no layer never has.
  EXPECT_THROW(ee.getBaseAction(dim), PluginCallError);
  try {
    joints.getBaseAction(dim);
    ADD_FAILURE() << "mobile_panda reported a base action";
  } catch (const PluginCallError& e) {
    EXPECT_NE(std::string(e.what()).find("no layer"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ee.findSceneDifference(ee.saveState(), joints.saveState()), "");
  // A TCP sweep with base motion and a closing gripper: every control
  // step's base action keeps the two scenes bit-identical.
  for (int k = 0; k < 60; ++k) {
    Eigen::VectorXd action = Eigen::VectorXd::Zero(ee.getControllerDescription().action_dim);
    action[0] = 0.3 * std::sin(0.1 * k);
    action[2] = 0.2;
    action[3] = -0.1;
    action.segment<3>(4) = Eigen::Vector3d(0.4, -0.3 * std::cos(0.2 * k), 0.2);
    action[9] = 0.5;
    action[10] = -1.0 + k / 30.0;  // gripper
    ee.step(action);
    const Eigen::VectorXd base = ee.getBaseAction(dim);
    ASSERT_EQ(base.size(), Eigen::Index(dim));
    EXPECT_EQ(base.head<4>(), action.head<4>());
    EXPECT_EQ(base[11], action[10]);
    EXPECT_LE(base.cwiseAbs().maxCoeff(), 1.0);
    joints.step(base);
    ASSERT_EQ(joints.findSceneDifference(joints.saveState(), ee.saveState()), "") << "control step " << k;
  }
  // Something moved: the comparison is not of two resting robots.
  EXPECT_NE(joints.findSceneDifference(joints.saveState(), [&] {
              Environment fresh(registry, "RobotTestbed-v0", makeOptions("mobile_panda"));
              fresh.reset("0", 4);
              return fresh.saveState();
            }()),
            "");
}

TEST(ControllerLayer, AControllerBuiltBeforeAbi17LoadsAndIsNoLayer) {
  PluginRegistry registry;
  registry.loadDirectories({MANIBENCH_TEST_BUILD_PLUGIN_DIR});
  registry.loadLibrary(std::string(MANIBENCH_TEST_FIXTURE_DIR) + "/layer/libfixture_pre_layer_controller.so");
  EnvironmentOptions options;
  options.controller = "pre_layer_controller";
  Environment env(registry, "Reach-v0", options);
  // Its SDK would name a base, but its info ends before base_controller.
  EXPECT_EQ(env.getControllerDescription().base_controller, "");
  env.reset(env.listObjects("train").front(), 0);
  const Eigen::VectorXd action = Eigen::VectorXd::Constant(env.getControllerDescription().action_dim, 0.3);
  env.step(action);  // it drives
  try {
    env.getBaseAction(env.getControllerDescription().action_dim);
    ADD_FAILURE() << "a pre-1.7 controller reported a base action";
  } catch (const PluginCallError& e) {
    EXPECT_NE(std::string(e.what()).find("no layer"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace manibench
