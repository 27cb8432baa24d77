// MPI ranks (docs/distributed.md): `mpirun -np 3 manibench eval` writes the
// files one process writes, byte for byte; a rank killed outright loses
// only its unfinished episodes, which --resume then runs. Open MPI refuses
// root unless told (CI runs as root), and this machine has fewer cores
// than ranks (--oversubscribe).
#include <dirent.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <functional>
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

const std::vector<std::string> kMpirun = {"--allow-run-as-root", "--oversubscribe", "--mca", "btl", "self,vader",
                                          "-x", "MANIBENCH_PLUGIN_PATH"};

std::vector<std::string> evalArguments(const fs::path& out, const std::string& levels,
                                       const std::string& steps = "25") {
  return {"eval", "Reach-v0", "--policy", "random", "--objects", "8,11", "--levels", levels,
          "--set", "episode.max_steps=" + steps, "--no-progress", "--out", out.string()};
}

std::vector<std::string> underMpirun(int ranks, const std::vector<std::string>& arguments) {
  std::vector<std::string> a = kMpirun;
  a.insert(a.end(), {"-np", std::to_string(ranks), MANIBENCH_TEST_CLI});
  a.insert(a.end(), arguments.begin(), arguments.end());
  return a;
}

TEST(Mpi, ThreeRanksWriteWhatOneProcessWrites) {
  TempDir dir;
  ASSERT_EQ(runCli(evalArguments(dir / "one", "0-4")).exit_code, 0);
  const auto three = testing::runProgram(MANIBENCH_TEST_MPIRUN, underMpirun(3, evalArguments(dir / "three", "0-4")));
  ASSERT_EQ(three.exit_code, 0) << three.out << three.err;
  testing::expectMentions(three.out, {"3 MPI rank(s)", "10 of 10 episodes"});
  expectSameFiles(dir / "one", dir / "three");
  // Rank 0 alone prints and writes: one table, one set of files.
  EXPECT_EQ(three.out.find("evaluating"), three.out.rfind("evaluating")) << three.out;
  const auto single = testing::runProgram(MANIBENCH_TEST_MPIRUN, underMpirun(1, evalArguments(dir / "mpi1", "0-4")));
  ASSERT_EQ(single.exit_code, 0) << single.out << single.err;
  expectSameFiles(dir / "one", dir / "mpi1");
}

// Noise makes objects need different numbers of rounds (docs/distributed.md):
// rank 0 gets the trajectories in any order and must write the single run's.
TEST(Mpi, ThreeRanksGenerateTheTrajectoriesOneProcessGenerates) {
  TempDir dir;
  auto arguments = [](const std::string& out) {
    return std::vector<std::string>{"demos", "generate", "Reach-v0", "--policy", "reach_expert", "--objects",
                                    "0,1,2,3,4", "--per-object", "2", "--max-attempts", "6", "--action-noise",
                                    "0.08", "--seed", "2", "--no-progress", "--out", out};
  };
  const std::string one = (dir / "one.h5").string(), three = (dir / "three.h5").string();
  const auto single = runCli(arguments(one));
  ASSERT_TRUE(contains(single.out, "wrote 9 trajectories")) << single.out << single.err;
  const auto ranks = testing::runProgram(MANIBENCH_TEST_MPIRUN, underMpirun(3, arguments(three)));
  ASSERT_TRUE(contains(ranks.out, "3 MPI rank(s)")) << ranks.out << ranks.err;
  ASSERT_TRUE(contains(ranks.out, "wrote 9 trajectories")) << ranks.out << ranks.err;
  EXPECT_TRUE(readTrajectories(three) == readTrajectories(one));
  EXPECT_FALSE(fs::exists(three + ".unordered.h5"));
}

// The rank of an Open MPI process, from its environment; -1 if none.
int readRank(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/environ", std::ios::binary);
  std::string entry;
  while (std::getline(in, entry, '\0'))
    if (entry.rfind("OMPI_COMM_WORLD_RANK=", 0) == 0) return std::stoi(entry.substr(21));
  return -1;
}

std::vector<pid_t> listChildren(pid_t parent) {
  std::vector<pid_t> children;
  DIR* proc = opendir("/proc");
  while (dirent* e = readdir(proc)) {
    const pid_t pid = atoi(e->d_name);
    if (pid <= 0) continue;
    std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
    std::string text;
    std::getline(stat, text);
    const std::size_t close = text.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream fields(text.substr(close + 2));
    char state;
    pid_t ppid = 0;
    fields >> state >> ppid;
    if (ppid == parent) children.push_back(pid);
  }
  closedir(proc);
  return children;
}

TEST(Mpi, KilledRankLosesOnlyItsUnfinishedEpisodesAndResumeCompletes) {
  TempDir dir;
  const fs::path out = dir / "ranks";
  ASSERT_EQ(runCli(evalArguments(dir / "one", "0-29", "150")).exit_code, 0);
  std::vector<std::string> words = underMpirun(3, evalArguments(out, "0-29", "150"));
  words.insert(words.begin(), MANIBENCH_TEST_MPIRUN);
  const pid_t mpirun = testing::startInBackground(words);
  ASSERT_GT(mpirun, 0);
  // Rank 2 is killed once rank 0's journal has a few episodes.
  for (int i = 0; i < 6000 && countEpisodes(out / "journal.jsonl") < 4; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  pid_t victim = -1;
  for (pid_t child : listChildren(mpirun))
    if (readRank(child) == 2) victim = child;
  ASSERT_GT(victim, 0);
  kill(victim, SIGKILL);
  int status = 0;
  waitpid(mpirun, &status, 0);
  const std::size_t kept = countEpisodes(out / "journal.jsonl");
  ASSERT_GE(kept, 4u);
  ASSERT_LT(kept, 60u) << "the run finished before the rank was killed";
  EXPECT_NE(status, 0);

  const auto resumed = testing::runProgram(MANIBENCH_TEST_MPIRUN, [&] {
    auto a = underMpirun(2, evalArguments(out, "0-29", "150"));
    a.push_back("--resume");
    return a;
  }());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out << resumed.err;
  testing::expectMentions(resumed.out, {"resuming: " + std::to_string(kept) + " episode(s) done"});
  expectSameFiles(dir / "one", out);
  EXPECT_EQ(countEpisodes(out / "journal.jsonl"), 60u);  // nothing twice
}

// What Slurm sends at a time limit: mpirun forwards it, rank 0 writes the
// episodes it has as partial results, as a single run does.
TEST(Mpi, SigtermOnMpirunLeavesReadablePartialResults) {
  TempDir dir;
  const fs::path out = dir / "ranks";
  std::vector<std::string> words = underMpirun(3, evalArguments(out, "0-199", "150"));
  words.insert(words.begin(), MANIBENCH_TEST_MPIRUN);
  const pid_t mpirun = testing::startInBackground(words);
  ASSERT_GT(mpirun, 0);
  for (int i = 0; i < 6000 && countEpisodes(out / "journal.jsonl") < 4; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  kill(mpirun, SIGTERM);
  int status = 0;
  waitpid(mpirun, &status, 0);
  const std::string json = readFile(out / "summary.json");
  EXPECT_TRUE(contains(json, "\"complete\": false")) << json;
  EXPECT_TRUE(contains(json, "\"episodes_planned\": 400")) << json;
  const auto episodes = readCsv(out / "episodes.csv");
  EXPECT_GE(episodes.size(), 4u);
  EXPECT_LT(episodes.size(), 400u);
  EXPECT_EQ(episodes.size(), countEpisodes(out / "journal.jsonl"));
}

// A stop signal at any moment keeps every episode the journal has: the
// files say what it says, whatever the timing (issue 43: once, under load,
// mpirun's SIGTERM left 15 journaled episodes and no files). Each run is
// signalled at one point: as soon as the journal exists (before any episode
// finished), mid-run, or when the files are being written (a second signal
// for a single process, whose first one stopped the run; mpirun's SIGTERM
// after a run that finished). The last point is sought by polling, so a run
// may also be signalled just before or after it: the checks hold for all.
enum class StopPoint { kJournalCreated, kMidRun, kWritingFiles };

struct StopCase {
  int ranks;  // 0: no mpirun
  StopPoint point;
};

class StopAt : public ::testing::TestWithParam<StopCase> {};

// The journal's episodes, by index (none when it was never created).
std::vector<uint64_t> listJournaled(const fs::path& journal) {
  std::vector<uint64_t> indices;
  if (!fs::exists(journal)) return indices;
  for (const EpisodeRecord& r : readJournal(journal.string()).result.episodes) indices.push_back(r.spec.index);
  std::sort(indices.begin(), indices.end());
  return indices;
}

TEST_P(StopAt, FilesAgreeWithTheJournal) {
  const StopCase c = GetParam();
  TempDir dir;
  const fs::path out = dir / "run";
  // Few episodes where the files are what is waited for, so the run ends.
  const std::string levels = c.point == StopPoint::kWritingFiles && c.ranks > 0 ? "0-5" : "0-199";
  std::vector<std::string> words = evalArguments(out, levels, "150");
  if (c.ranks > 0) {
    words = underMpirun(c.ranks, words);
    words.insert(words.begin(), MANIBENCH_TEST_MPIRUN);
  } else {
    words.insert(words.begin(), MANIBENCH_TEST_CLI);
  }
  const pid_t pid = testing::startInBackground(words);
  ASSERT_GT(pid, 0);
  // Polls `ready` every `ms` milliseconds (0: as fast as it can), at most a
  // minute: a loaded machine's startup is slow.
  auto waitFor = [](const std::function<bool()>& ready, int ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!ready() && std::chrono::steady_clock::now() < end)
      std::this_thread::sleep_for(std::chrono::milliseconds(ms));
  };
  const fs::path journal = out / "journal.jsonl";
  auto writing = [&] { return fs::exists(out / "summary.csv.partial") || fs::exists(out / "summary.csv"); };
  switch (c.point) {
    case StopPoint::kJournalCreated:
      waitFor([&] { return fs::exists(journal); }, 1);
      kill(pid, SIGTERM);
      break;
    case StopPoint::kMidRun:
      waitFor([&] { return countEpisodes(journal) >= 4; }, 10);
      kill(pid, SIGTERM);
      break;
    case StopPoint::kWritingFiles:
      if (c.ranks == 0) {
        waitFor([&] { return countEpisodes(journal) >= 4; }, 10);
        kill(pid, SIGTERM);
      }
      waitFor(writing, 0);
      kill(pid, SIGTERM);
      break;
  }
  int status = 0;
  waitpid(pid, &status, 0);
  const std::vector<uint64_t> journaled = listJournaled(journal);
  if (!fs::exists(journal)) {
    EXPECT_FALSE(fs::exists(out / "summary.json"));
    return;
  }
  const std::string json = readFile(out / "summary.json");
  ASSERT_FALSE(json.empty()) << journaled.size() << " journaled episode(s) and no summary.json";
  const std::size_t planned = c.ranks > 0 && c.point == StopPoint::kWritingFiles ? 12 : 400;
  EXPECT_TRUE(contains(json, "\"episodes_planned\": " + std::to_string(planned))) << json;
  EXPECT_TRUE(contains(json, journaled.size() < planned ? "\"complete\": false" : "\"complete\": true")) << json;
  std::vector<uint64_t> reported;
  for (const auto& row : readCsv(out / "episodes.csv")) reported.push_back(std::stoull(row.at("index")));
  std::sort(reported.begin(), reported.end());
  EXPECT_EQ(reported, journaled);
}

const StopCase kStopCases[] = {{0, StopPoint::kJournalCreated}, {0, StopPoint::kMidRun},
                               {0, StopPoint::kWritingFiles},   {3, StopPoint::kJournalCreated},
                               {3, StopPoint::kMidRun},         {3, StopPoint::kWritingFiles}};

std::string nameStopCase(const ::testing::TestParamInfo<StopCase>& info) {
  const char* point[] = {"JournalCreated", "MidRun", "WritingFiles"};
  return std::string(info.param.ranks ? "Mpirun" : "Single") + point[int(info.param.point)];
}

INSTANTIATE_TEST_SUITE_P(Points, StopAt, ::testing::ValuesIn(kStopCases), nameStopCase);

}  // namespace
}  // namespace manibench
