// Beyond one machine without MPI (docs/distributed.md): `--shard I/N` runs
// as a job array's tasks make them, `eval merge` / `demos merge` give the
// single run's files byte for byte, an incomplete merge names what is
// missing and --resume runs only that, a killed shard keeps what it
// finished, and results of different runs do not merge.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <manibench/demos.hpp>
#include <manibench/evaluation.hpp>
#include <sstream>
#include <thread>

#include "distributed_support.hpp"

namespace manibench {
namespace {

using testing::contains;
using testing::readFile;
using testing::countEpisodes;
using testing::expectSameFiles;
using testing::readTrajectories;
using testing::runCli;

// Short episodes of a random policy: 2 objects x 3 levels.
std::vector<std::string> evalArguments(const fs::path& out, std::vector<std::string> extra = {}) {
  std::vector<std::string> a = {"eval", "Reach-v0", "--policy", "random", "--objects", "8,11", "--levels", "0-2",
                                "--set", "episode.max_steps=25", "--no-progress", "--out", out.string()};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

TEST(EvalShards, ShardsMergeIntoTheSingleRunByteForByte) {
  TempDir dir;
  ASSERT_EQ(runCli(evalArguments(dir / "whole")).exit_code, 0);
  for (const char* shard : {"1/3", "2/3", "3/3"}) {
    const auto r = runCli(evalArguments(dir / (std::string("s") + shard[0]), {"--shard", shard, "--workers", "2"}));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(contains(readFile(dir / (std::string("s") + shard[0]) / "summary.json"),
                         "\"shard\": \"" + std::string(shard) + "\""));
  }
  // Each shard holds every third episode, with the whole list's seeds.
  const auto whole = readCsv(dir / "whole" / "episodes.csv");
  const auto second = readCsv(dir / "s2" / "episodes.csv");
  ASSERT_EQ(second.size(), 2u);
  EXPECT_EQ(second[0].at("index"), "1");
  EXPECT_EQ(second[0].at("seed"), whole[1].at("seed"));
  EXPECT_EQ(second[1].at("seed"), whole[4].at("seed"));

  const auto merged = runCli({"eval", "merge", (dir / "s3").string(), (dir / "s1").string(),
                              (dir / "s2").string(), "--out", (dir / "merged").string()});
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  expectSameFiles(dir / "whole", dir / "merged");
}

TEST(EvalShards, IncompleteMergeNamesTheMissingAndResumeRunsOnlyThem) {
  TempDir dir;
  ASSERT_EQ(runCli(evalArguments(dir / "whole")).exit_code, 0);
  for (const char* shard : {"1/3", "3/3"})
    ASSERT_EQ(runCli(evalArguments(dir / (std::string("s") + shard[0]), {"--shard", shard})).exit_code, 0);
  const auto whole = readCsv(dir / "whole" / "episodes.csv");
  const auto merged = runCli({"eval", "merge", (dir / "s1").string(), (dir / "s3").string(), "--out",
                              (dir / "merged").string()});
  EXPECT_EQ(merged.exit_code, 1);
  // Shard 2's episodes: indices 1 and 4.
  testing::expectMentions(merged.err, {"2 of 6 episodes", "object 8 seed " + whole[1].at("seed"),
                                       "object 11 seed " + whole[4].at("seed"), "--resume"});
  EXPECT_TRUE(contains(readFile(dir / "merged" / "summary.json"), "\"complete\": false"));
  const auto resumed = runCli(evalArguments(dir / "merged", {"--resume"}));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  testing::expectMentions(resumed.out, {"resuming: 4 episode(s) done"});
  expectSameFiles(dir / "whole", dir / "merged");
  // Once, not twice: the journal holds every episode one time.
  const std::string journal = readFile(dir / "merged" / "journal.jsonl");
  std::size_t lines = 0;
  for (std::size_t at = 0; (at = journal.find("\"episode\":", at)) != std::string::npos; ++at) ++lines;
  EXPECT_EQ(lines, 6u);
}

TEST(EvalShards, RunsOfDifferentEvaluationsDoNotMerge) {
  TempDir dir;
  ASSERT_EQ(runCli(evalArguments(dir / "a", {"--shard", "1/2"})).exit_code, 0);
  ASSERT_EQ(runCli(evalArguments(dir / "b", {"--shard", "2/2", "--seed", "7"})).exit_code, 0);
  ASSERT_EQ(runCli(evalArguments(dir / "c", {"--shard", "2/2", "--set", "episode.max_steps=20"})).exit_code, 0);
  const auto seed = runCli({"eval", "merge", (dir / "a").string(), (dir / "b").string()});
  EXPECT_EQ(seed.exit_code, 1);
  testing::expectMentions(seed.err, {"another evaluation", "seed: 0 vs 7"});
  const auto config = runCli({"eval", "merge", (dir / "a").string(), (dir / "c").string()});
  EXPECT_EQ(config.exit_code, 1);
  testing::expectMentions(config.err, {"configuration", "episode.max_steps=20"});
  // The same shard twice: its episodes would count twice.
  const auto twice = runCli({"eval", "merge", (dir / "a").string(), (dir / "a").string(), "--out",
                             (dir / "m").string()});
  EXPECT_EQ(twice.exit_code, 1);
  testing::expectMentions(twice.err, {"is in both"});
  // --resume into another run's folder.
  const auto other = runCli(evalArguments(dir / "a", {"--shard", "1/2", "--seed", "3", "--resume"}));
  EXPECT_EQ(other.exit_code, 1);
  testing::expectMentions(other.err, {"--resume", "seed: 0 vs 3"});
  const auto shard = runCli(evalArguments(dir / "a", {"--shard", "2/2", "--resume"}));
  EXPECT_EQ(shard.exit_code, 1);
  testing::expectMentions(shard.err, {"shard: 1 vs 2"});
  const auto usage = runCli(evalArguments(dir / "x", {"--shard", "4/3"}));
  EXPECT_EQ(usage.exit_code, 2);
  testing::expectMentions(usage.err, {"I must be 1 to N"});
}

// A shard killed outright (SIGKILL: no chance to write its files) keeps
// the episodes its journal has; --resume runs the rest, and the merge is
// the single run's.
TEST(EvalShards, KilledShardKeepsItsEpisodesAndResumeCompletesIt) {
  TempDir dir;
  // Long enough (about 40 x 100 steps a shard) that the kill comes first.
  const std::vector<std::string> levels = {"--levels", "0-39", "--set", "episode.max_steps=100"};
  auto clean = [&](const fs::path& out, std::vector<std::string> extra) {
    std::vector<std::string> a = {"eval", "Reach-v0", "--policy", "random", "--objects", "8,11",
                                  "--no-progress", "--out", out.string()};
    a.insert(a.end(), levels.begin(), levels.end());
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  ASSERT_EQ(runCli(clean(dir / "whole", {})).exit_code, 0);
  ASSERT_EQ(runCli(clean(dir / "s1", {"--shard", "1/2"})).exit_code, 0);

  const fs::path s2 = dir / "s2";
  std::vector<std::string> words = clean(s2, {"--shard", "2/2"});
  words.insert(words.begin(), MANIBENCH_TEST_CLI);
  const pid_t pid = testing::startInBackground(words);
  ASSERT_GT(pid, 0);
  // Killed once its journal has three episodes.
  for (int i = 0; i < 6000 && countEpisodes(s2 / "journal.jsonl") < 3; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  kill(-pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  const std::size_t kept = countEpisodes(s2 / "journal.jsonl");
  ASSERT_GE(kept, 3u);
  ASSERT_LT(kept, 40u) << "the shard finished before it was killed";
  EXPECT_FALSE(fs::exists(s2 / "summary.json"));

  // The merge names what the killed shard did not finish.
  const auto partial = runCli({"eval", "merge", (dir / "s1").string(), s2.string(), "--out", (dir / "m").string()});
  EXPECT_EQ(partial.exit_code, 1);
  testing::expectMentions(partial.err, {std::to_string(40 - kept) + " of 80 episodes", "object"});
  const auto resumed = runCli(clean(s2, {"--shard", "2/2", "--resume"}));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  testing::expectMentions(resumed.out, {"resuming: " + std::to_string(kept) + " episode(s) done"});
  const auto merged = runCli({"eval", "merge", (dir / "s1").string(), s2.string(), "--out", (dir / "m").string()});
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  expectSameFiles(dir / "whole", dir / "m");
}

// --- demonstrations ---------------------------------------------------------------

// Noisy actions make some episodes fail, so that objects need different
// numbers of rounds (one gives up after 6 attempts with 1 of 2): the order
// of the single run's file is then not object-major, and the merge must
// replay the rounds.
std::vector<std::string> demoArguments(const std::string& out, std::vector<std::string> extra = {}) {
  std::vector<std::string> a = {"demos", "generate", "Reach-v0", "--policy", "reach_expert", "--objects",
                                "0,1,2,3,4", "--per-object", "2", "--max-attempts", "6", "--action-noise",
                                "0.08", "--seed", "2", "--no-progress", "--out", out};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

TEST(DemoShards, ShardsMergeIntoTheSingleRunsTrajectoriesInItsOrder) {
  TempDir dir;
  const std::string whole = (dir / "whole.h5").string();
  const auto single = runCli(demoArguments(whole));
  ASSERT_TRUE(contains(single.out, "wrote 9 trajectories")) << single.out << single.err;
  std::vector<std::string> shards;
  for (const char* shard : {"1/3", "2/3", "3/3"}) {
    shards.push_back((dir / (std::string("s") + shard[0] + ".h5")).string());
    const auto r = runCli(demoArguments(shards.back(), {"--shard", shard}));
    ASSERT_TRUE(contains(r.out, "wrote")) << r.out << r.err;
  }
  const std::string merged = (dir / "merged.h5").string();
  const auto m = runCli({"demos", "merge", shards[2], shards[0], shards[1], "--out", merged});
  ASSERT_EQ(m.exit_code, 0) << m.err;
  const auto expected = readTrajectories(whole);
  EXPECT_EQ(expected.size(), 9u);
  EXPECT_TRUE(readTrajectories(merged) == expected);
  // The file's order is by rounds: not simply object after object.
  const DemoReader reader(whole);
  std::vector<std::string> objects;
  for (const std::string& name : reader.getTrajectoryNames()) objects.push_back(reader.readSummary(name).object_id);
  EXPECT_FALSE(std::is_sorted(objects.begin(), objects.end())) << "the noise gave every object one round";

  // Two shards only: the third's objects are named.
  const auto partial = runCli({"demos", "merge", shards[0], shards[1], "--out", (dir / "p.h5").string()});
  EXPECT_EQ(partial.exit_code, 1);
  testing::expectMentions(partial.err, {"missing: object 2: 0 of 2", "object(s) unfinished"});
  // Another run's shard.
  const std::string other = (dir / "other.h5").string();
  ASSERT_NE(runCli(demoArguments(other, {"--shard", "3/3", "--per-object", "1"})).exit_code, 2);
  const auto mismatch = runCli({"demos", "merge", shards[0], shards[1], other, "--out", (dir / "x.h5").string()});
  EXPECT_EQ(mismatch.exit_code, 1);
  testing::expectMentions(mismatch.err, {"another generation", "per_object: 2 vs 1"});
}

TEST(DemoShards, ResumeCompletesAStoppedFileAsTheSingleRunWritesIt) {
  TempDir dir;
  const std::string whole = (dir / "whole.h5").string();
  ASSERT_NE(runCli(demoArguments(whole)).exit_code, 2);
  // A run cut short: only the first trajectories, as a file killed after
  // them keeps (its generation_result never written).
  const std::string cut = (dir / "cut.h5").string();
  {
    const DemoReader reader(whole);
    DemoFileInfo info = reader.getInfo();
    info.generation_result.clear();
    DemoWriter writer(cut, info);
    for (std::size_t i = 0; i < 4; ++i) writer.append(reader.read(reader.getTrajectoryNames()[i]));
    writer.close();
  }
  // Another run's options: an error before anything runs, the file kept.
  const auto other = runCli(demoArguments(cut, {"--resume", "--seed", "4"}));
  EXPECT_EQ(other.exit_code, 1);
  testing::expectMentions(other.err, {"another generation", "seed: 2 vs 4"});
  EXPECT_EQ(DemoReader(cut).getTrajectoryNames().size(), 4u);
  const auto resumed = runCli(demoArguments(cut, {"--resume"}));
  testing::expectMentions(resumed.out, {"resumed " + cut + ": 9 trajectories"});
  EXPECT_TRUE(readTrajectories(cut) == readTrajectories(whole));
}

}  // namespace
}  // namespace manibench
