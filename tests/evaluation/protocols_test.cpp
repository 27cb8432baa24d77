// The evaluation protocols beside ManiSkill v1's B.4 (docs/evaluation.md,
// "Protocols"): without the early done (--no-early-done) an episode runs to
// its time limit and the report carries ManiSkill3's success_once and
// success_at_end; with it (the default) both equal the success column.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "eval_test_support.hpp"
#include "test_support.hpp"

namespace manibench {
namespace {

using testing::contains;
using testing::readFile;

// The Reach expert on two episodes of one object: cheap, and it succeeds.
const std::vector<std::string> kReach = {"Reach-v0", "--policy", "reach_expert", "--objects", "8", "--levels", "0-1"};

// Two procedural drawer cabinets of the test split.
const char* const kDrawerObjects = "2100_link_0,2101_link_2";

std::vector<std::string> with(const std::vector<std::string>& extra) { return joinArguments(kReach, extra); }

TEST(EvalProtocols, WithoutTheEarlyDoneEpisodesRunToTheLimitAndSuccessOnceIsTheEarlyDoneSuccess) {
  TempDir early, full;
  const auto a = runEval(early, kReach);
  ASSERT_EQ(a.exit_code, 0) << a.err << a.out;
  const auto b = runEval(full, with({"--no-early-done"}));
  ASSERT_EQ(b.exit_code, 0) << b.err << b.out;
  const auto early_episodes = readCsv(early / "episodes.csv"), full_episodes = readCsv(full / "episodes.csv");
  ASSERT_EQ(early_episodes.size(), 2u);
  ASSERT_EQ(full_episodes.size(), 2u);
  std::size_t successes = 0;
  for (std::size_t i = 0; i < early_episodes.size(); ++i) {
    const auto &e = early_episodes[i], &f = full_episodes[i];
    ASSERT_EQ(e.at("index"), f.at("index"));
    // The early done: the episode ends at its first success, so all three agree.
    EXPECT_EQ(e.at("success_once"), e.at("success"));
    EXPECT_EQ(e.at("success_at_end"), e.at("success"));
    // Without it: to the time limit (Reach's 100 steps), success is the
    // last step's, and the same seed gives the same episode up to the early
    // done's end, so success_once is the early-done success exactly.
    EXPECT_EQ(f.at("steps"), "100");
    EXPECT_EQ(f.at("success_at_end"), f.at("success"));
    EXPECT_EQ(f.at("success_once"), e.at("success")) << "episode " << i;
    if (e.at("success") == "1") {
      ++successes;
      EXPECT_LT(std::stoi(e.at("steps")), 100);
    }
  }
  EXPECT_GT(successes, 0u);  // the expert reaches: success_once is not trivially 0
  EXPECT_TRUE(contains(readFile(early / "summary.json"), "\"early_done\": true,"));
  EXPECT_TRUE(contains(readFile(full / "summary.json"), "\"early_done\": false,"));

  // The summaries count what episodes.csv says, with intervals around the rate.
  for (const TempDir* dir : {&early, &full}) {
    const auto episodes = readCsv(*dir / "episodes.csv");
    const auto summary = readCsv(*dir / "summary.csv");
    ASSERT_EQ(summary.size(), 2u);  // object 8, all
    std::size_t once = 0;
    for (const auto& e : episodes) once += std::stoi(e.at("success_once"));
    for (const auto& row : summary) {
      EXPECT_EQ(row.at("successes_once"), std::to_string(once)) << row.at("object");
      const double rate = std::stod(row.at("success_once_rate"));
      EXPECT_DOUBLE_EQ(rate, double(once) / double(episodes.size()));
      EXPECT_LE(std::stod(row.at("success_once_low")), rate);
      EXPECT_GE(std::stod(row.at("success_once_high")), rate);
      EXPECT_LT(std::stod(row.at("success_once_high")) - std::stod(row.at("success_once_low")), 1.0);
    }
    const std::string json = readFile(*dir / "summary.json");
    for (const char* field : {"\"success_once_rate\": ", "\"success_once_interval\": [", "\"success_at_end_rate\": ",
                              "\"success_at_end_interval\": ["})
      EXPECT_TRUE(contains(json, field)) << field << "\n" << json;
  }

  // The certificate's command carries the flag: --verify runs the episodes
  // without the early done again and finds them bit for bit.
  EXPECT_TRUE(contains(readFile(full / "certificate.json"), "\"--no-early-done\"")) << readFile(full / "certificate.json");
  const auto v = testing::runCli({"eval", "--verify", full.path().string()});
  EXPECT_EQ(v.exit_code, 0) << v.err << v.out;
  EXPECT_TRUE(contains(v.out, "verified: 2 episode(s) re-run")) << v.out;
}

// The opening curve (doors and drawers): each episode's max_opened is the
// most of its range the target opened at any step; the summaries count the
// episodes that reached each fraction, per object and overall, with their
// intervals. The expert's curve lies above the random policy's; a task
// without an opening (Reach) has none.
TEST(EvalProtocols, TheOpeningCurveCountsTheEpisodesThatOpenedEachFraction) {
  const std::vector<std::string> drawers = {"OpenCabinetDrawer-v0", "--objects", kDrawerObjects, "--levels", "0-1",
                                            "--no-early-done"};
  TempDir expert, random;
  const auto a = runEval(expert, joinArguments(drawers, {"--policy", "open_cabinet_expert"}));
  ASSERT_EQ(a.exit_code, 0) << a.err << a.out;
  const auto b = runEval(random, joinArguments(drawers, {"--policy", "random"}));
  ASSERT_EQ(b.exit_code, 0) << b.err << b.out;
  const std::vector<std::string> fractions = {"0.25", "0.5", "0.75", "0.9"};
  std::map<const TempDir*, double> at_90;
  for (const TempDir* dir : {&expert, &random}) {
    const auto episodes = readCsv(*dir / "episodes.csv");
    ASSERT_EQ(episodes.size(), 4u);
    for (const auto& e : episodes) {
      ASSERT_FALSE(e.at("max_opened").empty()) << e.at("index");
      const double opened = std::stod(e.at("max_opened"));
      EXPECT_GE(opened, -0.01);
      EXPECT_LE(opened, 1.01);
      if (e.at("success") == "1") EXPECT_GE(opened, 0.9) << "B.4's success opens 90 %";
    }
    for (const auto& row : readCsv(*dir / "summary.csv")) {
      double previous = 1;
      for (const std::string& f : fractions) {
        std::size_t n = 0, reached = 0;
        for (const auto& e : episodes)
          if (row.at("object") == "all" || e.at("object") == row.at("object")) {
            ++n;
            reached += std::stod(e.at("max_opened")) >= std::stod(f);
          }
        const double rate = std::stod(row.at("opened_" + f));
        EXPECT_DOUBLE_EQ(rate, double(reached) / double(n)) << row.at("object") << " " << f;
        EXPECT_LE(std::stod(row.at("opened_" + f + "_low")), rate);
        EXPECT_GE(std::stod(row.at("opened_" + f + "_high")), rate);
        EXPECT_LE(rate, previous) << "a larger fraction is reached no more often";
        previous = rate;
      }
      EXPECT_GE(std::stod(row.at("opened_0.9")), std::stod(row.at("success_rate")));
      if (row.at("object") == "all") at_90[dir] = std::stod(row.at("opened_0.9"));
    }
    EXPECT_TRUE(contains(readFile(*dir / "summary.json"), "\"opening_curve\": [{\"fraction\": 0.25, \"episodes\": "))
        << readFile(*dir / "summary.json");
  }
  EXPECT_TRUE(contains(a.out, "opened at least (at any step): 25 % ")) << a.out;
  EXPECT_TRUE(contains(a.out, "   once     95% interval")) << a.out;  // success_once beside success
  EXPECT_GT(at_90[&expert], at_90[&random]) << a.out << b.out;
  const auto v = testing::runCli({"eval", "--verify", expert.path().string()});
  EXPECT_EQ(v.exit_code, 0) << v.err << v.out;

  TempDir reach;
  const auto r = runEval(reach, kReach);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  for (const auto& e : readCsv(reach / "episodes.csv")) EXPECT_EQ(e.at("max_opened"), "");
  EXPECT_FALSE(contains(readFile(reach / "summary.csv"), "opened_"));
  EXPECT_FALSE(contains(r.out, "opened at least"));
}

// Rates per category (ABI 1.8's get_object_category): a PartNet object's
// category is its folder's name. Two categories of one object each: each
// category's line pools its objects' episodes; a task without categories
// (the Reach runs above) has no such lines.
TEST(EvalProtocols, RatesPerCategoryPoolTheirObjectsAndTheReportVerifies) {
  TempDir data, out;
  const fs::path mini = fs::path(MANIBENCH_TEST_SOURCE_DIR) / "tests/fixtures/partnet_mini";
  for (const auto& [category, id] : std::vector<std::pair<std::string, std::string>>{{"Cupboard", "100001"},
                                                                                    {"Chest", "100002"}}) {
    fs::create_directories(data / category);
    fs::copy(mini / id, data / category / id, fs::copy_options::recursive);
    std::ofstream(data / category / "test.txt") << id << "\n";
  }
  const std::string folders = "task.partnet_dir=[" + (data / "Cupboard").string() + ", " + (data / "Chest").string() + "]";
  const auto r = runEval(out, {"OpenCabinetDrawer-v0", "--policy", "open_cabinet_expert", "--levels", "0-1",
                               "--set", folders, "--set", "task.partnet_scale=1"});
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_TRUE(contains(r.out, "per category")) << r.out;
  const std::string json = readFile(out / "summary.json");
  EXPECT_TRUE(contains(json, "\"per_category\": [")) << json;
  EXPECT_TRUE(contains(json, "{\"category\": \"Chest\", \"objects\": 1, \"episodes\": 2,")) << json;
  EXPECT_TRUE(contains(json, "{\"category\": \"Cupboard\", \"objects\": 1, \"episodes\": 2,")) << json;
  EXPECT_TRUE(contains(readFile(out / "journal.jsonl"), "\"categories\":{\"100001_link_1\":\"Cupboard\"")) << r.out;
  const auto v = testing::runCli({"eval", "--verify", out.path().string()});
  EXPECT_EQ(v.exit_code, 0) << v.err << v.out;

  TempDir reach;
  ASSERT_EQ(runEval(reach, kReach).exit_code, 0);
  EXPECT_FALSE(contains(readFile(reach / "summary.json"), "per_category"));
}

}  // namespace
}  // namespace manibench
