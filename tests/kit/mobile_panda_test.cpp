// The SDK's mobile Panda facts (sdk/include/manibench/kit/mobile_panda.hpp)
// on the robots of assets/robots: joints, initial configuration with the
// task's lift, head cameras at the task's height, the agent state layout.
#include <manibench/kit/mobile_panda.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace {

namespace mobile_panda = manibench::kit::mobile_panda;
const std::string kRobots = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/assets/robots";

TEST(MobilePanda, FactsOfBothRobotsForATask) {
  const mobile_panda::Facts single = mobile_panda::loadFacts(kRobots, "mobile_panda_single", "OpenCabinetDrawer");
  EXPECT_EQ(single.joints.size(), 13u);
  EXPECT_EQ(single.initial.size(), 13);
  EXPECT_DOUBLE_EQ(single.initial[3], 0.0001) << "cabinet lift";
  EXPECT_EQ(single.tcp_links, std::vector<std::string>{"right_panda_tcp"});
  EXPECT_NE(single.camera_yaml.find("position: [0, 0, 1.5]"), std::string::npos) << single.camera_yaml;
  const mobile_panda::Facts dual = mobile_panda::loadFacts(kRobots, "mobile_panda_dual", "PushChair");
  ASSERT_EQ(dual.joints.size(), 22u);
  EXPECT_DOUBLE_EQ(dual.initial[3], 0.9) << "chair lift";
  EXPECT_DOUBLE_EQ(dual.initial[7], -1.5) << "right arm joint 4";
  EXPECT_DOUBLE_EQ(dual.initial[16], -1.5) << "left arm joint 4";
  EXPECT_DOUBLE_EQ(dual.initial[21], 0.02) << "left finger";
  EXPECT_EQ(dual.finger_links.size(), 4u);
  EXPECT_EQ(dual.arm_sides, (std::vector<std::string>{"right", "left"}));
  EXPECT_NE(dual.camera_yaml.find("position: [0, 0, 2]"), std::string::npos) << dual.camera_yaml;
  // An unlisted task gets the default lift and camera height.
  EXPECT_DOUBLE_EQ(mobile_panda::loadFacts(kRobots, "mobile_panda_dual", "Other").initial[3], 0.9);
}

TEST(MobilePanda, AgentStateLayouts) {
  const mobile_panda::AgentState single(mobile_panda::loadFacts(kRobots, "mobile_panda_single", "OpenCabinetDoor"));
  EXPECT_EQ(single.getDim(), 51u);  // ManiSkill's 38 with the base joints, then the TCP pose
  const mobile_panda::AgentState dual(mobile_panda::loadFacts(kRobots, "mobile_panda_dual", "PushChair"));
  EXPECT_EQ(dual.getDim(), 88u);
  uint32_t total = 0;
  for (const auto& s : dual.describe()) total += s.size;
  EXPECT_EQ(total, 88u);
  EXPECT_EQ(dual.describe().back().name, "left_tcp_pose");
  EXPECT_EQ(single.describe().back().name, "tcp_pose");
}

TEST(MobilePanda, MissingFactsNameTheFile) {
  try {
    mobile_panda::loadFacts("/nonexistent", "mobile_panda_dual", "PushChair");
    FAIL();
  } catch (const manibench::sdk::Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/mobile_panda_dual.yaml"), std::string::npos) << e.what();
  }
}

// Malformed facts: an error naming the file and what is wrong, never a read
// past a short list.
TEST(MobilePanda, MalformedFactsNameTheFileAndTheProblem) {
  const std::string dir = ::testing::TempDir() + "mobile_panda_malformed";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/mobile_panda_single.yaml";
  const auto expectError = [&](const std::string& text, const std::string& what) {
    std::ofstream(path) << text;
    try {
      mobile_panda::loadFacts(dir, "mobile_panda_single", "X");
      FAIL() << "no error for " << what;
    } catch (const manibench::sdk::Error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  const std::string arms =
      "arms:\n  - {side: right, tcp_link: t, finger_links: [l, r]}\n"
      "initial_configuration: {base: [0, 0, 0], lift: 0.1, arm: [], fingers: []}\n";
  expectError("joints: [a, b]\n" + arms, "(4 values)");
  expectError("joints: [a, b, c, d]\n" + arms +
                  "cameras: {width: 4, height: 4, fovy: 1, near: 0.1, far: 10, mount_height: {default: 1},\n"
                  "  mounts: [{name: head, parent_link: base_link, xyz: [0, 0], rpy: [0, 0, 0]}]}\n",
              "camera mount head needs xyz and rpy of 3 values");
  std::filesystem::remove_all(dir);
}

}  // namespace
