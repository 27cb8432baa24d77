#include <manibench/pointcloud.hpp>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace manibench {
namespace {

// SplitMix64: small, fast and the same on every platform and standard
// library (std::uniform_int_distribution is not), so that a seed gives
// the same cloud everywhere.
class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // In [0, bound): multiply-shift; the bias (bound / 2^64) is negligible.
  uint64_t below(uint64_t bound) {
    return static_cast<uint64_t>((static_cast<unsigned __int128>(next()) * bound) >> 64);
  }

 private:
  uint64_t state_;
};

// Marks `count` of `candidates` (all when it has no more) as chosen, at
// random without replacement (a partial Fisher-Yates shuffle).
void chooseSome(std::vector<uint32_t>& candidates, std::size_t count, SplitMix64& rng,
                std::vector<std::uint8_t>& chosen) {
  const std::size_t n = candidates.size();
  if (count >= n) {
    for (uint32_t i : candidates) chosen[i] = 1;
    return;
  }
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = i + static_cast<std::size_t>(rng.below(n - i));
    std::swap(candidates[i], candidates[j]);
    chosen[candidates[i]] = 1;
  }
}

}  // namespace

void PointCloud::appendFrom(const PointCloud& other, std::size_t i) {
  xyz.insert(xyz.end(), other.xyz.begin() + 3 * i, other.xyz.begin() + 3 * i + 3);
  rgb.insert(rgb.end(), other.rgb.begin() + 3 * i, other.rgb.begin() + 3 * i + 3);
  masks.insert(masks.end(), other.masks.begin() + std::size_t(mask_count) * i,
               other.masks.begin() + std::size_t(mask_count) * (i + 1));
}

void PointCloud::appendZero() {
  xyz.insert(xyz.end(), 3, 0.0f);
  rgb.insert(rgb.end(), 3, 0.0f);
  masks.insert(masks.end(), mask_count, 0);
}

std::vector<uint32_t> selectPointCloudSample(const PointCloud& raw,
                                             const PointCloudSampling& sampling,
                                             uint64_t seed) {
  const std::size_t n = raw.size();
  const std::size_t k = raw.mask_count;
  if (raw.xyz.size() != 3 * n || raw.rgb.size() != 3 * n || raw.masks.size() != k * n)
    throw std::invalid_argument(
        "point cloud arrays disagree: " + std::to_string(raw.xyz.size()) + " xyz values, " +
        std::to_string(raw.rgb.size()) + " rgb values and " + std::to_string(raw.masks.size()) +
        " mask values for " + std::to_string(k) + " masks");
  if (n > UINT32_MAX) throw std::invalid_argument("point cloud has more than 2^32 points");
  if (sampling.masked_total > sampling.total)
    throw std::invalid_argument("point cloud sampling: masked_total (" +
                                std::to_string(sampling.masked_total) + ") exceeds total (" +
                                std::to_string(sampling.total) + ")");
  SplitMix64 rng(seed);
  std::vector<std::uint8_t> chosen(n, 0);
  std::vector<uint32_t> candidates;
  candidates.reserve(n);

  // 1. Every mask gets up to per_mask points of its own.
  for (std::size_t m = 0; m < k; ++m) {
    candidates.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (raw.masks[i * k + m]) candidates.push_back(uint32_t(i));
    chooseSome(candidates, sampling.per_mask, rng, chosen);
  }
  // 2. More masked points up to masked_total.
  std::size_t masked = 0, masked_chosen = 0;
  candidates.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* bits = raw.masks.data() + i * k;
    if (std::none_of(bits, bits + k, [](std::uint8_t b) { return b != 0; })) continue;
    ++masked;
    if (chosen[i])
      ++masked_chosen;
    else
      candidates.push_back(uint32_t(i));
  }
  const std::size_t masked_goal = std::min<std::size_t>(sampling.masked_total, masked);
  if (masked_goal > masked_chosen) {
    chooseSome(candidates, masked_goal - masked_chosen, rng, chosen);
    masked_chosen = masked_goal;
  }
  std::vector<uint32_t> out;
  out.reserve(std::max<std::size_t>(sampling.total, masked_chosen));
  for (std::size_t i = 0; i < n; ++i)
    if (chosen[i]) out.push_back(uint32_t(i));
  // 3. Background above the ground fills up to total.
  if (sampling.total > out.size()) {
    candidates.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint8_t* bits = raw.masks.data() + i * k;
      if (!chosen[i] && raw.xyz[3 * i + 2] > sampling.ground_height &&
          std::none_of(bits, bits + k, [](std::uint8_t b) { return b != 0; }))
        candidates.push_back(uint32_t(i));
    }
    std::vector<std::uint8_t> background(n, 0);
    chooseSome(candidates, sampling.total - out.size(), rng, background);
    for (std::size_t i = 0; i < n; ++i)
      if (background[i]) out.push_back(uint32_t(i));
  }
  return out;
}

PointCloud samplePointCloud(const PointCloud& raw, const PointCloudSampling& sampling,
                            uint64_t seed) {
  const std::vector<uint32_t> indices = selectPointCloudSample(raw, sampling, seed);
  PointCloud out;
  out.mask_count = raw.mask_count;
  const std::size_t size = sampling.pad ? std::max<std::size_t>(indices.size(), sampling.total)
                                        : indices.size();
  out.xyz.reserve(3 * size);
  out.rgb.reserve(3 * size);
  out.masks.reserve(std::size_t(raw.mask_count) * size);
  for (uint32_t i : indices) out.appendFrom(raw, i);
  while (out.size() < size) out.appendZero();
  return out;
}

}  // namespace manibench
