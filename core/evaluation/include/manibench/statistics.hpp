// The statistics of evaluation reports (docs/evaluation.md, "Intervals"
// and "Comparing two policies"): Wilson's interval for one object's
// episodes, a bootstrap over objects for a rate over the split, and the
// paired comparison of two reports of the same episodes (a bootstrap
// interval of the difference, the exact McNemar test, the episodes needed
// to separate two policies at a margin). Deterministic: resampling uses a
// fixed seed and its own generator.
#pragma once

#include <manibench/sdk/random.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace manibench {

// Wilson's 95 % score interval for `successes` of `n` (0 <= low <= high
// <= 1; [0, 1] for n = 0).
void calcWilsonInterval(uint64_t successes, uint64_t n, double& low, double& high);
// The resamples and the seed of the bootstraps (fixed: the same episodes
// give the same interval); draws come from sdk::Random (SplitMix64), the
// same numbers on every platform, unlike the standard distributions.
inline constexpr int kBootstrapResamples = 2000;
inline constexpr uint64_t kBootstrapSeed = 0x6d616e6962656e63ULL;
// The 95 % percentile bootstrap interval of sum(successes) / sum(episodes)
// over objects drawn with replacement (kBootstrapResamples, sdk::Random(seed));
// with one object, that object's Wilson interval.
void calcBootstrapInterval(const std::vector<uint32_t>& successes, const std::vector<uint32_t>& episodes,
                           uint64_t seed, double& low, double& high);
// The overall line's interval: the wider of the bootstrap over objects and
// the Wilson interval of all episodes pooled (the bootstrap alone collapses
// to a point when every object's rate is the same, 1 say).
void calcOverallInterval(const std::vector<uint32_t>& successes, const std::vector<uint32_t>& episodes,
                         double& low, double& high);

// --- paired comparison: the same (object, level, seed) episodes under two
// policies A and B ---

// One object's episode pairs, by kind.
struct PairedCounts {
  std::string object;  // "all" for the overall line
  uint32_t pairs = 0;
  uint32_t successes_a = 0, successes_b = 0;
  uint32_t only_a = 0, only_b = 0;  // discordant pairs: A succeeded and B not, and the other way
};

struct PairedDifference {
  PairedCounts counts;
  double difference = 0;      // rate of A minus rate of B: (only_a - only_b) / pairs
  double low = 0, high = 0;   // its 95 % interval
  double p_value = 1;         // exact McNemar (two-sided sign test on the discordant pairs)
};

// Two-sided exact McNemar test: P(a count as far from (only_a + only_b) / 2
// as observed) under Binomial(only_a + only_b, 1/2); 1 without discordant pairs.
double calcExactMcNemarP(uint32_t only_a, uint32_t only_b);

// Per object: the difference with a bootstrap interval over its episode
// pairs; overall (`overall`): pooled over objects, with a bootstrap that
// resamples objects (widened to the pooled pairs' own bootstrap where
// that is wider, as for rates); each with its McNemar p-value.
std::vector<PairedDifference> comparePaired(const std::vector<PairedCounts>& objects, PairedDifference& overall);

// Episode pairs needed to tell a difference of `margin` from none with a
// two-sided 5 % McNemar test at 80 % power, when a fraction `discordance`
// of pairs is discordant (Connor 1987):
//   n = (z_0.975 sqrt(psi) + z_0.8 sqrt(psi - margin^2))^2 / margin^2,
// with psi = max(discordance, margin). Throws InvalidArgument unless
// 0 < margin <= 1.
uint64_t calcPairsNeeded(double discordance, double margin);

}  // namespace manibench
