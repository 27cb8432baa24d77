// Issue 51's matrix, the output side: an output that cannot be created and a
// full disk, for every command that writes results (eval, demos generate,
// demos merge, demos convert). Each ends with exit status 1 and an error
// naming the file and the system's reason, never a crash; what eval had
// journaled before the disk filled is kept, and `--resume` completes the
// run.
//
// The full disk is RLIMIT_FSIZE with SIGXFSZ ignored (both inherited by the
// command and its workers): a write past the limit fails with EFBIG ("File
// too large") as one past a full disk fails with ENOSPC, through the same
// error paths.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>

#include "test_support.hpp"

namespace manibench {
namespace {

namespace fs = std::filesystem;
using testing::runCli;

fs::path makeDir() {
  const fs::path dir = fs::temp_directory_path() / ("manibench_output_faults_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// In the forked child before the exec: files the command writes may grow
// to `bytes`, and a write past that fails instead of killing it.
std::function<void()> limitFileSize(rlim_t bytes) {
  return [bytes] {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{bytes, bytes};
    setrlimit(RLIMIT_FSIZE, &limit);
  };
}

std::size_t countLines(const fs::path& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

const std::vector<std::string> kEval = {"eval", "Reach-v0", "--policy", "reach_expert", "--objects", "8,9",
                                        "--episodes-per-object", "20", "--no-progress"};
const std::vector<std::string> kGenerate = {"demos", "generate", "Reach-v0", "--policy", "reach_expert",
                                            "--objects", "0,1", "--per-object", "3", "--no-progress"};

std::vector<std::string> with(std::vector<std::string> arguments, const std::vector<std::string>& more) {
  arguments.insert(arguments.end(), more.begin(), more.end());
  return arguments;
}

TEST(OutputFaults, AnOutputThatCannotBeCreatedIsAClearError) {
  const fs::path dir = makeDir();
  const fs::path file = dir / "a_file";
  std::ofstream(file) << "not a folder\n";
  const std::string under = (file / "out").string();

  const auto eval = runCli(with(kEval, {"--out", under}));
  EXPECT_EQ(eval.exit_code, 1) << eval.err;
  EXPECT_NE(eval.err.find(under), std::string::npos) << eval.err;
  EXPECT_NE(eval.err.find("Not a directory"), std::string::npos) << eval.err;

  const auto generate = runCli(with(kGenerate, {"--out", under + "/demos.h5"}));
  EXPECT_EQ(generate.exit_code, 1) << generate.err;
  EXPECT_NE(generate.err.find(under + "/demos.h5"), std::string::npos) << generate.err;
  EXPECT_NE(generate.err.find("Not a directory"), std::string::npos) << generate.err;

  const std::string source = (dir / "source.h5").string();
  ASSERT_EQ(runCli(with(kGenerate, {"--out", source})).exit_code, 0);
  const auto convert = runCli({"demos", "convert", source, "--obs", "pointcloud", "--out", under + "/pc.h5"});
  EXPECT_EQ(convert.exit_code, 1) << convert.err;
  EXPECT_NE(convert.err.find(under + "/pc.h5"), std::string::npos) << convert.err;
  EXPECT_NE(convert.err.find("Not a directory"), std::string::npos) << convert.err;
  fs::remove_all(dir);
}

TEST(OutputFaults, AFullDiskIsAClearErrorAndEvalKeepsWhatItJournaled) {
  const fs::path dir = makeDir();
  // eval: the journal fills first (an episode's line is about 600 bytes).
  const fs::path out = dir / "eval";
  const auto full = runCli(with(kEval, {"--out", out.string()}), {}, limitFileSize(8192));
  EXPECT_EQ(full.exit_code, 1) << full.err;
  EXPECT_NE(full.err.find((out / "journal.jsonl").string()), std::string::npos) << full.err;
  EXPECT_NE(full.err.find("File too large"), std::string::npos) << full.err;
  const std::size_t journaled = countLines(out / "journal.jsonl");
  EXPECT_GE(journaled, 3u);  // the header and episodes
  // With room again, --resume runs what is missing: every episode once.
  const auto resumed = runCli(with(kEval, {"--out", out.string(), "--resume"}));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_EQ(countLines(out / "episodes.csv"), 1u + 40u);

  // demos generate: HDF5's write fails; the command says why and exits 1
  // (it once segfaulted in HDF5's exit clean-up after printing the error).
  const std::string demos = (dir / "demos.h5").string();
  const auto generate = runCli(with(kGenerate, {"--out", demos}), {}, limitFileSize(8192));
  EXPECT_EQ(generate.exit_code, 1) << generate.err;
  EXPECT_NE(generate.err.find(demos), std::string::npos) << generate.err;
  EXPECT_NE(generate.err.find("File too large"), std::string::npos) << generate.err;

  // demos merge: the same (the shards stay as they were).
  std::vector<std::string> shards;
  for (const char* shard : {"1/2", "2/2"}) {
    shards.push_back((dir / ("shard" + std::string(1, shard[0]) + ".h5")).string());
    ASSERT_EQ(runCli(with(kGenerate, {"--shard", shard, "--out", shards.back()})).exit_code, 0);
  }
  const std::string merged = (dir / "merged.h5").string();
  const auto merge = runCli({"demos", "merge", shards[0], shards[1], "--out", merged}, {}, limitFileSize(8192));
  EXPECT_EQ(merge.exit_code, 1) << merge.err;
  EXPECT_NE(merge.err.find(merged), std::string::npos) << merge.err;
  EXPECT_NE(merge.err.find("File too large"), std::string::npos) << merge.err;
  ASSERT_EQ(runCli({"demos", "merge", shards[0], shards[1], "--out", merged}).exit_code, 0);

  // demos convert: each trajectory it could not write is named.
  const std::string source = (dir / "source.h5").string();
  ASSERT_EQ(runCli(with(kGenerate, {"--out", source})).exit_code, 0);
  const auto convert = runCli({"demos", "convert", source, "--obs", "pointcloud", "--out", (dir / "pc.h5").string()},
                              {}, limitFileSize(40 * 1024));
  EXPECT_EQ(convert.exit_code, 1) << convert.err;
  const std::string said = convert.out + convert.err;  // the list is on stdout, the count on stderr
  EXPECT_NE(said.find("not converted: traj_0"), std::string::npos) << said;
  EXPECT_NE(said.find("File too large"), std::string::npos) << said;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace manibench
