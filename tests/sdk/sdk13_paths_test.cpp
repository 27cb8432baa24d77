// A family written against SDK 1.3 includes <manibench/sdk/mobile_panda.hpp>
// and <manibench/sdk/policy_math.hpp> and names sdk::mobile_panda::... and
// sdk::getVector3...; those moved to the kit (manibench::kit), and the SDK
// promises 1.x source compatibility: the old paths forward to the kit, and
// the old names are the kit's own (same functions, same types).
#include <manibench/sdk/mobile_panda.hpp>
#include <manibench/sdk/policy_math.hpp>

#include <gtest/gtest.h>

#include <type_traits>

namespace {

namespace sdk = manibench::sdk;
namespace kit = manibench::kit;
const std::string kRobots = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/assets/robots";

TEST(Sdk13Paths, TheOldMobilePandaNamesAreTheKits) {
  static_assert(std::is_same_v<sdk::mobile_panda::AgentState, kit::mobile_panda::AgentState>);
  static_assert(std::is_same_v<sdk::mobile_panda::Facts, kit::mobile_panda::Facts>);
  const sdk::mobile_panda::Facts facts = sdk::mobile_panda::loadFacts(kRobots, "mobile_panda_single", "OpenCabinetDoor");
  const sdk::mobile_panda::AgentState state(facts);
  EXPECT_EQ(state.getDim(), 51u);
}

TEST(Sdk13Paths, TheOldPolicyMathNamesAreTheKits) {
  static_assert(std::is_same_v<sdk::MobilePandaSpeeds, kit::MobilePandaSpeeds>);
  Eigen::VectorXd state(7);
  state << 1, 2, 3, 1, 0, 0, 0;
  EXPECT_EQ(sdk::getVector3(state, 0), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(sdk::getQuaternion(state, 3).isApprox(Eigen::Quaterniond::Identity()));
  EXPECT_DOUBLE_EQ(sdk::clipUnit(2.0), 1.0);
  EXPECT_DOUBLE_EQ(sdk::clipNorm(Eigen::Vector2d(3, 4), 1.0).norm(), 1.0);
  EXPECT_NEAR(sdk::wrapAngle(2.5 * M_PI), 0.5 * M_PI, 1e-12);
  EXPECT_EQ(&sdk::setBaseAction, &kit::setBaseAction);
  EXPECT_EQ(&sdk::setEeAction, &kit::setEeAction);
}

}  // namespace
