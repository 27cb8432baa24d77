// The statistics of reports (manibench/statistics.hpp): Wilson's interval
// and McNemar's exact test against values computed by hand, the sample
// size formula, the bootstrap intervals' coverage checked by simulation
// (1,000 synthetic reports of a known rate and of a known paired
// difference), and `manibench compare` on two real reports.
#include <gtest/gtest.h>

#include <manibench/error.hpp>
#include <manibench/statistics.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>

#include "eval_test_support.hpp"

namespace manibench {
namespace {

using testing::contains;

TEST(Statistics, WilsonIntervalsOfKnownCounts) {
  double low, high;
  calcWilsonInterval(5, 10, low, high);  // (p + z^2/2n) / (1 + z^2/n) -+ ...
  EXPECT_NEAR(low, 0.236593, 1e-6);
  EXPECT_NEAR(high, 0.763407, 1e-6);
  calcWilsonInterval(0, 10, low, high);
  EXPECT_EQ(low, 0);
  EXPECT_NEAR(high, 0.277533, 1e-6);
  calcWilsonInterval(5, 5, low, high);
  EXPECT_NEAR(low, 0.565518, 1e-6);
  EXPECT_EQ(high, 1);
  calcWilsonInterval(0, 0, low, high);
  EXPECT_EQ(low, 0);
  EXPECT_EQ(high, 1);
}

TEST(Statistics, McNemarExactAndPairsNeeded) {
  EXPECT_EQ(calcExactMcNemarP(0, 0), 1);
  EXPECT_NEAR(calcExactMcNemarP(4, 0), 0.125, 1e-12);              // 2 / 2^4
  EXPECT_NEAR(calcExactMcNemarP(1, 3), 0.625, 1e-12);              // 2 (1 + 4) / 16
  EXPECT_NEAR(calcExactMcNemarP(12, 0), 2.0 / 4096, 1e-15);
  EXPECT_NEAR(calcExactMcNemarP(30, 20), 0.20263, 1e-5);           // a sign test's table value
  EXPECT_EQ(calcExactMcNemarP(7, 7), 1);
  // psi 0.6, margin 0.1: (1.95996 sqrt(0.6) + 0.84162 sqrt(0.59))^2 / 0.01 = 468.5.
  EXPECT_EQ(calcPairsNeeded(0.6, 0.1), 469u);
  // A discordance below the margin is raised to it (every discordant pair one way).
  EXPECT_EQ(calcPairsNeeded(0.0, 0.2), calcPairsNeeded(0.2, 0.2));
  EXPECT_THROW(calcPairsNeeded(0.5, 0), InvalidArgument);
}

TEST(Statistics, BootstrapIsDeterministicAndOneObjectIsWilson) {
  const std::vector<uint32_t> successes = {3, 5, 1, 4}, episodes = {5, 5, 5, 5};
  double low1, high1, low2, high2;
  calcBootstrapInterval(successes, episodes, kBootstrapSeed, low1, high1);
  calcBootstrapInterval(successes, episodes, kBootstrapSeed, low2, high2);
  EXPECT_EQ(low1, low2);
  EXPECT_EQ(high1, high2);
  EXPECT_LT(low1, 13.0 / 20);
  EXPECT_GT(high1, 13.0 / 20);
  double wl, wh;
  calcWilsonInterval(3, 5, wl, wh);
  calcBootstrapInterval({3}, {5}, kBootstrapSeed, low1, high1);
  EXPECT_EQ(low1, wl);
  EXPECT_EQ(high1, wh);
  // Every object at 1: the bootstrap alone is [1, 1]; the overall interval
  // is the pooled Wilson interval.
  calcOverallInterval({5, 5, 5, 5}, {5, 5, 5, 5}, low1, high1);
  calcWilsonInterval(20, 20, wl, wh);
  EXPECT_EQ(low1, wl);
  EXPECT_EQ(high1, 1);
}

// A population of objects with known rates (the split's objects are a
// sample of it): 1,000 synthetic reports of 20 objects x 10 episodes.
struct Population {
  std::vector<double> a, b;  // per object: policy A's and B's success probability
  double mean_a = 0, difference = 0;
  explicit Population(uint64_t seed) {
    sdk::Random random(seed);
    auto uniform = [&] { return random.uniform(0, 1); };
    for (int i = 0; i < 200; ++i) {
      a.push_back(0.2 + 0.7 * uniform());
      b.push_back(std::clamp(a.back() - 0.1 + 0.2 * (uniform() - 0.5), 0.0, 1.0));
      mean_a += a.back() / 200;
      difference += (a.back() - b.back()) / 200;
    }
  }
};

TEST(Statistics, IntervalsCoverTheirTruthInSimulation) {
  const Population population(7);
  sdk::Random random(11);
  auto uniform = [&] { return random.uniform(0, 1); };
  int rate_covered = 0, difference_covered = 0;
  const int reports = 1000;
  for (int r = 0; r < reports; ++r) {
    std::vector<uint32_t> successes, episodes;
    std::vector<PairedCounts> pairs;
    for (int k = 0; k < 20; ++k) {
      const std::size_t object = random.below(population.a.size());
      PairedCounts c;
      c.object = std::to_string(k);
      for (int e = 0; e < 10; ++e) {
        // The same episode under both policies: correlated outcomes.
        const double u = uniform();
        const bool a = u < population.a[object];
        const bool b = (uniform() < 0.5 ? u : uniform()) < population.b[object];
        ++c.pairs;
        c.successes_a += a;
        c.successes_b += b;
        c.only_a += a && !b;
        c.only_b += b && !a;
      }
      successes.push_back(c.successes_a);
      episodes.push_back(c.pairs);
      pairs.push_back(c);
    }
    double low, high;
    calcOverallInterval(successes, episodes, low, high);
    rate_covered += low <= population.mean_a && population.mean_a <= high;
    PairedDifference overall;
    comparePaired(pairs, overall);
    difference_covered += overall.low <= population.difference && population.difference <= overall.high;
  }
  const double rate_coverage = double(rate_covered) / reports, difference_coverage = double(difference_covered) / reports;
  std::cout << "coverage of the 95 % intervals: rate " << rate_coverage << ", paired difference "
            << difference_coverage << " (true difference " << population.difference << ")\n";
  EXPECT_GE(rate_coverage, 0.92);
  EXPECT_LE(rate_coverage, 0.99);
  EXPECT_GE(difference_coverage, 0.92);
  EXPECT_LE(difference_coverage, 0.99);
}

TEST(Compare, PairsTheSameEpisodesAndRefusesOthers) {
  TempDir expert, random, other;
  const std::vector<std::string> common = {"Reach-v0", "--objects", "8,11", "--levels", "0-3", "--set",
                                           "episode.max_steps=30"};
  auto with = [&](const std::string& policy, std::vector<std::string> extra = {}) {
    std::vector<std::string> a = common;
    a.insert(a.end(), {"--policy", policy});
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  ASSERT_EQ(runEval(expert, with("reach_expert")).exit_code, 0);
  ASSERT_EQ(runEval(random, with("random")).exit_code, 0);
  ASSERT_EQ(runEval(other, with("random", {"--seed", "3"})).exit_code, 0);
  const auto r = testing::runCli({"compare", expert.path().string(), random.path().string(), "--margin", "0.2"});
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  // The counts are the episodes': only A = the expert's successes the random policy missed.
  const auto a = readCsv(expert / "episodes.csv"), b = readCsv(random / "episodes.csv");
  ASSERT_EQ(a.size(), b.size());
  int only_a = 0, only_b = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].at("seed"), b[i].at("seed"));
    only_a += a[i].at("success") == "1" && b[i].at("success") == "0";
    only_b += a[i].at("success") == "0" && b[i].at("success") == "1";
  }
  std::ostringstream p;
  p << std::setprecision(3) << calcExactMcNemarP(only_a, only_b);
  std::ostringstream all;
  all << "\nall" << std::string(7, ' ');
  EXPECT_TRUE(contains(r.out, "\nall ")) << r.out;
  EXPECT_TRUE(contains(r.out, " " + std::to_string(only_a) + " ")) << r.out;
  EXPECT_TRUE(contains(r.out, p.str() + "\n")) << p.str() << "\n" << r.out;
  EXPECT_TRUE(contains(r.out, "to tell a difference of 0.2 from none")) << r.out;
  const auto refused = testing::runCli({"compare", expert.path().string(), other.path().string()});
  EXPECT_EQ(refused.exit_code, 1);
  testing::expectMentions(refused.err, {"not of the same episodes", "seed: 0 in A, 3 in B"});
}

}  // namespace
}  // namespace manibench
