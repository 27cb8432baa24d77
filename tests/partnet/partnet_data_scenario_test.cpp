// The benchmark on real PartNet-Mobility objects, read from the folder that
// MANIBENCH_PARTNET_DIR names (its layout: <dir>/<category>/<id>/, as
// ../shared/partnet holds 15 objects; .ci/run sets it). The dataset's terms
// forbid redistribution, so no PartNet file is in this repository: where
// the variable is unset every test here skips with one line, and the
// hand-made fixtures (tests/fixtures/partnet_*) keep guarding the loaders.
//
// What is checked is what a user with the dataset meets: every object
// loads in each family it belongs to (the oven is skipped for its reason),
// the targets found per object, each expert's success, a
// demonstration on a real object replayed bit for bit, a point cloud in
// the colours of the meshes' textures.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace manibench {
namespace {

using testing::runCli;

// The category folder, or "" (and the test skips) without the dataset.
std::string findCategory(const std::string& category) {
  const char* dir = std::getenv("MANIBENCH_PARTNET_DIR");
  if (dir == nullptr || *dir == '\0') return "";
  return (std::filesystem::path(dir) / category).string();
}

#define REQUIRE_CATEGORY(var, category)                                                      \
  const std::string var = findCategory(category);                                            \
  if (var.empty()) GTEST_SKIP() << "MANIBENCH_PARTNET_DIR is unset (no PartNet-Mobility data)"; \
  if (!std::filesystem::is_directory(var)) GTEST_SKIP() << var << " is not there"

// `manibench objects TASK --check` on one category folder.
testing::CommandResult checkObjects(const std::string& task, const std::string& folder) {
  return runCli({"objects", task, "--check", "--set", "task.partnet_dir=" + folder});
}

TEST(PartNetData, EveryCabinetLoadsWithItsDoorsAndDrawers) {
  REQUIRE_CATEGORY(folder, "StorageFurniture");
  const auto drawers = checkObjects("OpenCabinetDrawer-v0", folder);
  EXPECT_EQ(drawers.exit_code, 0) << drawers.out << drawers.err;
  EXPECT_NE(drawers.out.find("6 of 6 objects loaded"), std::string::npos) << drawers.out;
  // 47578 has four drawers with handles; 45940 names its handles only in
  // result.json (its URDF's visuals are unnamed).
  EXPECT_NE(drawers.out.find("4 targets 47578_link_0 47578_link_1 47578_link_2 47578_link_3"), std::string::npos)
      << drawers.out;
  EXPECT_NE(drawers.out.find("1 target 45940_link_2"), std::string::npos) << drawers.out;
  const auto doors = checkObjects("OpenCabinetDoor-v0", folder);
  EXPECT_EQ(doors.exit_code, 0) << doors.out << doors.err;
  EXPECT_NE(doors.out.find("7 of 7 objects loaded"), std::string::npos) << doors.out;
  EXPECT_NE(doors.out.find("2 targets 45940_link_0 45940_link_1"), std::string::npos) << doors.out;
  // Flat panels are thin solids now: every collision mesh is a piece
  // (41083: 97 visuals, 97 collision meshes, 20 of them planar).
  EXPECT_NE(doors.out.find("41083          loaded: 4 movable joints, 2 targets 41083_link_0 41083_link_1, 97 "
                           "collision pieces"),
            std::string::npos)
      << doors.out;
}

TEST(PartNetData, TheOvenIsSkippedBecauseNoMovingLinkHasAHandle) {
  REQUIRE_CATEGORY(folder, "Oven");
  const auto result = checkObjects("OpenCabinetDoor-v0", folder);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.err.find("skipping PartNet cabinet 101773"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("no door or drawer with a handle"), std::string::npos) << result.err;
}

// Two category folders split by category: the cabinets' drawers are the
// test split, the oven (refused: no handle on a moving link) all of train.
TEST(PartNetData, FoldersOfTwoCategoriesSplitByCategory) {
  REQUIRE_CATEGORY(cabinets, "StorageFurniture");
  REQUIRE_CATEGORY(oven, "Oven");
  const std::vector<std::string> keys = {"--set", "task.partnet_dir=[" + cabinets + ", " + oven + "]", "--set",
                                         "task.partnet_test_categories=[StorageFurniture]"};
  auto list = [&](const std::string& split) {
    std::vector<std::string> args = {"objects", "OpenCabinetDrawer-v0", "--split", split};
    args.insert(args.end(), keys.begin(), keys.end());
    return runCli(args);
  };
  const auto test = list("test");
  EXPECT_EQ(test.exit_code, 0) << test.out << test.err;
  EXPECT_NE(test.out.find("47578_link_3"), std::string::npos) << test.out;
  EXPECT_EQ(test.out.find("101773"), std::string::npos) << "the oven is not in test: " << test.out;
  const auto train = list("train");
  EXPECT_EQ(train.out.find("47578"), std::string::npos) << train.out;
  EXPECT_NE(train.err.find("skipping PartNet cabinet 101773"), std::string::npos) << train.err;
}

TEST(PartNetData, EveryChairAndBucketLoads) {
  REQUIRE_CATEGORY(chairs, "Chair");
  REQUIRE_CATEGORY(buckets, "Bucket");
  // 179: a seat on a slider+ (a massless helper link between its slider
  // and its hinge) and 10 wheels on 5 casters.
  const auto chair = checkObjects("PushChair-v0", chairs);
  EXPECT_EQ(chair.exit_code, 0) << chair.out << chair.err;
  EXPECT_NE(chair.out.find("2 of 2 objects loaded"), std::string::npos) << chair.out;
  EXPECT_NE(chair.out.find("179            loaded: 17 movable joints"), std::string::npos) << chair.out;
  const auto bucket = checkObjects("MoveBucket-v0", buckets);
  EXPECT_EQ(bucket.exit_code, 0) << bucket.out << bucket.err;
  EXPECT_NE(bucket.out.find("4 of 4 objects loaded"), std::string::npos) << bucket.out;
}

// The success rate `eval` prints for `task`'s expert on the folder's
// objects of `category`, `episodes` per object (evaluation seed 0: the
// same episodes every run), after checking that all `expected` ran.
double evalExpert(const std::string& task, const std::string& expert, const std::string& folder, int episodes,
                  int expected) {
  const std::string out = (std::filesystem::temp_directory_path() / ("manibench_partnet_" + task)).string();
  std::filesystem::remove_all(out);
  const auto result = runCli({"eval", task, "--policy", expert, "--split", "train", "--episodes-per-object",
                              std::to_string(episodes), "--workers", "2", "--no-progress", "--set",
                              "task.partnet_dir=" + folder, "--out", out});
  std::filesystem::remove_all(out);
  EXPECT_EQ(result.exit_code, 0) << result.out << result.err;
  const std::string ran = std::to_string(expected) + " of " + std::to_string(expected) + " episodes";
  EXPECT_NE(result.out.find(ran), std::string::npos) << result.out;
  const std::size_t all = result.out.find("\nall ");
  if (all == std::string::npos) {
    ADD_FAILURE() << "no 'all' row: " << result.out;
    return 0;
  }
  std::istringstream row(result.out.substr(all + 5));
  int count = 0;
  double success = 0;
  row >> count >> success;
  std::cout << task << ", " << expert << ": " << success << " of " << count << " episodes\n";
  return success;
}

// Each expert on the folder's objects of its category, at the issue's
// targets (drawer 90 %, door 80 %, chair and bucket 60 %); what each got on
// 2026-11-28 in brackets. docs/partnet.md has the rates over more
// episodes (drawers 100 / 100, doors 89 / 100, chairs 33 / 50, buckets
// 31 / 40).
struct ExpertCase {
  const char *task, *expert, *category;
  int episodes_per_object, episodes;
  double target;
};

// (ctest's test names show the task, not the struct's bytes.)
void PrintTo(const ExpertCase& c, std::ostream* os) { *os << c.task << ", " << c.expert; }

class PartNetExpert : public ::testing::TestWithParam<ExpertCase> {};

TEST_P(PartNetExpert, ReachesTheTarget) {
  const ExpertCase& c = GetParam();
  REQUIRE_CATEGORY(folder, c.category);
  EXPECT_GE(evalExpert(c.task, c.expert, folder, c.episodes_per_object, c.episodes), c.target);
}

INSTANTIATE_TEST_SUITE_P(
    PartNetData, PartNetExpert,
    ::testing::Values(ExpertCase{"OpenCabinetDrawer-v0", "open_cabinet_expert", "StorageFurniture", 1, 10, 0.9},  // (10 / 10)
                    ExpertCase{"OpenCabinetDoor-v0", "open_cabinet_expert", "StorageFurniture", 2, 20, 0.8},    // (19 / 20)
                    ExpertCase{"PushChair-v0", "push_chair_expert", "Chair", 5, 10, 0.6},                       // (7 / 10)
                    ExpertCase{"MoveBucket-v0", "move_bucket_expert", "Bucket", 3, 12, 0.6}),                   // (9 / 12)
    [](const ::testing::TestParamInfo<ExpertCase>& info) {
      std::string name = info.param.task;
      return name.substr(0, name.find('-'));
    });

TEST(PartNetData, ADemonstrationOnARealCabinetReplaysBitForBit) {
  REQUIRE_CATEGORY(folder, "StorageFurniture");
  const std::string file = (std::filesystem::temp_directory_path() / "manibench_partnet_demo.h5").string();
  std::filesystem::remove(file);
  const auto made = runCli({"demos", "generate", "OpenCabinetDrawer-v0", "--policy", "open_cabinet_expert",
                            "--objects", "46236_link_1", "--per-object", "1", "--no-progress", "--set",
                            "task.partnet_dir=" + folder, "--out", file});
  ASSERT_EQ(made.exit_code, 0) << made.out << made.err;
  const auto replay = runCli({"demos", "replay", file, "--check"});
  EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  std::filesystem::remove(file);
}

// demos convert --controller on one real object per family: the expert's
// end-effector demonstration (up to 5 episodes for one success) in
// mobile_panda's actions replays bit for bit (docs/demonstrations.md,
// "Another controller").
struct RealConversionCase {
  const char *task, *expert, *category, *object;
};
void PrintTo(const RealConversionCase& c, std::ostream* os) { *os << c.task << ", " << c.object; }

class PartNetConversion : public ::testing::TestWithParam<RealConversionCase> {};

TEST_P(PartNetConversion, AnExpertsDemonstrationConvertsExactlyToMobilePanda) {
  const RealConversionCase& c = GetParam();
  REQUIRE_CATEGORY(folder, c.category);
  const auto dir = std::filesystem::temp_directory_path() / ("manibench_partnet_convert_" + std::string(c.object));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string ee = (dir / "ee.h5").string(), joints = (dir / "joints.h5").string();
  const auto made = runCli({"demos", "generate", c.task, "--policy", c.expert, "--objects", c.object, "--per-object",
                            "1", "--max-attempts", "5", "--no-progress", "--set", "task.partnet_dir=" + folder,
                            "--out", ee});
  ASSERT_EQ(made.exit_code, 0) << made.out << made.err;
  const auto converted = runCli({"demos", "convert", ee, "--controller", "mobile_panda", "--out", joints, "--no-progress"});
  ASSERT_EQ(converted.exit_code, 0) << converted.out << converted.err;
  EXPECT_NE(converted.out.find("wrote 1 trajectories for controller mobile_panda"), std::string::npos) << converted.out;
  const auto replay = runCli({"demos", "replay", joints, "--check"});
  EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  EXPECT_NE(replay.out.find("1 bit-identical"), std::string::npos) << replay.out;
  const auto info = runCli({"demos", "info", joints});
  EXPECT_NE(info.out.find("controller     mobile_panda\n"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("converted from " + ee + " (exact)"), std::string::npos) << info.out;
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(
    PartNetData, PartNetConversion,
    ::testing::Values(RealConversionCase{"OpenCabinetDrawer-v0", "open_cabinet_expert", "StorageFurniture", "46236_link_1"},
                      RealConversionCase{"OpenCabinetDoor-v0", "open_cabinet_expert", "StorageFurniture", "40147_link_0"},
                      RealConversionCase{"PushChair-v0", "push_chair_expert", "Chair", "179"},
                      RealConversionCase{"MoveBucket-v0", "move_bucket_expert", "Bucket", "100431"}),
    [](const ::testing::TestParamInfo<RealConversionCase>& info) {
      std::string name = info.param.task;
      return name.substr(0, name.find('-'));
    });

// The point cloud of a real cabinet carries its meshes' textures: 40147's
// .mtl files give Kd 1 1 1 and a wood image, so without the textures its
// points would be grey (r = g = b under the white lights); with them most
// are warm. The PLY is manibench render's: x, y, z floats, then r, g, b
// and the three masks (handle, target link, robot) as bytes.
TEST(PartNetData, ARealCabinetsPointCloudHasItsTexturesColours) {
  REQUIRE_CATEGORY(folder, "StorageFurniture");
  const std::string out = (std::filesystem::temp_directory_path() / "manibench_partnet_render").string();
  std::filesystem::remove_all(out);
  const auto result = runCli({"render", "OpenCabinetDrawer_40147-v0", "--obs", "pointcloud", "--seed", "1", "--set",
                              "task.partnet_dir=" + folder, "--out", out});
  ASSERT_EQ(result.exit_code, 0) << result.out << result.err;
  const std::string ply = testing::readFile(out + "/pointcloud.ply");
  const std::size_t header = ply.find("end_header\n");
  ASSERT_NE(header, std::string::npos);
  ASSERT_NE(ply.find("property uchar mask_robot\nend_header"), std::string::npos) << ply.substr(0, header);
  constexpr std::size_t kStride = 3 * sizeof(float) + 6;
  const std::size_t begin = header + 11, count = (ply.size() - begin) / kStride;
  ASSERT_EQ(count, 1200u);
  int object = 0, warm = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const char* p = ply.data() + begin + i * kStride;
    float z;
    std::memcpy(&z, p + 8, sizeof z);
    const auto* c = reinterpret_cast<const unsigned char*>(p + 12);
    if (c[5] != 0 || z < 0.005f) continue;  // the robot, the floor
    ++object;
    warm += int(c[0]) - int(c[2]) > 30;
  }
  ASSERT_GT(object, 200);
  EXPECT_GT(warm, object * 3 / 10) << warm << " of " << object << " cabinet points are wood-coloured";
  std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace manibench
