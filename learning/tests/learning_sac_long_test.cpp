// SAC learning Reach-v0 for real, and supplement C.2's pipeline end to end:
// minutes on the 2-core development VM, so these run only with
// MANIBENCH_LONG_TESTS=1 (skipped otherwise, and saying so):
//   MANIBENCH_LONG_TESTS=1 ctest -R SacLong --output-on-failure
//
// Budget (docs/learning-results.md): on Reach arm 0 a 2 x 64 SAC with batch
// 256 and one worker, success of the deterministic actor over 20 episodes
// every 5k env steps, training seeds 0-4 (2026-11-27, OpenBLAS's Haswell
// kernels): at 35k 0.85 / 0.95 / 0.40 / 0.75 / 0.60, at 60k 0.95 / 1.0 /
// 0.90 / 0.90 / 0.90; seed 0 stays at 0.9-1.0 from 45k on. So the test
// trains seed 0 for 60k steps and asks the 0.9 (2-3 minutes on the
// loaded VM). The population keeps 35k: it needs only C.2's 0.3 per agent.
#include <test_support.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace {

namespace fs = std::filesystem;
using manibench::testing::contains;
using manibench::testing::runCli;

bool longTestsEnabled() {
  const char* value = std::getenv("MANIBENCH_LONG_TESTS");
  return value != nullptr && std::string(value) == "1";
}

class SacLong : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!longTestsEnabled()) GTEST_SKIP() << "minutes long: set MANIBENCH_LONG_TESTS=1 to run it";
    dir_ = fs::temp_directory_path() / ("manibench_sac_long_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

double readSuccessRate(const std::string& summary) {
  std::ifstream in(summary);
  return nlohmann::json::parse(in)["overall"]["success_rate"].get<double>();
}

// The temperature as docs/learning-results.md measured these runs (before
// ManiSkill-Learn's alpha = 1 and gradient with respect to alpha became
// the defaults, 2026-11-28; not re-measured with those yet).
const std::vector<std::string> kReachAgent = {"--workers", "1", "--batch-size", "256", "--hidden", "64,64",
                                              "--random-steps", "1000", "--init-temperature", "0.2",
                                              "--log-temperature-gradient", "--no-progress"};

TEST_F(SacLong, SacReachesNinetyPercentOnReachWithinSixtyThousandSteps) {
  std::vector<std::string> train = {"train", "sac", "Reach_0-v0", "--steps", "60000", "--out", path("reach")};
  train.insert(train.end(), kReachAgent.begin(), kReachAgent.end());
  const manibench::testing::CommandResult r = runCli(train);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const manibench::testing::CommandResult eval =
      runCli({"eval", "Reach_0-v0", "--policy", "torch_policy", "--policy-config", path("reach/policy.yaml"),
              "--episodes-per-object", "20", "--workers", "2", "--no-progress", "--out", path("reach/eval")});
  ASSERT_EQ(eval.exit_code, 0) << eval.err;
  EXPECT_GE(readSuccessRate(path("reach/eval/summary.json")), 0.9);
}

// Two Reach objects, one agent each, demonstrations from each object's
// own agent (one file per object, and one over both), replayed bit for bit.
TEST_F(SacLong, APopulationOfTwoReachObjectsMakesDemonstrationsThatReplayBitForBit) {
  std::vector<std::string> command = {"train", "sac-population", "Reach-v0", "--objects", "0,1",
                                      "--steps", "35000", "--out", path("population"), "--demos", "3",
                                      "--eval-episodes", "10"};
  command.insert(command.end(), kReachAgent.begin(), kReachAgent.end());
  const manibench::testing::CommandResult r = runCli(command);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const std::string object : {"0", "1"}) {
    const std::string demos = path("population/demos/" + object + ".h5");
    ASSERT_TRUE(fs::exists(demos)) << r.err;
    const manibench::testing::CommandResult replay = runCli({"demos", "replay", demos, "--check"});
    EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
    const manibench::testing::CommandResult info = runCli({"demos", "info", demos});
    EXPECT_TRUE(contains(info.out, "trajectories   3 of 1 object")) << info.out;
  }
  // One file over both objects, each episode acted by its object's agent
  // (torch_policy on population.yaml, through ABI 1.5's reset_episode).
  const std::string both = path("population/both.h5");
  const manibench::testing::CommandResult generate =
      runCli({"demos", "generate", "Reach-v0", "--objects", "0,1", "--policy", "torch_policy", "--policy-config",
              path("population/population.yaml"), "--per-object", "3", "--no-progress", "--out", both});
  ASSERT_EQ(generate.exit_code, 0) << generate.out << generate.err;
  const manibench::testing::CommandResult replay = runCli({"demos", "replay", both, "--check"});
  EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  const manibench::testing::CommandResult info = runCli({"demos", "info", both});
  EXPECT_TRUE(contains(info.out, "trajectories   6 of 2 object(s)")) << info.out;
}

}  // namespace
