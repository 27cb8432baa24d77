#include "bench_run.hpp"

#include <chrono>
#include <cmath>
#include <exception>

namespace manibench::bench {

double uniformAt(double lo, double hi, std::uint64_t seed, long episode, long tick, int index) {
  std::uint64_t z = (seed * 0x2545F4914F6CDD1DULL) ^ (static_cast<std::uint64_t>(episode) << 40) ^
                    (static_cast<std::uint64_t>(tick) << 8) ^ static_cast<std::uint64_t>(index);
  z += 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return lo + (hi - lo) * static_cast<double>(z >> 11) * 0x1.0p-53;
}

double SceneRun::measure(double seconds) {
  using Clock = std::chrono::steady_clock;
  if (!ok()) return std::nan("");
  long steps = 0;
  const Clock::time_point start = Clock::now();
  double elapsed = 0;
  do {
    envStep();
    ++steps;
    elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  } while (ok() && elapsed < seconds);
  endWindow();
  return ok() ? steps / elapsed : std::nan("");
}

void SceneRun::runEpisodes(long count) {
  while (ok() && episodes_ < count) envStep();
}

std::string SceneRun::getProblem() const {
  std::string problem = failure_.empty() ? problem_ : failure_;
  const std::string engine_problems = getEngineProblems();
  if (!engine_problems.empty()) problem += (problem.empty() ? "" : "; ") + engine_problems;
  return problem;
}

void SceneRun::envStep() {
  try {
    runEnvStep();
    ++env_steps_;
  } catch (const std::exception& e) {
    failure_ = std::string("simulation failed: ") + e.what();
  }
}

}  // namespace manibench::bench
