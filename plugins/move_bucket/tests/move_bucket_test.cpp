// MoveBucket-v0 through the real plugin (plugins/move_bucket): every bucket
// loads, the observation layout, reset placement (B.2), determinism, the
// success conditions one by one (B.4), the random policy, the expert's
// refusal of other controllers.
#include <gtest/gtest.h>

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>
#include <manibench/plugin_instances.hpp>

#include <cmath>
#include <random>
#include <set>

#include "move_bucket.hpp"
#include "test_env.hpp"

namespace {

namespace mb = manibench;
namespace bk = move_bucket;
using L = bk::ObservationLayout;
using manibench::sdk::kPi;

std::unique_ptr<mb::Environment> makeEnv(const std::vector<std::string>& overrides = {}) {
  return mb::testing::makeEnvironment("MoveBucket-v0", overrides);
}

std::vector<std::string> allBuckets() {
  std::vector<std::string> ids = bk::listGeneratedBuckets("train");
  for (const std::string& id : bk::listGeneratedBuckets("test")) ids.push_back(id);
  return ids;
}

// ---- the task through the real plugin ---------------------------------------------

TEST(MoveBucket, EveryBucketLoadsAndTheLayoutIsTheDocumentedOne) {
  const auto env = makeEnv();
  EXPECT_EQ(env->listObjects("train"), bk::listGeneratedBuckets("train"));
  EXPECT_EQ(env->listObjects("test"), bk::listGeneratedBuckets("test"));
  const mb::TaskDescription& info = env->getTaskDescription();
  EXPECT_EQ(info.observation_dim, L::kDim);
  EXPECT_EQ(info.agent_state_dim, L::kAgentDim);
  EXPECT_EQ(info.masks, std::vector<std::string>{"robot"});
  EXPECT_EQ(info.success_conditions,
            (std::vector<std::string>{"on_platform", "upright", "static", "ball_inside", "success"}));
  EXPECT_EQ(info.max_episode_steps, 200u);
  EXPECT_EQ(info.frame_skip, 5u);
  for (const std::string& id : allBuckets()) {
    ASSERT_NO_THROW(env->reset(id, 1)) << id;
    const Eigen::VectorXd& o = env->getObservation();
    ASSERT_TRUE(o.allFinite()) << id;
    EXPECT_EQ(o.segment<4>(L::kBucketRim), Eigen::Vector4d(bk::generateBucket(id).rim_height,
                                                            bk::generateBucket(id).rim_outer_y,
                                                            bk::generateBucket(id).rim_inner_y,
                                                            bk::generateBucket(id).rim_outer_x))
        << id;
  }
  EXPECT_THROW(env->reset("3200", 0), std::exception);
}

Eigen::Quaterniond getQuat(const Eigen::VectorXd& s, uint32_t at) {
  return Eigen::Quaterniond(s[at], s[at + 1], s[at + 2], s[at + 3]);
}

// B.2 and ManiSkill v1's placement: platform at the origin, the bucket
// upright on the floor 0.8-1.2 m from it at any yaw, the robot 0.6-0.8 m
// from the bucket on its far side, facing it; the ball inside at the
// bottom; a bail folded down to its limit.
TEST(MoveBucket, ResetPlacesBucketRobotBallAndPlatform) {
  const auto env = makeEnv();
  std::set<double> yaws;
  for (uint64_t seed = 0; seed < 16; ++seed) {
    const std::string id = seed % 2 ? "3003" : "3104";  // with a bail, without
    env->reset(id, seed);
    const Eigen::VectorXd s = env->getObservation();
    const Eigen::Vector3d bucket = s.segment<3>(L::kBucketPose), platform = s.segment<3>(L::kPlatformPose);
    const Eigen::Quaterniond q = getQuat(s, L::kBucketPose + 3);
    EXPECT_NEAR(platform.norm(), 0.1, 1e-12) << "the box centre, 0.1 m up at the origin";
    EXPECT_EQ(s.segment<3>(L::kPlatformHalfSize), Eigen::Vector3d(0.3, 0.3, 0.1));
    const double d = bucket.head<2>().norm();
    EXPECT_GE(d, 0.8);
    EXPECT_LE(d, 1.2);
    EXPECT_NEAR(bucket.z(), 0, 1e-3) << "on the floor";
    EXPECT_GT((q * Eigen::Vector3d::UnitZ()).z(), 1 - 1e-6) << "upright";
    yaws.insert(std::round(100 * std::atan2((q * Eigen::Vector3d::UnitX()).y(), (q * Eigen::Vector3d::UnitX()).x())));
    const Eigen::Vector2d base = s.segment<2>(mb::testing::getObservationOffset(*env, "base_position"));
    const double r = (base - bucket.head<2>()).norm();
    EXPECT_GE(r, 0.6);
    EXPECT_LE(r, 0.8);
    const Eigen::Vector2d away = bucket.head<2>().normalized(), to_robot = (base - bucket.head<2>()).normalized();
    EXPECT_GE(away.dot(to_robot), std::cos(0.4 * kPi) - 1e-9) << "the robot on the bucket's far side";
    const double yaw = s[mb::testing::getObservationOffset(*env, "base_yaw")];
    const Eigen::Vector2d heading(std::cos(yaw), std::sin(yaw));
    EXPECT_GE(heading.dot(-to_robot), std::cos(0.05 * kPi) - 1e-9) << "facing the bucket";
    EXPECT_NEAR(s[mb::testing::getObservationOffset(*env, "joint_positions") + 3], 0.5, 1e-9) << "lift";
    const Eigen::Vector3d ball = q.inverse() * (s.segment<3>(L::kBallPosition) - bucket);
    EXPECT_LT(ball.head<2>().norm(), 1e-6);
    EXPECT_NEAR(ball.z(), bk::generateBucket(id).floor_height + bk::kBallRadius, 2e-3);
    const Eigen::Vector4d bail = s.segment<4>(L::kBailJoint);
    ASSERT_EQ(bk::getBucketParams(id).bail, id == "3003");
    if (id == "3003") {
      ASSERT_GT(bail[3], kPi / 2);
      EXPECT_TRUE(bail[0] == bail[2] || bail[0] == bail[3]) << "at a limit";
    } else {
      EXPECT_EQ(bail, Eigen::Vector4d::Zero()) << "no bail";
    }
  }
  EXPECT_GT(yaws.size(), 12u);
}

TEST(MoveBucket, SameSeedSameEpisodeOtherSeedOtherEpisode) {
  const auto a = makeEnv(), b = makeEnv();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::VectorXd> actions(25, Eigen::VectorXd(20));
  for (Eigen::VectorXd& x : actions)
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = u(rng);
  a->reset("3007", 5);
  b->reset("3101", 0);
  b->reset("3007", 5);
  EXPECT_EQ(a->getObservation(), b->getObservation());
  for (const Eigen::VectorXd& x : actions) {
    const mb::StepResult ra = a->step(x), rb = b->step(x);
    ASSERT_EQ(ra.reward, rb.reward);
  }
  EXPECT_EQ(a->getObservation(), b->getObservation()) << "bit-identical";
  b->reset("3007", 6);
  a->reset("3007", 5);
  EXPECT_NE(a->getObservation(), b->getObservation());
}

// At reset the bucket is upright, static and holds the ball, but is not on
// the platform; each condition is reported with its value.
TEST(MoveBucket, SuccessConditionsAreReportedOneByOne) {
  const auto env = makeEnv();
  env->reset("3000", 2);
  const mb::StepResult r = env->step(Eigen::VectorXd::Zero(20));
  ASSERT_EQ(r.flags.size(), 5u);
  EXPECT_EQ(r.flags, (std::vector<uint8_t>{0, 1, 1, 1, 0}));
  EXPECT_GE(r.values[0], 0.8 - 0.01) << "distance to the platform";
  EXPECT_LT(r.values[1], 0.01) << "tilt";
  EXPECT_LT(r.values[2], 0.1) << "speed";
  EXPECT_GT(r.values[3], 0) << "the ball's height in the bucket";
  EXPECT_EQ(r.values[4], 0) << "held steps";
  EXPECT_LT(r.reward, -10) << "first stage";
}

// The random policy (mobile_panda, the default controller) never succeeds:
// the bucket must end up upright on a platform a metre away.
TEST(MoveBucket, RandomPolicyFails) {
  const auto env = makeEnv();
  mb::PolicyInstance random(mb::testing::getBuildTreeRegistry(), "random", "", env->calcPolicyLayout());
  for (uint64_t seed = 0; seed < 3; ++seed) {
    const mb::EpisodeResult r = mb::runEpisode(*env, random, env->listObjects("train")[seed * 7], seed);
    EXPECT_FALSE(r.success) << seed;
    EXPECT_EQ(r.steps, 200u);
    EXPECT_TRUE(env->getObservation().allFinite());
  }
}

TEST(MoveBucket, ExpertRefusesOtherControllersAndTasks) {
  const auto env = makeEnv();  // mobile_panda
  const std::string message = mb::testing::catchMessage<std::exception>([&] {
    mb::PolicyInstance expert(mb::testing::getBuildTreeRegistry(), "move_bucket_expert", "",
                              env->calcPolicyLayout(mb::ObservationMode::State));
  });
  mb::testing::expectMentions(message, {"mobile_panda_ee", "move_bucket_expert"});
}

}  // namespace
