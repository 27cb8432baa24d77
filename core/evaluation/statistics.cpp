// The statistics of evaluation reports (statistics.hpp; the formulas in
// docs/evaluation.md, "Intervals" and "Comparing two policies").
#include <manibench/error.hpp>
#include <manibench/statistics.hpp>

#include <algorithm>
#include <cmath>

namespace manibench {
namespace {

// The p-quantile of sorted values (linear between neighbours).
double calcQuantile(const std::vector<double>& sorted, double p) {
  const double at = p * double(sorted.size() - 1);
  const std::size_t below = std::size_t(at);
  if (below + 1 >= sorted.size()) return sorted.back();
  return sorted[below] + (at - double(below)) * (sorted[below + 1] - sorted[below]);
}

// The paired difference of resampled pairs: n draws among the four kinds.
double drawPairedDifference(sdk::Random& random, const PairedCounts& c) {
  int64_t net = 0;
  for (uint32_t i = 0; i < c.pairs; ++i) {
    const std::size_t j = random.below(c.pairs);
    if (j < c.only_a)
      ++net;
    else if (j < std::size_t(c.only_a) + c.only_b)
      --net;
  }
  return double(net) / double(c.pairs);
}

void calcPercentiles(std::vector<double>& values, double& low, double& high) {
  std::sort(values.begin(), values.end());
  low = calcQuantile(values, 0.025);
  high = calcQuantile(values, 0.975);
}

// The interval of a pooled paired difference, resampling its pairs.
void calcPairsBootstrap(const PairedCounts& c, uint64_t seed, double& low, double& high) {
  if (c.pairs == 0) {
    low = -1;
    high = 1;
    return;
  }
  sdk::Random random(seed);
  std::vector<double> values;
  values.reserve(kBootstrapResamples);
  for (int b = 0; b < kBootstrapResamples; ++b) values.push_back(drawPairedDifference(random, c));
  calcPercentiles(values, low, high);
}

}  // namespace

void calcWilsonInterval(uint64_t successes, uint64_t n, double& low, double& high) {
  if (n == 0) {
    low = 0;
    high = 1;
    return;
  }
  const double z = 1.959963984540054;  // the normal's 97.5 % quantile
  const double p = double(successes) / double(n), z2n = z * z / double(n);
  const double centre = (p + z2n / 2) / (1 + z2n);
  const double half = z / (1 + z2n) * std::sqrt(p * (1 - p) / double(n) + z2n / (4 * double(n)));
  low = std::max(0.0, centre - half);
  high = std::min(1.0, centre + half);
  // Exact at the ends: no successes (failures) gives low (high) = 0 (1).
  if (successes == 0) low = 0;
  if (successes == n) high = 1;
}

void calcBootstrapInterval(const std::vector<uint32_t>& successes, const std::vector<uint32_t>& episodes,
                           uint64_t seed, double& low, double& high) {
  const std::size_t k = successes.size();
  if (k == 0) {
    low = 0;
    high = 1;
    return;
  }
  if (k == 1) return calcWilsonInterval(successes[0], episodes[0], low, high);
  sdk::Random random(seed);
  std::vector<double> rates;
  rates.reserve(kBootstrapResamples);
  for (int b = 0; b < kBootstrapResamples; ++b) {
    uint64_t s = 0, n = 0;
    for (std::size_t i = 0; i < k; ++i) {
      const std::size_t j = random.below(k);
      s += successes[j];
      n += episodes[j];
    }
    rates.push_back(n ? double(s) / double(n) : 0);
  }
  std::sort(rates.begin(), rates.end());
  low = calcQuantile(rates, 0.025);
  high = calcQuantile(rates, 0.975);
}

void calcOverallInterval(const std::vector<uint32_t>& successes, const std::vector<uint32_t>& episodes,
                         double& low, double& high) {
  calcBootstrapInterval(successes, episodes, kBootstrapSeed, low, high);
  // A percentile bootstrap cannot leave the range of the objects' rates
  // (every object at 1 gives [1, 1]): the pooled episodes' Wilson interval
  // bounds it from the episodes' side.
  uint64_t s = 0, n = 0;
  for (std::size_t i = 0; i < successes.size(); ++i) {
    s += successes[i];
    n += episodes[i];
  }
  double pooled_low, pooled_high;
  calcWilsonInterval(s, n, pooled_low, pooled_high);
  low = std::min(low, pooled_low);
  high = std::max(high, pooled_high);
}

double calcExactMcNemarP(uint32_t only_a, uint32_t only_b) {
  const uint32_t n = only_a + only_b, k = std::min(only_a, only_b);
  if (n == 0) return 1;
  // P(X <= k) for X ~ Binomial(n, 1/2), summed in logarithms (n may be large).
  double tail = 0;
  for (uint32_t i = 0; i <= k; ++i)
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) - n * std::log(2.0));
  return std::min(1.0, 2 * tail);
}

std::vector<PairedDifference> comparePaired(const std::vector<PairedCounts>& objects, PairedDifference& overall) {
  std::vector<PairedDifference> out;
  PairedCounts all;
  all.object = "all";
  for (const PairedCounts& c : objects) {
    PairedDifference d;
    d.counts = c;
    d.difference = c.pairs ? (double(c.only_a) - double(c.only_b)) / c.pairs : 0;
    calcPairsBootstrap(c, kBootstrapSeed, d.low, d.high);
    d.p_value = calcExactMcNemarP(c.only_a, c.only_b);
    out.push_back(d);
    all.pairs += c.pairs;
    all.successes_a += c.successes_a;
    all.successes_b += c.successes_b;
    all.only_a += c.only_a;
    all.only_b += c.only_b;
  }
  overall = PairedDifference();
  overall.counts = all;
  overall.difference = all.pairs ? (double(all.only_a) - double(all.only_b)) / all.pairs : 0;
  overall.p_value = calcExactMcNemarP(all.only_a, all.only_b);
  if (objects.size() < 2) {
    calcPairsBootstrap(all, kBootstrapSeed, overall.low, overall.high);
    return out;
  }
  // Objects drawn with replacement: the pooled difference of each draw.
  sdk::Random random(kBootstrapSeed);
  std::vector<double> values;
  values.reserve(kBootstrapResamples);
  for (int b = 0; b < kBootstrapResamples; ++b) {
    int64_t net = 0, pairs = 0;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const PairedCounts& c = objects[random.below(objects.size())];
      net += int64_t(c.only_a) - int64_t(c.only_b);
      pairs += c.pairs;
    }
    values.push_back(pairs ? double(net) / double(pairs) : 0);
  }
  calcPercentiles(values, overall.low, overall.high);
  double pooled_low, pooled_high;
  calcPairsBootstrap(all, kBootstrapSeed, pooled_low, pooled_high);
  overall.low = std::min(overall.low, pooled_low);
  overall.high = std::max(overall.high, pooled_high);
  return out;
}

uint64_t calcPairsNeeded(double discordance, double margin) {
  if (!(margin > 0 && margin <= 1)) throw InvalidArgument("the margin must be in (0, 1], got " + std::to_string(margin));
  const double z_alpha = 1.959963984540054, z_beta = 0.8416212335729143;  // the normal's 97.5 % and 80 % quantiles
  const double psi = std::min(1.0, std::max(discordance, margin));
  const double root = z_alpha * std::sqrt(psi) + z_beta * std::sqrt(std::max(0.0, psi - margin * margin));
  return uint64_t(std::ceil(root * root / (margin * margin)));
}

}  // namespace manibench
