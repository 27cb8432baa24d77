// The manibench host program, run as a user runs it.
#include <gtest/gtest.h>

#include "test_support.hpp"

namespace manibench {
namespace {

using testing::runCli;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(Cli, HelpAndUsageErrors) {
  const auto help = runCli({"--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_TRUE(contains(help.out, "usage: manibench"));
  for (const char* command : {"list", "info", "run", "demo"}) {
    const auto r = runCli({command, "--help"});
    EXPECT_EQ(r.exit_code, 0) << command;
    EXPECT_TRUE(contains(r.out, std::string("usage: manibench ") + command)) << r.out;
  }
  EXPECT_EQ(runCli({}).exit_code, 2);
  const auto unknown = runCli({"frobnicate"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_TRUE(contains(unknown.err, "unknown command 'frobnicate'")) << unknown.err;
  const auto bad_option = runCli({"run", "Reach-v0", "--policy", "random", "--bogus"});
  EXPECT_EQ(bad_option.exit_code, 2);
  EXPECT_TRUE(contains(bad_option.err, "unknown option '--bogus'")) << bad_option.err;
  EXPECT_EQ(runCli({"run", "Reach-v0"}).exit_code, 2);  // no --policy
  EXPECT_EQ(runCli({"run", "Reach-v0", "--policy", "random", "--seed", "-3"}).exit_code, 2);
}

TEST(Cli, ListShowsEveryPluginWithItsLibrary) {
  const auto r = runCli({"list"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {"Reach-v0", "reach_expert", "random", "zero", "joint_velocity", "joint_position"})
    EXPECT_TRUE(contains(r.out, name)) << name << "\n" << r.out;
  EXPECT_TRUE(contains(r.out, MANIBENCH_TEST_BUILD_PLUGIN_DIR)) << r.out;
  EXPECT_FALSE(contains(r.out, "refused")) << r.out;
}

TEST(Cli, ListReportsBrokenLibrariesAndKeepsWorking) {
  const auto r = runCli({"list"}, {std::string("MANIBENCH_PLUGIN_PATH=") + MANIBENCH_TEST_FIXTURE_DIR});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "refused libraries")) << r.out;
  EXPECT_TRUE(contains(r.out, "ABI 99.0")) << r.out;
  EXPECT_TRUE(contains(r.out, "Reach-v0")) << r.out;  // the build tree still loads
}

TEST(Cli, InfoPrintsLayouts) {
  const auto r = runCli({"info", "Reach-v0"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "observation (state), 15 values")) << r.out;
  EXPECT_TRUE(contains(r.out, "joint_positions")) << r.out;
  EXPECT_TRUE(contains(r.out, "action, 2 values")) << r.out;
  EXPECT_TRUE(contains(r.out, "shoulder")) << r.out;
  EXPECT_TRUE(contains(r.out, "success conditions: reached static success")) << r.out;
  EXPECT_TRUE(contains(r.out, "objects: 8 train, 4 test")) << r.out;
}

TEST(Cli, RunPrintsStepsReturnAndFlags) {
  const auto r = runCli({"run", "Reach-v0", "--policy", "reach_expert", "--seed", "1", "--split", "test"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "steps, return")) << r.out;
  EXPECT_TRUE(contains(r.out, "success")) << r.out;
  EXPECT_TRUE(contains(r.out, "yes")) << r.out;
  // Same seed, same output.
  EXPECT_EQ(r.out, runCli({"run", "Reach-v0", "--policy", "reach_expert", "--seed", "1", "--split", "test"}).out);
}

TEST(Cli, UnknownNamesAreClearErrors) {
  const auto policy = runCli({"run", "Reach-v0", "--policy", "nope"});
  EXPECT_EQ(policy.exit_code, 1);
  EXPECT_TRUE(contains(policy.err, "no policy named 'nope'")) << policy.err;
  EXPECT_TRUE(contains(policy.err, "reach_expert")) << policy.err;
  const auto task = runCli({"info", "Nope-v0"});
  EXPECT_EQ(task.exit_code, 1);
  EXPECT_TRUE(contains(task.err, "no task named 'Nope-v0'")) << task.err;
}

TEST(Cli, PolicyCanBeAPathToALibrary) {
  const auto r = runCli({"run", "Reach-v0", "--policy",
                         std::string(MANIBENCH_TEST_BUILD_PLUGIN_DIR) + "/libmanibench_example_policies.so"});
  // That library registers two policies: the host must say so, not guess.
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(contains(r.err, "registers 2 policies")) << r.err;
}

}  // namespace
}  // namespace manibench
