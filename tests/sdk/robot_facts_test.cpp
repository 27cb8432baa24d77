// sdk/robot_facts.hpp: the robots' YAML facts as tasks read them (joints,
// initial configuration with the task's lift, head cameras at the task's
// mount height), and clear errors for a missing or malformed file.
#include <gtest/gtest.h>

#include <manibench/sdk/robot_facts.hpp>

#include <cstdio>
#include <fstream>
#include <string>

#include "test_support.hpp"

namespace {

namespace sdk = manibench::sdk;
const std::string kRobots = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/assets/robots";

TEST(RobotFacts, DualArmRobotForEachTask) {
  const sdk::RobotFacts bucket = sdk::readRobotFacts(kRobots + "/mobile_panda_dual.yaml", "MoveBucket");
  ASSERT_EQ(bucket.joints.size(), 22u);
  EXPECT_EQ(bucket.joints[3], "lift");
  EXPECT_EQ(bucket.joints[13], "left_panda_joint1");
  ASSERT_EQ(bucket.initial.size(), 22);
  EXPECT_EQ(bucket.initial[3], 0.5);
  for (int arm : {4, 13}) {  // joints 1-7 [0, 0, 0, -1.5, 0, 3, 0.78], fingers 0.02
    EXPECT_EQ(bucket.initial[arm + 3], -1.5);
    EXPECT_EQ(bucket.initial[arm + 6], 0.78);
    EXPECT_EQ(bucket.initial[arm + 8], 0.02);
  }
  EXPECT_NE(bucket.camera_config.find("head_left"), std::string::npos);
  EXPECT_NE(bucket.camera_config.find("position: [0, 0, 1.5]"), std::string::npos) << bucket.camera_config;
  const sdk::RobotFacts chair = sdk::readRobotFacts(kRobots + "/mobile_panda_dual.yaml", "PushChair");
  EXPECT_EQ(chair.initial[3], 0.9);
  EXPECT_NE(chair.camera_config.find("position: [0, 0, 2]"), std::string::npos) << chair.camera_config;
  const sdk::RobotFacts other = sdk::readRobotFacts(kRobots + "/mobile_panda_dual.yaml", "NoSuchTask");
  EXPECT_EQ(other.initial[3], 0.9) << "the default lift";
}

TEST(RobotFacts, SingleArmRobot) {
  const sdk::RobotFacts door = sdk::readRobotFacts(kRobots + "/mobile_panda_single.yaml", "OpenCabinetDoor");
  ASSERT_EQ(door.joints.size(), 13u);
  EXPECT_EQ(door.initial.size(), 13);
  EXPECT_EQ(door.initial[3], 0.0001);
}

TEST(RobotFacts, BadFilesAreNamed) {
  manibench::testing::expectMentions(
      manibench::testing::catchMessage<sdk::Error>([] { sdk::readRobotFacts("/no/such/robot.yaml", "X"); }),
      {"/no/such/robot.yaml", "task.robot_dir"});
  const std::string path = ::testing::TempDir() + "robot_facts_broken.yaml";
  std::ofstream(path) << "joints: [a, b]\ninitial_configuration: {base: [0, 0, 0], lift: 0.1, arm: [], fingers: []}\n"
                         "arms: []\n";
  manibench::testing::expectMentions(
      manibench::testing::catchMessage<sdk::Error>([&] { sdk::readRobotFacts(path, "X"); }),
      {path, "4 values for 2 joints"});
  std::remove(path.c_str());
}

}  // namespace
