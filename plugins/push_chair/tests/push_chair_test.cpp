// PushChair-v0 (plugins/push_chair): chair ids and splits, generated URDFs,
// reset placement, reward stages, success conditions one by one, the robot
// mask and the target marker on real renders, the random policy, the
// PartNet-Mobility loader on a hand-made fixture (tests/partnet_chairs). The
// generator, loader and reward are checked directly (the family's objects
// library and header); everything else runs the real plugin.
#include <gtest/gtest.h>

#include <manibench/config.hpp>
#include <manibench/environment.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "push_chair.hpp"
#include "test_env.hpp"

namespace {

namespace mb = manibench;
namespace pc = push_chair;
using L = pc::ObservationLayout;

const std::string kFixture = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/plugins/push_chair/tests/partnet_chairs";

std::unique_ptr<mb::Environment> makeEnv(const std::vector<std::string>& overrides = {}) {
  return mb::testing::makeEnvironment("PushChair-v0", overrides);
}

double calcTilt(const Eigen::VectorXd& s) {
  const Eigen::Quaterniond q(s[L::kChairPose + 3], s[L::kChairPose + 4], s[L::kChairPose + 5], s[L::kChairPose + 6]);
  return std::acos(std::clamp((q * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0));
}

TEST(PushChair, SameIdSameChairDifferentIdsDiffer) {
  EXPECT_EQ(pc::generateChair("3004").urdf, pc::generateChair("3004").urdf);
  EXPECT_EQ(pc::generateChair("3104").urdf, pc::generateChair("3104").urdf);
  std::set<std::string> urdfs;
  for (const std::string split : {"train", "test"})
    for (const std::string& id : pc::listGeneratedChairs(split)) urdfs.insert(pc::generateChair(id).urdf);
  EXPECT_EQ(urdfs.size(), 40u);
  EXPECT_THROW(pc::generateChair("3030"), manibench::sdk::Error);
  EXPECT_THROW(pc::generateChair("chair"), manibench::sdk::Error);
  EXPECT_THROW(pc::listGeneratedChairs("val"), manibench::sdk::Error);
}

TEST(PushChair, SplitsAreDisjointLargeEnoughAndTheTestSplitHoldsUnseenDesigns) {
  const auto env = makeEnv();
  const std::vector<std::string> train = env->listObjects("train"), test = env->listObjects("test");
  EXPECT_GE(train.size(), 26u);
  EXPECT_GE(test.size(), 10u);
  for (const std::string& id : test) EXPECT_EQ(std::count(train.begin(), train.end(), id), 0) << id;
  std::set<pc::BackrestShape> train_backs, test_backs;
  std::set<pc::ArmrestType> train_arms, test_arms;
  double train_width = 0, test_width = 0;
  for (const std::string& id : train) {
    const pc::ChairParams p = pc::getChairParams(id);
    train_backs.insert(p.backrest);
    train_arms.insert(p.armrest);
    train_width = std::max(train_width, p.seat_width);
  }
  for (const std::string& id : test) {
    const pc::ChairParams p = pc::getChairParams(id);
    test_backs.insert(p.backrest);
    test_arms.insert(p.armrest);
    test_width = std::max(test_width, p.seat_width);
  }
  for (const pc::BackrestShape b : test_backs) EXPECT_EQ(train_backs.count(b), 0u) << pc::toString(b);
  for (const pc::ArmrestType a : test_arms) {
    if (a != pc::ArmrestType::kNone) {
      EXPECT_EQ(train_arms.count(a), 0u) << pc::toString(a);
    }
  }
  EXPECT_GT(test_width, train_width);
}

// Sizes of real office chairs (asset-facts.md), 5 casters, at most 20 joints.
TEST(PushChair, GeneratedChairsHaveRealisticSizesAndJoints) {
  for (const std::string split : {"train", "test"})
    for (const std::string& id : pc::listGeneratedChairs(split)) {
      const pc::ChairParams p = pc::getChairParams(id);
      const pc::ChairModel m = pc::generateChair(id);
      const double across = 2 * (p.base_radius + 0.02);
      EXPECT_GE(across, 0.66 - 1e-9) << id;
      EXPECT_LE(across, 0.71 + 1e-9) << id;
      EXPECT_GE(p.seat_width, 0.38) << id;
      EXPECT_LE(p.seat_width, 0.56) << id;
      EXPECT_EQ(m.wheel_links.size(), 5u) << id;
      EXPECT_GE(m.joints.size(), 11u) << id << ": 5 swivels, 5 wheels, the seat";
      EXPECT_LE(m.joints.size(), std::size_t(pc::kMaxChairJoints)) << id;
      EXPECT_LE(m.height, 1.2 + 1e-9) << id;
      EXPECT_GT(m.height, p.seat_height + 0.3) << id;
    }
}

// Every generated chair loads and stands on its wheels.
TEST(PushChair, GeneratedUrdfsLoadAndStand) {
  const auto env = makeEnv();
  for (const std::string split : {"train", "test"})
    for (const std::string& id : env->listObjects(split)) {
      ASSERT_NO_THROW(env->reset(id, 0)) << id;
      const Eigen::VectorXd& obs = env->getObservation();
      ASSERT_EQ(obs.size(), Eigen::Index(L::kDim));
      EXPECT_TRUE(obs.allFinite()) << id;
      EXPECT_NEAR(obs[L::kChairPose + 2], 0.0, 1e-9) << id << ": root frame on the floor";
      EXPECT_EQ(env->getScene().getJoints(env->getScene().findArticulation("chair")).size(),
                pc::generateChair(id).joints.size());
    }
  EXPECT_THROW(env->reset("3999", 0), std::exception);
}

TEST(PushChair, ResetPlacesChairAndRobotAtTheirDistancesFacingTheChair) {
  const auto env = makeEnv();
  const std::string object = env->listObjects("train")[2];
  std::set<double> bearings;
  for (uint64_t seed = 0; seed < 12; ++seed) {
    env->reset(object, seed);
    const Eigen::VectorXd s = env->getObservation();
    const Eigen::Vector2d target = s.segment<2>(L::kTarget), chair = s.segment<2>(L::kChairPose);
    const Eigen::Vector2d base = s.segment<2>(mb::testing::getObservationOffset(*env, "base_position"));
    EXPECT_EQ(s[L::kTarget + 2], 0.0) << "on the ground";
    EXPECT_GE((chair - target).norm(), 0.8) << seed;
    EXPECT_LE((chair - target).norm(), 1.2) << seed;
    EXPECT_GE((base - chair).norm(), 0.8) << seed;
    EXPECT_LE((base - chair).norm(), 1.2) << seed;
    const double heading = s[mb::testing::getObservationOffset(*env, "base_yaw")];
    EXPECT_GT((chair - base).normalized().dot(Eigen::Vector2d(std::cos(heading), std::sin(heading))),
              std::cos(0.051 * M_PI));
    EXPECT_LT(calcTilt(s), 1e-9);
    EXPECT_TRUE(s.segment<3>(L::kChairVelocity).isZero());
    EXPECT_NEAR(s[mb::testing::getObservationOffset(*env, "joint_positions") + 3], 0.9, 1e-9) << "lift at 0.9 m";
    bearings.insert(std::atan2(chair.y() - target.y(), chair.x() - target.x()));
  }
  EXPECT_GE(bearings.size(), 10u) << "the placement is randomized";
  mb::testing::expectSameStartAfterAnotherObject(*env, object, env->listObjects("test").back());
}

TEST(PushChair, EveryRewardStageStrictlyExceedsTheOneBefore) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  auto sample = [&](int stage) {
    pc::RewardInput in;
    in.ee_distance = stage == 1 ? pc::kNearDistance + 3 * u(rng) : pc::kNearDistance * u(rng);
    in.target_distance = stage == 3 ? pc::kTargetRadius * u(rng) * 0.99999 : pc::kTargetRadius + 3 * u(rng);
    in.speed = 3 * u(rng);
    in.angular_speed = 3 * u(rng);
    in.speed_to_target = (2 * u(rng) - 1) * in.speed;
    in.tilt = (stage == 1 && u(rng) < 0.3 ? M_PI : pc::kFallenTilt * 0.99999) * u(rng);
    in.action_norm = 5 * u(rng);
    in.is_static = u(rng) < 0.5;
    return in;
  };
  double best[4] = {0, -INFINITY, -INFINITY, -INFINITY}, worst[4] = {0, INFINITY, INFINITY, INFINITY};
  for (int i = 0; i < 30000; ++i)
    for (int stage = 1; stage <= 3; ++stage) {
      const pc::RewardInput in = sample(stage);
      ASSERT_EQ(pc::calcRewardStage(in), stage);
      const double r = pc::calcStagedReward(in);
      best[stage] = std::max(best[stage], r);
      worst[stage] = std::min(worst[stage], r);
    }
  EXPECT_LT(best[1], worst[2]);
  EXPECT_LT(best[2], worst[3]);
  // a fallen chair is back in stage 1, whatever else holds, with the -5 term
  pc::RewardInput fallen;
  fallen.ee_distance = 0.01;
  fallen.target_distance = 0.01;
  fallen.tilt = pc::kFallenTilt;
  EXPECT_EQ(pc::calcRewardStage(fallen), 1);
  EXPECT_NEAR(pc::calcStagedReward(fallen), 2 * (-10.0 - 0.1 - std::log(0.1) - 5.0 - 0.2 * pc::kFallenTilt), 1e-9);
  // within a stage: closer, faster towards the target, stiller, upright is better
  pc::RewardInput a, b;
  a.ee_distance = 0.5;
  b.ee_distance = 1.0;
  EXPECT_GT(pc::calcStagedReward(a), pc::calcStagedReward(b));
  a.ee_distance = b.ee_distance = 0.05;
  a.speed_to_target = a.speed = 0.3;
  EXPECT_GT(pc::calcStagedReward(a), pc::calcStagedReward(b));
  b = a;
  b.target_distance = 0.5;
  EXPECT_GT(pc::calcStagedReward(b), pc::calcStagedReward(a)) << "closer to the target";
  a.target_distance = b.target_distance = 0.05;
  a.speed = 0;
  b.speed = 0.3;
  EXPECT_GT(pc::calcStagedReward(a), pc::calcStagedReward(b));
  a.is_static = true;
  EXPECT_NEAR(pc::calcStagedReward(a) - pc::calcStagedReward(pc::RewardInput{a.ee_distance, a.target_distance, 0, 0, 0,
                                                                                  0, 0, false}),
              4.0, 1e-12);
  b = a;
  b.tilt = 0.1;
  EXPECT_NEAR(pc::calcStagedReward(a) - pc::calcStagedReward(b), 2 * 0.2 * 0.1, 1e-12);
}

// Puts the chair's root at `xy` (yaw 0), still, with the robot where reset put it.
void placeChair(mb::Environment& env, const Eigen::Vector2d& xy, double roll = 0) {
  mb::Scene& scene = env.updScene();
  const int chair = scene.findArticulation("chair");
  mb::Pose pose;
  pose.position = Eigen::Vector3d(xy.x(), xy.y(), 0);
  pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
  scene.setRootPose(chair, pose);
  scene.setRootTwist(chair, mb::Twist());
}

TEST(PushChair, SuccessNeedsTheChairCloseStaticAndUprightForTenSteps) {
  const auto env = makeEnv();
  const std::string object = env->listObjects("train").front();
  env->reset(object, 3);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(env->getControllerDescription().action_dim);
  mb::StepResult r = env->step(zero);
  ASSERT_EQ(r.flags.size(), 4u);
  EXPECT_FALSE(r.flags[0]) << "0.8-1.2 m from the target";
  EXPECT_GE(r.values[0], 0.8 - 0.01);
  EXPECT_TRUE(r.flags[1]) << "a chair left alone is static";
  EXPECT_TRUE(r.flags[2]) << "and upright";
  EXPECT_FALSE(r.success);
  // At 8 cm from the target: close, static, upright; success after 10 steps.
  env->reset(object, 3);
  placeChair(*env, Eigen::Vector2d(0.08, 0));
  uint32_t steps = 0;
  do {
    r = env->step(zero);
    ++steps;
    EXPECT_TRUE(r.flags[0]) << steps;
    EXPECT_NEAR(r.values[0], 0.08, 0.01);
    EXPECT_TRUE(r.flags[1]) << steps;
    EXPECT_TRUE(r.flags[2]) << steps;
  } while (!r.success && steps < 30);
  EXPECT_TRUE(r.success);
  EXPECT_EQ(steps, 10u) << "success after 10 consecutive steps";
  EXPECT_EQ(r.values[3], 10.0);
  // 20 cm away: not close, never a success.
  env->reset(object, 3);
  placeChair(*env, Eigen::Vector2d(0, 0.2));
  for (int i = 0; i < 12; ++i) r = env->step(zero);
  EXPECT_FALSE(r.flags[0]);
  EXPECT_FALSE(r.success);
  // At the target but lying on its side: not upright, never a success, and
  // the reward is stage 1 with the fallen penalty.
  env->reset(object, 3);
  placeChair(*env, Eigen::Vector2d(0, 0), M_PI / 2);
  for (int i = 0; i < 12; ++i) r = env->step(zero);
  EXPECT_FALSE(r.flags[2]);
  EXPECT_GT(r.values[2], pc::kUprightTilt);
  EXPECT_FALSE(r.success);
  EXPECT_LT(r.reward, 2 * (-10.0 - 5.0));
  // Sliding through the target at 0.5 m/s: close but not static.
  env->reset(object, 3);
  placeChair(*env, Eigen::Vector2d(-0.05, 0));
  mb::Twist twist;
  twist.linear = Eigen::Vector3d(0.5, 0, 0);
  env->updScene().setRootTwist(env->getScene().findArticulation("chair"), twist);
  r = env->step(zero);
  EXPECT_TRUE(r.flags[0]);
  EXPECT_FALSE(r.flags[1]);
  EXPECT_GT(r.values[1], 0.1);
}

// Short episodes: random flailing is the slowest thing to simulate.
TEST(PushChair, RandomPolicyNeverSucceeds) {
  const auto env = makeEnv({"episode.max_steps=40"});
  std::mt19937_64 rng(11);
  const std::vector<std::string> objects = env->listObjects("train");
  for (uint64_t seed = 0; seed < 2; ++seed) {
    env->reset(objects[seed * 7 % objects.size()], seed);
    const mb::StepResult r = mb::testing::runRandomEpisode(
        *env, rng, [&](const mb::StepResult&) { EXPECT_TRUE(env->getObservation().allFinite()); });
    EXPECT_FALSE(r.success) << "seed " << seed;
    EXPECT_FALSE(r.flags[0]) << "seed " << seed;
  }
}

// ABI 1.2 episode state: the task keeps nothing per step beyond the scene
// and the SDK's hold count (placement, target and joint dynamics are reset
// choices, re-derived from the seed), so a saved state continues bit for
// bit in a fresh environment that was on another chair.
TEST(PushChair, RestoringAStateContinuesBitIdentically) {
  const auto env = makeEnv();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::VectorXd> actions(50, Eigen::VectorXd(env->getControllerDescription().action_dim));
  for (Eigen::VectorXd& a : actions)
    for (Eigen::Index i = 0; i < a.size(); ++i) a[i] = u(rng);
  env->reset("3104", 9);
  for (int k = 0; k < 20; ++k) env->step(actions[k]);
  const std::vector<uint8_t> blob = env->saveState();
  std::vector<mb::StepResult> first;
  std::vector<Eigen::VectorXd> observations;
  for (int k = 20; k < 50; ++k) {
    first.push_back(env->step(actions[k]));
    observations.push_back(env->getObservation());
  }
  const auto fresh = makeEnv();
  fresh->reset("3000", 1);
  fresh->restoreState(blob);
  for (int k = 20; k < 50; ++k) {
    const mb::StepResult r = fresh->step(actions[k]);
    ASSERT_EQ(r.reward, first[k - 20].reward) << "step " << k;
    ASSERT_EQ(r.values, first[k - 20].values) << "step " << k;
    ASSERT_EQ(fresh->getObservation(), observations[k - 20]) << "step " << k;
  }
}

TEST(PushChair, InfoPrintsTheStateLayoutAndObjectsListsTheSplits) {
  const mb::testing::CommandResult info = mb::testing::runCli({"info", "PushChair-v0"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  for (const std::string segment : {"chair_pose", "chair_joint_positions", "seat_top", "target", "right_tcp"})
    EXPECT_NE(info.out.find(segment), std::string::npos) << segment << "\n" << info.out;
  const mb::testing::CommandResult test = mb::testing::runCli({"objects", "PushChair-v0", "--split", "test", "--ids"});
  ASSERT_EQ(test.exit_code, 0) << test.err;
  std::istringstream lines(test.out);
  int count = 0;
  for (std::string id; std::getline(lines, id); ++count) EXPECT_EQ(id.rfind("31", 0), 0u) << id;
  EXPECT_EQ(count, 10);
  // the fixed-object environment of one chair (the host's rule)
  const mb::testing::CommandResult fixed = mb::testing::runCli({"objects", "PushChair_3100-v0", "--ids"});
  ASSERT_EQ(fixed.exit_code, 0) << fixed.err;
  EXPECT_EQ(fixed.out, "3100\n");
  const auto env = makeEnv();
  uint32_t total = 0;
  for (const mb::sdk::Segment& s : env->calcPolicyLayout(mb::ObservationMode::State).observation_segments)
    total += s.size;
  EXPECT_EQ(total, L::kDim);
  EXPECT_EQ(env->getTaskDescription().agent_state_dim, L::kAgentDim);
}

TEST(PushChair, ExpertRefusesOtherControllers) {
  const auto env = makeEnv();  // default controller mobile_panda
  try {
    mb::PolicyInstance policy(mb::testing::getBuildTreeRegistry(), "push_chair_expert", "",
                              env->calcPolicyLayout(mb::ObservationMode::State));
    FAIL() << "expected a refusal";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("mobile_panda_ee"), std::string::npos) << e.what();
  }
}

std::string calcProbeCamera(const std::string& name, const Eigen::Vector3d& eye, const Eigen::Vector3d& direction) {
  const Eigen::Vector3d d = direction.normalized();
  const double pitch = -std::asin(d.z()), yaw = std::atan2(d.y(), d.x());
  std::ostringstream out;
  out.precision(17);
  out << "{name: " << name << ", pose: {position: [" << eye.x() << ", " << eye.y() << ", " << eye.z()
      << "], rpy: [0, " << pitch << ", " << yaw << "]}, width: 48, height: 48, fovy: 0.5, near: 0.05}";
  return out.str();
}

// B.3 on real renders: one mask (robot); a camera looking down at the
// target sees the red marker there (visual only: the chair placed on it
// stays on the floor) and no robot; one looking down at the base sees the
// robot mask.
TEST(PushChair, TargetMarkerIsVisibleAndTheRobotMaskCoversTheRobot) {
  const auto state_env = makeEnv();
  const std::string object = state_env->listObjects("test").front();
  state_env->reset(object, 0);
  const Eigen::VectorXd s = state_env->getObservation();
  const Eigen::Vector3d target = s.segment<3>(L::kTarget);
  const uint32_t at = mb::testing::getObservationOffset(*state_env, "base_position");
  const Eigen::Vector3d base(s[at], s[at + 1], 0);
  const std::string cameras = "cameras=[" +
                              calcProbeCamera("at_target", target + Eigen::Vector3d(0.01, 0, 1.0),
                                              Eigen::Vector3d(-0.01, 0, -1.0)) +
                              ", " +
                              calcProbeCamera("at_robot", base + Eigen::Vector3d(0.01, 0, 3.0),
                                              Eigen::Vector3d(-0.01, 0, -1.0)) +
                              "]";
  const auto env = makeEnv({"observation.mode=rgbd", cameras});
  env->reset(object, 0);
  const mb::VisualObservation& v = env->getVisualObservation();
  ASSERT_EQ(v.camera_count, 2u);
  ASSERT_EQ(v.mask_count, 1u);
  const uint32_t cams = v.camera_count;
  auto robot = [&](uint32_t camera, uint32_t row, uint32_t col) {
    return v.masks[(row * v.width + col) * cams + camera] != 0;
  };
  auto rgb = [&](uint32_t camera, uint32_t row, uint32_t col, int c) {
    return v.rgb[((row * v.width + col) * cams + camera) * 3 + c];
  };
  int red = 0, robot_pixels = 0;
  for (uint32_t row = 0; row < v.height; ++row)
    for (uint32_t col = 0; col < v.width; ++col) {
      red += rgb(0, row, col, 0) > 0.5 && rgb(0, row, col, 1) < 0.3 && rgb(0, row, col, 2) < 0.3;
      EXPECT_FALSE(robot(0, row, col));
      robot_pixels += robot(1, row, col);
    }
  EXPECT_GT(red, 100) << "the marker fills the middle of the view";
  EXPECT_GT(robot_pixels, 100);
  // no collision: a chair at the target stands on the floor, not on the disc
  placeChair(*env, target.head<2>());
  env->step(Eigen::VectorXd::Zero(env->getControllerDescription().action_dim));
  const int chair = env->getScene().findArticulation("chair");
  EXPECT_NEAR(env->getScene().getLinkPose(env->getScene().findLink(chair, "base")).position.z(), 0.0, 2e-3);
}

// ---- PartNet-Mobility chairs (tests/partnet_chairs, hand-made) -----------------

TEST(PushChairPartNet, LoaderFindsWheelsCastersAndTheSeat) {
  const pc::ChairModel m = pc::loadPartNetChair(kFixture, "200001", 0.8);
  EXPECT_EQ(m.wheel_links, (std::vector<std::string>{"wheel_0", "wheel_1", "wheel_2", "wheel_3", "wheel_4"}));
  EXPECT_EQ(m.seat_link, "link_1");
  EXPECT_NE(m.urdf.find("<link name=\"wheel_3\">"), std::string::npos);
  EXPECT_EQ(m.urdf.find("\"link_3\""), std::string::npos) << "every reference to a wheel renamed";
  int swivels = 0, wheels = 0, seats = 0;
  for (const pc::ChairJoint& j : m.joints) {
    if (j.role == pc::JointRole::kCasterSwivel) {
      ++swivels;
      EXPECT_NEAR(j.lever, 0.03, 1e-6) << j.name << ": the trail";
    }
    if (j.role == pc::JointRole::kWheel) {
      ++wheels;
      EXPECT_NEAR(j.lever, 0.03, 1e-3) << j.name << ": the wheel's radius";
    }
    seats += j.role == pc::JointRole::kSeat;
  }
  EXPECT_EQ(swivels, 5);
  EXPECT_EQ(wheels, 5);
  EXPECT_EQ(seats, 1);
  // designed Z-up at 0.8 scale: wheels' bottom at 0, backrest top at 0.99 m
  EXPECT_NEAR(m.seat_top.norm(), 0.47 - 0.39, 1e-6) << "the cushion's top above the swivel, not the backrest's";
  EXPECT_NEAR(m.root_height, 0.0, 1e-6);
  EXPECT_NEAR(m.height, 0.4 + 0.07 + 0.05 + 0.42, 1e-6);
  EXPECT_NEAR(m.footprint_radius, std::hypot(0.32 + 0.03 + 0.03, 0.012), 1e-4) << "the wheels' outer edge";
  EXPECT_FALSE(m.surface.empty());
}

// Any number of casters: 200003 stands on four, its wheels wheel_0..3
// (the task's material `wheel_*` gives them all v1's wheel friction).
TEST(PushChairPartNet, AChairOnFourCastersLoads) {
  const pc::ChairModel m = pc::loadPartNetChair(kFixture, "200003", 0.8);
  EXPECT_EQ(m.wheel_links, (std::vector<std::string>{"wheel_0", "wheel_1", "wheel_2", "wheel_3"}));
  int swivels = 0;
  for (const pc::ChairJoint& j : m.joints) swivels += j.role == pc::JointRole::kCasterSwivel;
  EXPECT_EQ(swivels, 4);
}

TEST(PushChairPartNet, BadFoldersGetClearErrors) {
  // A chair whose semantics.txt names no seat, and one with a link that
  // already has a wheel's name but is not labelled a wheel.
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "push_chair_bad_folders";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  for (const char* id : {"1", "2"})
    std::filesystem::copy(kFixture + "/200001", dir / id, std::filesystem::copy_options::recursive);
  auto rewrite = [&](const std::filesystem::path& file, const std::string& from, const std::string& to) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    std::string s = text.str();
    for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
      s.replace(at, from.size(), to);
    std::ofstream(file) << s;
  };
  rewrite(dir / "1" / "semantics.txt", " seat", " cushion");
  rewrite(dir / "2" / "mobility.urdf", "\"link_0\"", "\"wheel_7\"");
  rewrite(dir / "2" / "semantics.txt", "link_0 ", "wheel_7 ");
  mb::testing::expectMentions(
      mb::testing::catchMessage<manibench::sdk::Error>([&] { pc::loadPartNetChair(dir.string(), "1", 0.8); }),
      {(dir / "1").string(), "labels no link 'seat'"});
  mb::testing::expectMentions(
      mb::testing::catchMessage<manibench::sdk::Error>([&] { pc::loadPartNetChair(dir.string(), "2", 0.8); }),
      {(dir / "2").string(), "link 'wheel_7' is not labelled a wheel"});
  EXPECT_THROW(pc::loadPartNetChair(kFixture, "999999", 0.8), manibench::sdk::Error);
  std::filesystem::remove_all(dir);
}

// The folder replaces the generator; a chair the family cannot use is
// skipped with a warning, as in every family (kit/catalog.hpp).
TEST(PushChairPartNet, FolderReplacesTheGeneratorAndTheChairStandsAndRolls) {
  const auto env = makeEnv({"task.partnet_dir=" + kFixture});
  EXPECT_EQ(env->listObjects("test"), std::vector<std::string>{"200002"});
  EXPECT_EQ(env->listObjects("train"), (std::vector<std::string>{"200001", "200003"}));
  // the four-caster chair stands on its wheels too
  env->reset("200003", 2);
  const Eigen::VectorXd zero4 = Eigen::VectorXd::Zero(env->getControllerDescription().action_dim);
  const Eigen::VectorXd start4 = env->getObservation();
  for (int i = 0; i < 40; ++i) env->step(zero4);
  EXPECT_LT((env->getObservation().segment<3>(L::kChairPose) - start4.segment<3>(L::kChairPose)).norm(), 0.01);
  EXPECT_LT(calcTilt(env->getObservation()), 0.02);
  env->reset("200001", 2);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(env->getControllerDescription().action_dim);
  const Eigen::VectorXd start = env->getObservation();
  for (int i = 0; i < 40; ++i) env->step(zero);  // 2 s alone
  const Eigen::VectorXd rest = env->getObservation();
  EXPECT_LT((rest.segment<3>(L::kChairPose) - start.segment<3>(L::kChairPose)).norm(), 0.01);
  EXPECT_LT(calcTilt(rest), 0.02);
  // given 0.4 m/s it rolls on its wheels, upright
  mb::Twist twist;
  twist.linear = Eigen::Vector3d(0.4, 0, 0);
  env->updScene().setRootTwist(env->getScene().findArticulation("chair"), twist);
  for (int i = 0; i < 10; ++i) env->step(zero);
  const Eigen::VectorXd rolled = env->getObservation();
  // sliding on its wheels (friction 1) it would stop within 1 cm
  EXPECT_GT(rolled[L::kChairPose] - rest[L::kChairPose], 0.015);
  EXPECT_LT(calcTilt(rolled), 0.05 * M_PI);
}

}  // namespace
