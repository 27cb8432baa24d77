// Point clouds with segmentation masks, and the subsampling of the ManiSkill
// baselines (supplement D.1) that turns a camera frame's ~10^5 points into
// a fixed budget that keeps every mask visible.
#pragma once

#include <manibench/error.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace manibench {

// Row-major point data: xyz (world frame, m) and rgb (in [0, 1]) three
// floats per point, masks mask_count bytes per point (0 or 1).
struct PointCloud {
  uint32_t mask_count = 0;
  std::vector<float> xyz;
  std::vector<float> rgb;
  std::vector<std::uint8_t> masks;

  std::size_t size() const { return xyz.size() / 3; }
  void clear() {
    xyz.clear();
    rgb.clear();
    masks.clear();
  }
  // Appends point `i` of `other` (same mask_count).
  void appendFrom(const PointCloud& other, std::size_t i);
  // Appends a point at the origin, black, in no mask.
  void appendZero();
};

// Supplement D.1, with the numbers of the ManiSkill-Learn baselines.
struct PointCloudSampling {
  // 1. Up to `per_mask` points of every mask (all of them if it has fewer).
  uint32_t per_mask = 50;
  // 2. More points in at least one mask, at random, until `masked_total`
  //    masked points are chosen (all masked points if there are fewer).
  uint32_t masked_total = 800;
  // 3. Points in no mask and above the ground (z > ground_height: the
  //    ground plane itself, which the renderer puts at z = 0 within a few
  //    micrometres, is dropped) fill the cloud up to `total`.
  uint32_t total = 1200;
  float ground_height = 1e-3f;
  // 4. When fewer than `total` points qualify, pad with zero points (origin,
  //    black, no mask) so the size is always `total`, as ManiSkill-Learn
  //    does; false keeps only the chosen points.
  bool pad = true;
};

// The D.1 rule on candidates named by index (a point of a cloud, a pixel of
// a camera), for callers that classify once and compute positions only for
// what is kept: the pointcloud observation adds each hit pixel with its
// mask bits, and unprojects only the chosen ones. Its buffers are kept from
// one sample to the next (no allocation once they have grown).
class PointCloudSampler {
 public:
  // Starts a new sample.
  void clear();
  // The candidates, in increasing index order: one in the masks of `bits`
  // (bit m: mask m, at least one set), or one in no mask.
  void addMasked(uint32_t index, std::uint64_t bits) {
    const auto position = static_cast<uint32_t>(masked_.size());
    masked_.push_back(index);
    if (per_mask_.size() < 64 && (bits >> per_mask_.size()) != 0) growMasks(bits);
    for (std::uint64_t rest = bits; rest != 0; rest &= rest - 1)
      per_mask_[std::size_t(__builtin_ctzll(rest))].push_back(position);
  }
  void addBackground(uint32_t index) { background_.push_back(index); }
  std::size_t getMaskedCount() const { return masked_.size(); }
  std::size_t getBackgroundCount() const { return background_.size(); }

  // The indices D.1 keeps: the masked ones first, then the background ones,
  // each group in increasing index order. `is_above_ground(index)` is asked
  // of background candidates only, in random order until enough are found
  // (so a caller computes few heights). The same candidates, sampling and
  // seed always give the same indices (the generator is fixed, not the
  // standard library's). Throws InvalidArgument when masked_total >
  // total.
  const std::vector<uint32_t>& select(const PointCloudSampling& sampling, uint64_t seed,
                                      const std::function<bool(uint32_t)>& is_above_ground);
  // How many of select()'s indices are masked (they come first).
  std::size_t getSelectedMaskedCount() const { return selected_masked_; }

 private:
  void growMasks(std::uint64_t bits);

  std::vector<uint32_t> masked_, background_;
  std::vector<std::vector<uint32_t>> per_mask_;  // positions in masked_, per mask
  std::vector<std::uint8_t> chosen_;             // per position in masked_
  std::vector<uint32_t> candidates_, selected_, accepted_;
  std::size_t selected_masked_ = 0;
};

// Indices into `raw` of the points D.1 keeps: the masked ones first, then
// the background ones, each group in increasing index order. The same raw
// cloud, sampling and seed always give the same indices (the generator is
// fixed, not the standard library's). Throws InvalidArgument when
// the sizes of raw's arrays disagree or masked_total > total.
std::vector<uint32_t> selectPointCloudSample(const PointCloud& raw,
                                             const PointCloudSampling& sampling,
                                             uint64_t seed);

// The chosen points (selectPointCloudSample), padded when sampling.pad.
PointCloud samplePointCloud(const PointCloud& raw, const PointCloudSampling& sampling,
                            uint64_t seed);

}  // namespace manibench
