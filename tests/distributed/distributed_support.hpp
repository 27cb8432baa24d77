// What the tests of shards, merges and MPI ranks share: the single run's
// files against another's, a journal's episodes, a demonstration file's
// trajectories as bytes, a command started in the background.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <manibench/demos.hpp>
#include <manibench/evaluation.hpp>
#include <string>
#include <vector>

#include "eval_test_support.hpp"
#include "test_support.hpp"

namespace manibench::testing {

// episodes.csv, summary.csv, certificate.json and summary.json (but its
// timing line) the same.
inline void expectSameFiles(const fs::path& a, const fs::path& b) {
  EXPECT_EQ(readFile(a / "episodes.csv"), readFile(b / "episodes.csv")) << a << " vs " << b;
  EXPECT_EQ(readFile(a / "summary.csv"), readFile(b / "summary.csv")) << a << " vs " << b;
  EXPECT_EQ(readFile(a / "certificate.json"), readFile(b / "certificate.json")) << a << " vs " << b;
  EXPECT_EQ(withoutTiming(readFile(a / "summary.json")), withoutTiming(readFile(b / "summary.json")))
      << a << " vs " << b;
}

// The episode lines of a journal (0 when there is none yet).
inline std::size_t countEpisodes(const fs::path& journal) {
  const std::string text = readFile(journal);
  std::size_t n = 0;
  for (std::size_t at = 0; (at = text.find("\"episode\":", at)) != std::string::npos; ++at) ++n;
  return n;
}

// Every field of every trajectory, as bytes, in file order.
inline std::vector<std::string> readTrajectories(const std::string& path) {
  const DemoReader reader(path);
  std::vector<std::string> all;
  for (const std::string& name : reader.getTrajectoryNames()) {
    EpisodeRecord r;
    r.trajectory = std::make_shared<Trajectory>(reader.read(name));
    all.push_back(packEpisodeRecord(r));
  }
  return all;
}

// `words` (the program first, found in PATH) started in a process group of
// its own, its output to /dev/null; its process id.
inline pid_t startInBackground(std::vector<std::string> words) {
  const pid_t pid = fork();
  if (pid != 0) return pid;
  setpgid(0, 0);
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  const int null = open("/dev/null", O_WRONLY);
  dup2(null, 1);
  dup2(null, 2);
  execvp(argv[0], argv.data());
  _exit(127);
}

}  // namespace manibench::testing
