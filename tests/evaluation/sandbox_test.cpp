// The evaluated policy's sandbox (issue 30, docs/evaluation.md "Sandbox"):
// policies that attack the run (kill the worker or a sibling, fork, open a
// socket, read or write files they should not, exhaust memory, CPU or
// output, exit, write into the worker's memory) fail only their own
// episodes with a message naming what was refused, everything else equals
// a run in which those episodes simply failed, and no process of the run
// outlives it; the sandboxed path gives the in-process path's results bit
// for bit.
#include <dirent.h>
#include <gtest/gtest.h>
#include <linux/landlock.h>
#include <seccomp.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <manibench/evaluation.hpp>
#include <random>

#include "eval_test_support.hpp"
#include "test_support.hpp"

namespace manibench {
namespace {

using testing::contains;
using testing::readFile;

const std::string kEvalFixtureDir = std::string(MANIBENCH_TEST_FIXTURE_DIR) + "/eval";
const std::string kFixturePath = "MANIBENCH_PLUGIN_PATH=" + kEvalFixtureDir;

bool hasLandlock() {
  return syscall(SYS_landlock_create_ruleset, nullptr, 0, LANDLOCK_CREATE_RULESET_VERSION) > 0;
}

// Processes whose environment holds `tag` (every process a run starts
// inherits it, unless it clears its environment).
std::vector<std::string> findTaggedProcesses(const std::string& tag) {
  std::vector<std::string> found;
  DIR* proc = opendir("/proc");
  if (!proc) return found;
  while (dirent* entry = readdir(proc)) {
    const std::string name = entry->d_name;
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string environ = readFile("/proc/" + name + "/environ");
    if (contains(environ, tag)) found.push_back(name + " " + readFile("/proc/" + name + "/comm"));
  }
  closedir(proc);
  return found;
}

std::string makeTag() {
  std::random_device device;
  return "MANIBENCH_SANDBOX_TEST_TAG=" + std::to_string(device()) + "_" + std::to_string(getpid());
}

struct FixtureRun {
  testing::CommandResult result;
  std::vector<std::map<std::string, std::string>> episodes;
  std::string summary;
};

// Reach-v0 on two objects, four levels each (odd and even seeds), two
// workers, tight limits so that the limit fixtures fail fast (the CPU
// limit 1 s unless the attack needs room, below); a step
// timeout long enough for the spinning one to reach its CPU limit on a
// loaded machine (it did not within 10 s under ctest -j2 at a load of 12).
FixtureRun runFixture(const TempDir& out, const std::string& policy, const std::vector<std::string>& env,
               std::vector<std::string> extra = {}, const std::function<void()>& in_child = {},
               const std::string& cpu_limit_s = "1") {
  std::vector<std::string> args = {"Reach-v0",         "--policy",   policy,  "--objects",
                                   "8,10",             "--levels",   "0-3",   "--workers",
                                   "2",                "--policy-cpu-limit", cpu_limit_s,
                                   "--policy-memory-limit", "256", "--policy-output-limit", "1",
                                   "--step-timeout",   "120"};
  args.insert(args.end(), extra.begin(), extra.end());
  std::vector<std::string> environment = env;
  environment.push_back(kFixturePath);
  FixtureRun run;
  run.result = runEval(out, args, environment, in_child);
  run.episodes = readCsv(out / "episodes.csv");
  run.summary = readFile(out / "summary.csv");
  return run;
}

struct Attack {
  std::string policy;
  std::string failure;
  std::string message_part;
  bool needs_landlock = false;
  std::string cpu_limit_s = "1";
};

// Filling its 256 MiB costs the allocating policy 0.64 s of CPU time per
// episode on the idle development VM (0.55 s under ASan, its abort's report
// included), and more than 1 s on CI's slower machine under make sanitize
// (2026-11-27): it gets a CPU limit it cannot reach first, so that its
// memory limit is what stops it (as python/tests/test_policy_sandbox.py).
const std::string kAllocatingCpuLimitS = "30";

TEST(Sandbox, EachAttackFailsOnlyItsOwnEpisodes) {
  TempDir reference_dir;
  const FixtureRun reference = runFixture(reference_dir, "fixture_flaky_throw", {});
  ASSERT_EQ(reference.result.exit_code, 0) << reference.result.err;
  ASSERT_EQ(reference.episodes.size(), 8u);
  std::size_t failed = 0;
  for (const auto& e : reference.episodes) failed += e.at("failure").empty() ? 0 : 1;
  ASSERT_GT(failed, 0u);
  ASSERT_LT(failed, reference.episodes.size());

  TempDir files;
  const std::string secret = (files / "secret.txt").string();
  const std::string escape = (files / "escape.txt").string();
  std::ofstream(secret) << "the test split's answers\n";
  const std::vector<Attack> attacks = {
      {"fixture_kill_parent", failure::kSandbox, "refused by the sandbox: kill (a signal to process"},
      {"fixture_kill_sibling", failure::kSandbox, "refused by the sandbox: kill (a signal to process"},
      {"fixture_fork_child", failure::kSandbox,
       "refused by the sandbox: clone (the policy may not start processes)"},
      {"fixture_socket", failure::kSandbox, "refused by the sandbox: socket (no network"},
      {"fixture_read_file", failure::kPolicyError, "reading " + secret + ": Permission denied", true},
      {"fixture_write_file", failure::kPolicyError, "writing " + escape + ": Permission denied",
       true},
      // Under AddressSanitizer a `new` that fails reports "out of memory"
      // and aborts (it cannot throw std::bad_alloc): still only its episodes.
      testing::kAddressSanitized
          ? Attack{"fixture_allocate", failure::kCrash, "the policy process was killed by signal 6 (SIGABRT",
                   false, kAllocatingCpuLimitS}
          : Attack{"fixture_allocate", failure::kSandbox, "ran out of its memory limit, 256 MiB", false,
                   kAllocatingCpuLimitS},
      {"fixture_spin", failure::kSandbox, "CPU time limit (1 s in this episode)"},
      {"fixture_flood_stdout", failure::kSandbox, "more than its output limit (1048576 bytes"},
      {"fixture_exit", failure::kCrash, "the policy process exited with status 0"},
      {"fixture_write_env_memory", failure::kSandbox,
       "refused by the sandbox: process_vm_writev (access to process"},
  };
  for (const Attack& attack : attacks) {
    SCOPED_TRACE(attack.policy);
    if (attack.needs_landlock && !hasLandlock()) {
      std::cerr << "skipping " << attack.policy << ": this kernel has no Landlock\n";
      continue;
    }
    const std::string tag = makeTag();
    TempDir out;
    const FixtureRun run = runFixture(out, attack.policy,
                               {tag, "MANIBENCH_FIXTURE_SECRET=" + secret,
                                "MANIBENCH_FIXTURE_ESCAPE=" + escape},
                               {}, {}, attack.cpu_limit_s);
    EXPECT_EQ(run.result.exit_code, reference.result.exit_code) << run.result.err;
    EXPECT_EQ(run.summary, reference.summary);
    ASSERT_EQ(run.episodes.size(), reference.episodes.size());
    for (std::size_t i = 0; i < run.episodes.size(); ++i) {
      auto mine = run.episodes[i], theirs = reference.episodes[i];
      if (theirs.at("failure").empty()) {
        EXPECT_EQ(mine, theirs) << "episode " << i;
        continue;
      }
      EXPECT_EQ(mine.at("failure"), attack.failure) << mine.at("message");
      EXPECT_EQ(mine.at("message").rfind("policy act at step 2: ", 0), 0u) << mine.at("message");
      EXPECT_TRUE(contains(mine.at("message"), attack.message_part)) << mine.at("message");
      for (auto* row : {&mine, &theirs}) {
        row->erase("failure");
        row->erase("message");
      }
      EXPECT_EQ(mine, theirs) << "episode " << i;
    }
    EXPECT_FALSE(fs::exists(escape));
    EXPECT_EQ(findTaggedProcesses(tag), std::vector<std::string>());
  }
}

// What a kernel without Landlock gives (before 5.13, Landlock left out of
// `lsm=`, or a container whose filter refuses its calls), made here on any
// kernel by a seccomp filter, inherited by the run's every process, that
// answers the Landlock calls ENOSYS as such a kernel does: the run says
// "no file rules" on its first line and in summary.json, a policy reads a
// file outside its allowance (there is nothing to stop it), and the rest
// of the sandbox holds (a signal to the parent is still refused).
void withoutLandlock() {
  scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_ALLOW);
  for (int call : {SYS_landlock_create_ruleset, SYS_landlock_add_rule, SYS_landlock_restrict_self})
    seccomp_rule_add(ctx, SCMP_ACT_ERRNO(ENOSYS), call, 0);
  if (seccomp_load(ctx) != 0) _exit(126);
  seccomp_release(ctx);
}

TEST(Sandbox, WithoutLandlockTheRunSaysSoAndTheRestHolds) {
  TempDir reference_dir;
  const FixtureRun reference = runFixture(reference_dir, "fixture_flaky_throw", {});
  ASSERT_EQ(reference.result.exit_code, 0) << reference.result.err;
  TempDir files;
  const std::string secret = (files / "secret.txt").string();
  std::ofstream(secret) << "the test split's answers\n";
  const std::vector<std::string> env = {"MANIBENCH_FIXTURE_SECRET=" + secret};
  const std::string no_rules = "seccomp, rlimits; no file rules (this kernel has no Landlock)";

  TempDir read_dir;
  const FixtureRun read = runFixture(read_dir, "fixture_read_file", env, {}, withoutLandlock);
  ASSERT_EQ(read.result.exit_code, 0) << read.result.err;
  EXPECT_TRUE(contains(read.result.out + read.result.err, "the policy sandboxed (" + no_rules + ")"))
      << read.result.out << read.result.err;
  EXPECT_TRUE(contains(readFile(read_dir / "summary.json"), no_rules));
  ASSERT_EQ(read.episodes.size(), reference.episodes.size());
  for (const auto& e : read.episodes) EXPECT_EQ(e.at("failure"), "") << e.at("message");

  TempDir kill_dir;
  const FixtureRun kill = runFixture(kill_dir, "fixture_kill_parent", {}, {}, withoutLandlock);
  EXPECT_EQ(kill.result.exit_code, reference.result.exit_code) << kill.result.err;
  EXPECT_EQ(kill.summary, reference.summary);
  EXPECT_TRUE(contains(readFile(kill_dir / "summary.json"), no_rules));
  std::size_t refused = 0;
  for (const auto& e : kill.episodes) refused += contains(e.at("message"), "refused by the sandbox: kill") ? 1 : 0;
  EXPECT_GT(refused, 0u);

  // And with the kernel's Landlock, where it has one, the run names it.
  if (hasLandlock()) {
    TempDir with_dir;
    const FixtureRun with = runFixture(with_dir, "fixture_read_file", env);
    EXPECT_TRUE(contains(readFile(with_dir / "summary.json"), "seccomp, Landlock ABI "));
    EXPECT_EQ(with.summary, reference.summary);
  }
}

// A deterministic policy gives the same episodes, bit for bit, in its
// sandboxed process and in the worker's (--trusted-policy).
TEST(Sandbox, ResultsEqualTheTrustedPathBitForBit) {
  for (const std::string policy : {"random", "reach_expert"}) {
    SCOPED_TRACE(policy);
    TempDir sandboxed, trusted;
    const std::vector<std::string> args = {"Reach-v0", "--policy",  policy,    "--objects",
                                           "8,10",     "--levels", "0-2", "--workers", "2"};
    std::vector<std::string> trusted_args = args;
    trusted_args.push_back("--trusted-policy");
    const auto a = runEval(sandboxed, args);
    const auto b = runEval(trusted, trusted_args);
    ASSERT_EQ(a.exit_code, 0) << a.err;
    ASSERT_EQ(b.exit_code, 0) << b.err;
    EXPECT_EQ(readFile(sandboxed / "episodes.csv"), readFile(trusted / "episodes.csv"));
    EXPECT_EQ(readFile(sandboxed / "summary.csv"), readFile(trusted / "summary.csv"));
    EXPECT_TRUE(contains(readFile(sandboxed / "summary.json"), "\"policy_process\": {\"sandbox\": true"));
    EXPECT_TRUE(contains(readFile(trusted / "summary.json"), "\"policy_process\": {\"sandbox\": false}"));
  }
}

// The visual observations cross the block whole: a policy that acts from a
// hash of every byte of them gives the same episodes sandboxed and not.
TEST(Sandbox, VisualObservationsCrossBitForBit) {
  for (const std::string mode : {"pointcloud", "rgbd"}) {
    SCOPED_TRACE(mode);
    TempDir sandboxed, trusted;
    const std::vector<std::string> args = {
        "Reach-v0", "--policy", "fixture_observation_digest", "--obs", mode, "--objects", "8",
        "--levels", "0-1", "--set", "episode.max_steps=5"};
    std::vector<std::string> trusted_args = args;
    trusted_args.push_back("--trusted-policy");
    const auto a = runEval(sandboxed, args, {kFixturePath});
    const auto b = runEval(trusted, trusted_args, {kFixturePath});
    ASSERT_EQ(a.exit_code, 0) << a.err;
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const std::string episodes = readFile(sandboxed / "episodes.csv");
    EXPECT_EQ(episodes, readFile(trusted / "episodes.csv"));
    EXPECT_FALSE(contains(episodes, "policy_error")) << episodes;
  }
}

}  // namespace
}  // namespace manibench
