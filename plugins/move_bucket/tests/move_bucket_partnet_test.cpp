// PartNet-Mobility buckets (plugins/move_bucket/partnet_loader.cpp) on the
// hand-made fixture plugins/move_bucket/tests/fixtures/partnet_buckets (an
// octagonal bucket with a handle, a square one without; sizes in its
// make_fixture.py): the splits, the bucket frame, rim, floor and handle
// measured from the meshes, errors naming the file, and the task on them
// (standing still, deterministic).
#include <gtest/gtest.h>

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "move_bucket.hpp"
#include "test_env.hpp"

namespace {

namespace mb = manibench;
namespace bk = move_bucket;
using L = bk::ObservationLayout;

const std::string kFixture =
    std::string(MANIBENCH_TEST_SOURCE_DIR) + "/plugins/move_bucket/tests/fixtures/partnet_buckets";
constexpr double kScale = 0.3;  // the fixture's raw units are metres / 0.3
constexpr double kTol = 1e-5;   // the OBJ files hold 6 decimals of raw units

TEST(MoveBucketPartNet, SplitsComeFromTestTxt) {
  EXPECT_EQ(manibench::kit::partnet::listObjectIds(kFixture, "train"), std::vector<std::string>{"200001"});
  EXPECT_EQ(manibench::kit::partnet::listObjectIds(kFixture, "test"), std::vector<std::string>{"200002"});
}

// ManiSkill v1 scaled its buckets by 0.3, and its bucket 4018 by 0.35: a
// folder of v1's own ids gets v1's sizes (task.partnet_scale 0, the
// default), from the shipped facts (assets/objects/move_bucket.yaml), not
// from code; task.partnet_scale replaces them all.
TEST(MoveBucketPartNet, V1ScalesItsBucketsAsV1Did) {
  const manibench::kit::ObjectFacts v1(manibench::sdk::Config(""), "move_bucket");
  EXPECT_EQ(v1.calcScale("4018"), 0.35);
  for (const char* id : {"4000", "4019", "100461", "200001"}) EXPECT_EQ(v1.calcScale(id), 0.3) << id;
  const manibench::kit::ObjectFacts fixed(manibench::sdk::Config("partnet_scale: 0.5"), "move_bucket");
  EXPECT_EQ(fixed.calcScale("4018"), 0.5);
}

TEST(MoveBucketPartNet, RimFloorAndHandleAreMeasuredInTheBucketFrame) {
  const bk::BucketModel octagon = bk::loadPartNetBucket(kFixture, "200001", kScale);
  // 0.28 m tall, apothem 0.15 at the rim (flat faces on x and y), walls 7 mm,
  // bottom 10 mm; the frame's origin at the bottom's centre, z up.
  EXPECT_NEAR(octagon.rim_height, 0.28, kTol);
  EXPECT_NEAR(octagon.rim_outer_y, 0.15, kTol);
  EXPECT_NEAR(octagon.rim_outer_x, 0.15, kTol);
  EXPECT_NEAR(octagon.rim_inner_y, 0.143, kTol);
  EXPECT_NEAR(octagon.floor_height, 0.010, kTol);
  EXPECT_TRUE(octagon.lower.isApprox(Eigen::Vector3d(-0.15, -0.15, 0), kTol)) << octagon.lower.transpose();
  EXPECT_TRUE(octagon.upper.isApprox(Eigen::Vector3d(0.15, 0.15, 0.28), kTol))
      << octagon.upper.transpose() << ": the handle (out to 0.169 m) is not the body";
  EXPECT_EQ(octagon.bail_joint, "joint_0");
  EXPECT_DOUBLE_EQ(octagon.bail_lower, -2.0);
  EXPECT_DOUBLE_EQ(octagon.bail_upper, 2.0);
  EXPECT_EQ(octagon.body_link, "move_bucket_frame");
  EXPECT_NE(octagon.urdf.find("<link name=\"move_bucket_frame\""), std::string::npos);
  EXPECT_LT(octagon.urdf.find("<link name=\"move_bucket_frame\""), octagon.urdf.find("<link name=\"base\""))
      << "the frame link comes first";
  EXPECT_TRUE(octagon.files.empty()) << "meshes stay where they are";
  EXPECT_EQ(octagon.base_dir, kFixture + "/200001");
  ASSERT_GT(octagon.surface_points.size(), 50u);
  for (const Eigen::Vector3d& p : octagon.surface_points)
    EXPECT_TRUE((p.array() >= octagon.lower.array() - kTol).all() && (p.array() <= octagon.upper.array() + kTol).all());

  const bk::BucketModel square = bk::loadPartNetBucket(kFixture, "200002", kScale);
  EXPECT_NEAR(square.rim_height, 0.26, kTol);
  EXPECT_NEAR(square.rim_outer_y, 0.13, kTol);
  EXPECT_NEAR(square.rim_inner_y, 0.124, kTol);
  EXPECT_NEAR(square.floor_height, 0.012, kTol);
  EXPECT_TRUE(square.bail_joint.empty());
  // The reward's surface points cover the faces, not only the corners the
  // square's coarse mesh has: some lie near the middle of the rim's side.
  ASSERT_EQ(square.surface_points.size(), 1024u);
  double nearest = 1;
  for (const Eigen::Vector3d& p : square.surface_points)
    nearest = std::min(nearest, (p - Eigen::Vector3d(0, 0.13, 0.2)).norm());
  EXPECT_LT(nearest, 0.02);
  // Another scale scales every length.
  EXPECT_NEAR(bk::loadPartNetBucket(kFixture, "200002", 0.6).rim_height, 0.52, 2 * kTol);
}

TEST(MoveBucketPartNet, ErrorsNameTheFileAndTheProblem) {
  mb::testing::expectMentions(
      mb::testing::catchMessage<manibench::sdk::Error>([] { bk::loadPartNetBucket(kFixture, "999", kScale); }),
      {kFixture + "/999/mobility.urdf"});
  // A face naming a vertex that is not there.
  const std::string dir = ::testing::TempDir() + "move_bucket_partnet_block";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::filesystem::copy(kFixture + "/200002", dir + "/2", std::filesystem::copy_options::recursive);
  std::ofstream(dir + "/2/textured_objs/original-3.obj", std::ios::app) << "f 1 2 99\n";
  mb::testing::expectMentions(
      mb::testing::catchMessage<manibench::sdk::Error>([&] { bk::loadPartNetBucket(dir, "2", kScale); }),
      {dir + "/2/textured_objs/original-3.obj", "bad face index '99'"});
  // A solid block: no rim's inside, no floor.
  std::filesystem::create_directories(dir + "/1");
  std::ofstream(dir + "/1/mobility.urdf")
      << "<?xml version=\"1.0\"?><robot name=\"block\"><link name=\"base\"/><link name=\"link_0\"><visual>"
         "<geometry><box size=\"1 1 1\"/></geometry></visual></link><joint name=\"joint_0\" type=\"fixed\">"
         "<parent link=\"base\"/><child link=\"link_0\"/></joint></robot>\n";
  mb::testing::expectMentions(
      mb::testing::catchMessage<manibench::sdk::Error>([&] { bk::loadPartNetBucket(dir, "1", kScale); }),
      {dir + "/1/mobility.urdf", "rim's inside"});
  std::filesystem::remove_all(dir);
  // The task refuses a folder that is not one, and a negative scale (0 is
  // the object facts' own).
  auto makeEnvironment = [](std::vector<std::string> overrides) {
    mb::ConfigSources sources;
    sources.overrides = std::move(overrides);
    const mb::ConfigNode config =
        mb::loadTaskConfig(mb::testing::getBuildTreeRegistry(), "MoveBucket-v0", sources);
    mb::Environment env(mb::testing::getBuildTreeRegistry(), "MoveBucket-v0", mb::calcEnvironmentOptions(config));
  };
  mb::testing::expectMentions(
      mb::testing::catchMessage<std::exception>([&] { makeEnvironment({"task.partnet_dir=/no/such/folder"}); }),
      {"task.partnet_dir", "/no/such/folder"});
  mb::testing::expectMentions(mb::testing::catchMessage<std::exception>([&] {
                                makeEnvironment({"task.partnet_dir=" + kFixture, "task.partnet_scale=-0.3"});
                              }),
                              {"task.partnet_scale must be positive (or 0: the object facts' scale"});
}

std::unique_ptr<mb::Environment> makePartNetEnv(std::vector<std::string> overrides = {}) {
  overrides.insert(overrides.begin(), "task.partnet_dir=" + kFixture);
  return mb::testing::makeEnvironment("MoveBucket-v0", overrides);
}

// A bucket the family cannot read is skipped when the split is listed,
// with its reason, once (kit/catalog.hpp), and the others stay usable.
TEST(MoveBucketPartNet, AnUnreadableBucketIsSkippedWithAWarning) {
  const std::string dir = ::testing::TempDir() + "move_bucket_partnet_skip";
  std::filesystem::remove_all(dir);
  std::filesystem::copy(kFixture, dir, std::filesystem::copy_options::recursive);
  std::filesystem::create_directories(dir + "/200009");
  std::ofstream(dir + "/200009/mobility.urdf") << "<robot name=\"cut\">\n";
  ::testing::internal::CaptureStderr();
  const auto env = makePartNetEnv({"task.partnet_dir=" + dir});
  EXPECT_EQ(env->listObjects("train"), std::vector<std::string>{"200001"});
  EXPECT_EQ(env->listObjects("train"), std::vector<std::string>{"200001"});
  const std::string warnings = ::testing::internal::GetCapturedStderr();
  mb::testing::expectMentions(warnings, {"MoveBucket: skipping PartNet bucket 200009 (" + dir + "/200009)"});
  EXPECT_EQ(warnings.find("200009 ("), warnings.rfind("200009 (")) << warnings;
  env->reset("200001", 0);
  std::filesystem::remove_all(dir);
}

// The task on the fixture: the folder replaces the generator; a reset stands
// the bucket on the floor with the ball on its bottom; left alone for a
// second, the bucket stays upright and still, the ball inside, the handle
// at its limit.
TEST(MoveBucketPartNet, TheTaskRunsOnAPartNetFolder) {
  const auto env = makePartNetEnv();
  EXPECT_EQ(env->listObjects("train"), std::vector<std::string>{"200001"});
  EXPECT_EQ(env->listObjects("test"), std::vector<std::string>{"200002"});
  const bk::BucketModel model = bk::loadPartNetBucket(kFixture, "200001", kScale);
  for (uint64_t seed : {0, 1}) {
    env->reset("200001", seed);
    Eigen::VectorXd s = env->getObservation();
    EXPECT_NEAR(s[L::kBucketPose + 2], 0, 1e-9) << "the bottom on the floor";
    EXPECT_EQ(s.segment<4>(L::kBucketRim),
              Eigen::Vector4d(model.rim_height, model.rim_outer_y, model.rim_inner_y, model.rim_outer_x));
    EXPECT_NEAR(s[L::kBallPosition + 2], model.floor_height + bk::kBallRadius, 2e-3);
    EXPECT_TRUE(s[L::kBailJoint] == -2.0 || s[L::kBailJoint] == 2.0) << "the handle folded to a limit";
    const Eigen::Vector3d start = s.segment<3>(L::kBucketPose);
    mb::StepResult r;
    for (int step = 0; step < 20; ++step) r = env->step(Eigen::VectorXd::Zero(20));
    s = env->getObservation();
    EXPECT_LT((s.segment<3>(L::kBucketPose) - start).norm(), 2e-3) << seed;
    EXPECT_EQ(r.flags, (std::vector<uint8_t>{0, 1, 1, 1, 0})) << "upright, static, ball inside";
  }
}

// Determinism holds for loaded buckets too: two environments, the same
// seed and actions, bit-identical observations.
TEST(MoveBucketPartNet, SameSeedSameEpisode) {
  const auto a = makePartNetEnv(), b = makePartNetEnv();
  a->reset("200001", 3);
  b->reset("200002", 0);
  b->reset("200001", 3);
  for (int step = 0; step < 15; ++step) {
    Eigen::VectorXd x(20);
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = std::sin(1.7 * double(step) + double(i));
    ASSERT_EQ(a->step(x).reward, b->step(x).reward) << step;
  }
  EXPECT_EQ(a->getObservation(), b->getObservation());
}

}  // namespace
