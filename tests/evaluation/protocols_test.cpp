// The evaluation protocols beside ManiSkill v1's B.4 (docs/evaluation.md,
// "Protocols"): without the early done (--no-early-done) an episode runs to
// its time limit and the report carries ManiSkill3's success_once and
// success_at_end; with it (the default) both equal the success column.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "eval_test_support.hpp"
#include "test_support.hpp"

namespace manibench {
namespace {

using testing::contains;
using testing::readFile;

// The Reach expert on two episodes of one object: cheap, and it succeeds.
const std::vector<std::string> kReach = {"Reach-v0", "--policy", "reach_expert", "--objects", "8", "--levels", "0-1"};

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

}  // namespace
}  // namespace manibench
