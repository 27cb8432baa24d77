#include <manibench/error.hpp>
#include <manibench/pointcloud.hpp>
#include <manibench/sdk/random.hpp>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace manibench {
namespace {

// Marks `count` of `candidates` (all when it has no more) as chosen, at
// random without replacement (a partial Fisher-Yates shuffle).
void chooseSome(std::vector<uint32_t>& candidates, std::size_t count, sdk::Random& rng,
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

void PointCloudSampler::clear() {
  masked_.clear();
  background_.clear();
  for (std::vector<uint32_t>& list : per_mask_) list.clear();
}

void PointCloudSampler::growMasks(std::uint64_t bits) {
  std::size_t count = 64;
  while (count > 0 && ((bits >> (count - 1)) & 1u) == 0) --count;
  if (count > per_mask_.size()) per_mask_.resize(count);
}

const std::vector<uint32_t>& PointCloudSampler::select(
    const PointCloudSampling& sampling, uint64_t seed,
    const std::function<bool(uint32_t)>& is_above_ground) {
  if (sampling.masked_total > sampling.total)
    throw InvalidArgument("point cloud sampling: masked_total (" +
                                std::to_string(sampling.masked_total) + ") exceeds total (" +
                                std::to_string(sampling.total) + ")");
  // The SDK's SplitMix64: the same numbers on every platform and standard
  // library (std::uniform_int_distribution's are not), so a seed gives the
  // same cloud everywhere.
  sdk::Random rng(seed);
  const std::size_t masked = masked_.size();
  chosen_.assign(masked, 0);
  // 1. Every mask gets up to per_mask points of its own (a point already
  // chosen for an earlier mask counts for this one too).
  for (std::vector<uint32_t>& list : per_mask_) chooseSome(list, sampling.per_mask, rng, chosen_);
  // 2. More masked points up to masked_total.
  std::size_t masked_chosen = 0;
  candidates_.clear();
  for (std::size_t p = 0; p < masked; ++p) {
    if (chosen_[p])
      ++masked_chosen;
    else
      candidates_.push_back(uint32_t(p));
  }
  const std::size_t masked_goal = std::min<std::size_t>(sampling.masked_total, masked);
  if (masked_goal > masked_chosen) {
    chooseSome(candidates_, masked_goal - masked_chosen, rng, chosen_);
    masked_chosen = masked_goal;
  }
  selected_.clear();
  for (std::size_t p = 0; p < masked; ++p)
    if (chosen_[p]) selected_.push_back(masked_[p]);
  selected_masked_ = selected_.size();
  // 3. Background above the ground fills up to total: a partial Fisher-
  // Yates shuffle of the background whose prefix, without the points on or
  // below the ground, is a uniform sample of those above it; heights are
  // asked only along that prefix.
  if (sampling.total > selected_.size()) {
    const std::size_t goal = sampling.total - selected_.size();
    const std::size_t n = background_.size();
    accepted_.clear();
    for (std::size_t i = 0; i < n && accepted_.size() < goal; ++i) {
      const std::size_t j = i + static_cast<std::size_t>(rng.below(n - i));
      std::swap(background_[i], background_[j]);
      if (is_above_ground(background_[i])) accepted_.push_back(background_[i]);
    }
    std::sort(accepted_.begin(), accepted_.end());
    selected_.insert(selected_.end(), accepted_.begin(), accepted_.end());
  }
  return selected_;
}

std::vector<uint32_t> selectPointCloudSample(const PointCloud& raw,
                                             const PointCloudSampling& sampling,
                                             uint64_t seed) {
  const std::size_t n = raw.size();
  const std::size_t k = raw.mask_count;
  if (raw.xyz.size() != 3 * n || raw.rgb.size() != 3 * n || raw.masks.size() != k * n)
    throw InvalidArgument(
        "point cloud arrays disagree: " + std::to_string(raw.xyz.size()) + " xyz values, " +
        std::to_string(raw.rgb.size()) + " rgb values and " + std::to_string(raw.masks.size()) +
        " mask values for " + std::to_string(k) + " masks");
  if (n > UINT32_MAX) throw InvalidArgument("point cloud has more than 2^32 points");
  if (k > 64) throw InvalidArgument("point cloud has more than 64 masks");
  PointCloudSampler sampler;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t bits = 0;
    for (std::size_t m = 0; m < k; ++m)
      if (raw.masks[i * k + m]) bits |= std::uint64_t(1) << m;
    if (bits != 0)
      sampler.addMasked(uint32_t(i), bits);
    else
      sampler.addBackground(uint32_t(i));
  }
  return sampler.select(sampling, seed, [&](uint32_t i) {
    return raw.xyz[3 * std::size_t(i) + 2] > sampling.ground_height;
  });
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
