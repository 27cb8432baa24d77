// manibench survey, run as a user runs it on a folder of PartNet-Mobility
// objects (the hand-made tests/fixtures/partnet_mini, in that layout): the
// expert's episodes succeed, episodes built to fail are classified by why,
// and an object the task cannot use is named with its reason.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "test_support.hpp"

namespace manibench {
namespace {

namespace fs = std::filesystem;
using testing::runCli;

const std::string kMini = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/tests/fixtures/partnet_mini";

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The outcome column of episodes.csv, one entry per episode.
std::vector<std::string> readOutcomes(const fs::path& dir) {
  std::istringstream in(readFile(dir / "episodes.csv"));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> outcomes;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream row(line);
    for (std::string f; std::getline(row, f, ',');) fields.push_back(f);
    if (fields.size() > 6) outcomes.push_back(fields[6]);
  }
  return outcomes;
}

class SurveyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("manibench_survey_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(SurveyTest, TheExpertSucceedsOnEveryObjectAndTheFilesSaySo) {
  const fs::path out = dir_ / "out";
  const auto r = runCli({"survey", "OpenCabinetDrawer-v0", kMini, "--episodes-per-object", "2", "--set",
                         "task.partnet_scale=1", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("with policy open_cabinet_expert"), std::string::npos) << r.out;
  // Both splits: 100001 (train) and 100002 (test), one drawer each.
  EXPECT_NE(r.out.find("100001_link_1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("100002_link_1"), std::string::npos) << r.out;
  EXPECT_EQ(readOutcomes(out), std::vector<std::string>(4, "success"));
  const std::string json = readFile(out / "survey.json");
  EXPECT_NE(json.find("\"category\": \"partnet_mini\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"success_rate\": 1.0"), std::string::npos) << json;
  EXPECT_NE(readFile(out / "objects.csv").find("partnet_mini,100001,loaded,"), std::string::npos);
  EXPECT_NE(readFile(out / "survey.svg").find("<svg"), std::string::npos);
}

TEST_F(SurveyTest, APolicyThatNeverMovesNeverReachesTheHandle) {
  const fs::path out = dir_ / "out";
  const auto r = runCli({"survey", "OpenCabinetDoor-v0", kMini, "--policy", "zero", "--episodes-per-object", "1",
                         "--set", "task.partnet_scale=1", "--set", "episode.max_steps=20", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(readOutcomes(out), std::vector<std::string>(2, "never_reached"));
  EXPECT_NE(r.out.find("never_reached 2"), std::string::npos) << r.out;
}

// Pads without friction: the expert reaches the handle and closes on it,
// but the drawer's pull slides it out of the fingers.
TEST_F(SurveyTest, FingersWithoutFrictionLoseTheGrasp) {
  const fs::path out = dir_ / "out";
  const fs::path config = dir_ / "slippery.yaml";
  std::ofstream(config) << "physics:\n  contact:\n    bodies:\n"
                           "      - {articulation: robot, link: right_panda_leftfinger, static_friction: 0.0, dynamic_friction: 0.0}\n"
                           "      - {articulation: robot, link: right_panda_rightfinger, static_friction: 0.0, dynamic_friction: 0.0}\n";
  const auto r = runCli({"survey", "OpenCabinetDrawer-v0", kMini, "--episodes-per-object", "1", "--set",
                         "task.partnet_scale=1", "--config", config.string(), "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  for (const std::string& o : readOutcomes(out)) EXPECT_EQ(o, "grasp_lost") << r.out;
}

// An object without a handle part is refused, with the task's reason, in
// the table and in objects.csv; the others are surveyed.
TEST_F(SurveyTest, AnObjectTheTaskCannotUseIsRefusedWithItsReason) {
  const fs::path data = dir_ / "Cabinets";
  fs::copy(kMini, data, fs::copy_options::recursive);
  fs::copy(data / "100001", data / "100009", fs::copy_options::recursive);
  const fs::path urdf = data / "100009" / "mobility.urdf";
  std::string text = readFile(urdf);
  text = std::regex_replace(text, std::regex("name=\"handle"), "name=\"knob");
  std::ofstream(urdf) << text;
  const fs::path out = dir_ / "out";
  const auto r = runCli({"survey", "OpenCabinetDrawer-v0", data.string(), "--episodes-per-object", "1", "--set",
                         "task.partnet_scale=1", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("100009"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("refused: no door or drawer with a handle part"), std::string::npos) << r.out;
  EXPECT_NE(readFile(out / "objects.csv").find("Cabinets,100009,refused,,,no door or drawer with a handle part"),
            std::string::npos)
      << readFile(out / "objects.csv");
  EXPECT_EQ(readOutcomes(out).size(), 2u);
}

// A target the task leaves out (a flap that would open into the ground) is
// named with its reason: an object whose only door it is appears refused,
// not missing; the folder's other object is surveyed.
TEST_F(SurveyTest, AnObjectWhoseEveryTargetIsLeftOutIsNamedWithTheReason) {
  testing::FixtureCopy data("partnet_mini");
  testing::makeFlap(data, true);
  const fs::path out = dir_ / "out";
  const auto r = runCli({"survey", "OpenCabinetDoor-v0", data.folder(), "--policy", "zero", "--episodes-per-object",
                         "1", "--set", "task.partnet_scale=1", "--set", "episode.max_steps=5", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("100001                 refused: every target left out: link_0: it reaches "), std::string::npos)
      << r.out;
  const std::string objects = readFile(out / "objects.csv");
  EXPECT_NE(objects.find(",100001,refused,,,every target left out: link_0: it reaches "), std::string::npos) << objects;
  EXPECT_NE(objects.find(",100002,loaded,"), std::string::npos) << objects;
  EXPECT_EQ(readOutcomes(out).size(), 1u);  // 100002's door
  EXPECT_NE(readFile(out / "survey.json").find("\"targets_left_out\": 0"), std::string::npos);
}

// Two folders of one category (two downloads of it) are one category: one
// row in the table, each object listed once.
TEST_F(SurveyTest, TwoFoldersOfOneCategoryAreOneCategory) {
  for (const char* half : {"a", "b"}) {
    fs::create_directories(dir_ / half);
    fs::copy(kMini, dir_ / half / "Cabinets", fs::copy_options::recursive);
  }
  fs::remove_all(dir_ / "a" / "Cabinets" / "100002");
  fs::remove(dir_ / "a" / "Cabinets" / "test.txt");  // it names 100002
  fs::remove_all(dir_ / "b" / "Cabinets" / "100001");
  const fs::path out = dir_ / "out";
  const auto r = runCli({"survey", "OpenCabinetDrawer-v0", (dir_ / "a" / "Cabinets").string(),
                         (dir_ / "b" / "Cabinets").string(), "--policy", "zero", "--episodes-per-object", "1", "--set",
                         "task.partnet_scale=1", "--set", "episode.max_steps=5", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = r.out.find(what); at != std::string::npos; at = r.out.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("\n  100001_link_1 "), 1u) << r.out;
  EXPECT_EQ(count("\n  100002_link_1 "), 1u) << r.out;
  EXPECT_EQ(count("\n  Cabinets "), 1u) << r.out;
  EXPECT_EQ(readOutcomes(out).size(), 2u);
}

TEST_F(SurveyTest, UsageErrors) {
  EXPECT_EQ(runCli({"survey", "OpenCabinetDrawer-v0"}).exit_code, 2);
  const auto r = runCli({"survey", "OpenCabinetDrawer-v0", (dir_ / "nothing").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("is not a folder"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace manibench
