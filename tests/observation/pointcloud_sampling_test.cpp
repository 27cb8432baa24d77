// The point-cloud subsampling of supplement D.1 on crafted clouds: how many
// points of each kind it keeps, in which priority, the ground rule, the
// padding, and that a seed fixes the sample.
#include <manibench/pointcloud.hpp>

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>

namespace manibench {
namespace {

// `counts[m]` points in mask m alone (z = 1), then `background` points in
// no mask above the ground (z = 0.5) and `ground` on it (z = 0). A point's
// x is its index, so samples can be traced back.
PointCloud makeCloud(const std::vector<uint32_t>& counts, uint32_t background, uint32_t ground) {
  PointCloud cloud;
  cloud.mask_count = uint32_t(counts.size());
  auto add = [&](float z, int mask) {
    const float i = float(cloud.size());
    cloud.xyz.insert(cloud.xyz.end(), {i, 0.0f, z});
    cloud.rgb.insert(cloud.rgb.end(), {0.5f, 0.25f, 1.0f});
    for (uint32_t m = 0; m < cloud.mask_count; ++m) cloud.masks.push_back(int(m) == mask);
  };
  for (std::size_t m = 0; m < counts.size(); ++m)
    for (uint32_t i = 0; i < counts[m]; ++i) add(1.0f, int(m));
  for (uint32_t i = 0; i < background; ++i) add(0.5f, -1);
  for (uint32_t i = 0; i < ground; ++i) add(0.0f, -1);
  return cloud;
}

struct Tally {
  std::vector<uint32_t> per_mask;
  uint32_t background = 0, ground = 0, zero = 0;
};

Tally tally(const PointCloud& cloud) {
  Tally t;
  t.per_mask.assign(cloud.mask_count, 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    bool any = false;
    for (uint32_t m = 0; m < cloud.mask_count; ++m)
      if (cloud.masks[i * cloud.mask_count + m]) {
        ++t.per_mask[m];
        any = true;
      }
    const float z = cloud.xyz[3 * i + 2];
    if (any) continue;
    if (z == 0.5f)
      ++t.background;
    else if (z == 0.0f && cloud.rgb[3 * i] == 0.5f)
      ++t.ground;
    else if (z == 0.0f && cloud.rgb[3 * i] == 0.0f && cloud.xyz[3 * i] == 0.0f)
      ++t.zero;
  }
  return t;
}

TEST(PointCloudSampling, SmallMaskKeepsAllAndLargeMaskFillsTo800) {
  // Mask 0 has 20 points (all kept), mask 1 has 5000: after 50 of its own,
  // it fills the masked budget to 800; background fills to 1200.
  const PointCloud raw = makeCloud({20, 5000}, 3000, 3000);
  const PointCloud out = samplePointCloud(raw, {}, 7);
  ASSERT_EQ(out.size(), 1200u);
  const Tally t = tally(out);
  EXPECT_EQ(t.per_mask[0], 20u);
  EXPECT_EQ(t.per_mask[1], 780u);
  EXPECT_EQ(t.background, 400u);
  EXPECT_EQ(t.ground, 0u) << "ground points (z <= 1e-3) are never sampled";
  EXPECT_EQ(t.zero, 0u);
  // No point twice.
  std::set<float> xs;
  for (std::size_t i = 0; i < out.size(); ++i) xs.insert(out.xyz[3 * i]);
  EXPECT_EQ(xs.size(), out.size());
}

TEST(PointCloudSampling, EveryMaskGetsItsFiftyBeforeTheRest) {
  // Twenty masks of 100 points: each first gets 50 (1000 > 800 in total),
  // so no further masked points and only 200 background points.
  std::vector<uint32_t> counts(20, 100);
  const PointCloud raw = makeCloud(counts, 1000, 0);
  const PointCloud out = samplePointCloud(raw, {}, 1);
  const Tally t = tally(out);
  for (uint32_t m = 0; m < 20; ++m) EXPECT_EQ(t.per_mask[m], 50u) << "mask " << m;
  EXPECT_EQ(t.background, 200u);
  EXPECT_EQ(out.size(), 1200u);
}

TEST(PointCloudSampling, FewMaskedPointsAreAllKeptAndBackgroundFills) {
  const PointCloud raw = makeCloud({30, 60, 100}, 5000, 100);
  const std::vector<uint32_t> indices = selectPointCloudSample(raw, {}, 3);
  ASSERT_EQ(indices.size(), 1200u);
  // Every masked point (190 < 800) is kept, first and in order.
  for (uint32_t i = 0; i < 190; ++i) EXPECT_EQ(indices[i], i);
  for (std::size_t i = 190; i < indices.size(); ++i) {
    EXPECT_GE(indices[i], 190u);
    EXPECT_LT(indices[i], 190u + 5000u) << "a ground point was sampled";
  }
}

TEST(PointCloudSampling, TooFewPointsArePaddedWithZeros) {
  const PointCloud raw = makeCloud({10}, 100, 500);
  const PointCloud out = samplePointCloud(raw, {}, 3);
  ASSERT_EQ(out.size(), 1200u);
  const Tally t = tally(out);
  EXPECT_EQ(t.per_mask[0], 10u);
  EXPECT_EQ(t.background, 100u);
  EXPECT_EQ(t.ground, 0u);
  EXPECT_EQ(t.zero, 1090u);
  PointCloudSampling unpadded;
  unpadded.pad = false;
  EXPECT_EQ(samplePointCloud(raw, unpadded, 3).size(), 110u);
}

TEST(PointCloudSampling, GroundThresholdIsStrict) {
  PointCloud raw = makeCloud({}, 0, 0);
  for (float z : {0.0f, 1e-3f, 1.1e-3f, -0.5f, 2.0f}) {
    raw.xyz.insert(raw.xyz.end(), {0.0f, 0.0f, z});
    raw.rgb.insert(raw.rgb.end(), {1.0f, 1.0f, 1.0f});
  }
  PointCloudSampling sampling;
  sampling.pad = false;
  EXPECT_EQ(selectPointCloudSample(raw, sampling, 0), (std::vector<uint32_t>{2, 4}));
}

TEST(PointCloudSampling, PointsInSeveralMasksCountOnce) {
  // 100 points in both masks: each mask's 50 may overlap, then the masked
  // budget (all 100 < 800) takes them all.
  PointCloud raw;
  raw.mask_count = 2;
  for (int i = 0; i < 100; ++i) {
    raw.xyz.insert(raw.xyz.end(), {float(i), 0.0f, 1.0f});
    raw.rgb.insert(raw.rgb.end(), {1.0f, 1.0f, 1.0f});
    raw.masks.insert(raw.masks.end(), {1, 1});
  }
  PointCloudSampling sampling;
  sampling.pad = false;
  EXPECT_EQ(selectPointCloudSample(raw, sampling, 5).size(), 100u);
}

TEST(PointCloudSampling, SameSeedSameSampleOtherSeedOtherSample) {
  const PointCloud raw = makeCloud({2000, 3000}, 20000, 1000);
  const auto a = selectPointCloudSample(raw, {}, 42);
  EXPECT_EQ(a, selectPointCloudSample(raw, {}, 42));
  EXPECT_NE(a, selectPointCloudSample(raw, {}, 43));
  const PointCloud p = samplePointCloud(raw, {}, 42);
  const PointCloud q = samplePointCloud(raw, {}, 42);
  EXPECT_EQ(p.xyz, q.xyz);
  EXPECT_EQ(p.rgb, q.rgb);
  EXPECT_EQ(p.masks, q.masks);
}

TEST(PointCloudSampling, InconsistentArraysAreRejected) {
  PointCloud raw = makeCloud({5}, 5, 0);
  raw.masks.pop_back();
  try {
    selectPointCloudSample(raw, {}, 0);
    FAIL() << "no error";
  } catch (const manibench::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("disagree"), std::string::npos) << e.what();
  }
  PointCloudSampling bad;
  bad.masked_total = 2000;
  EXPECT_THROW(selectPointCloudSample(makeCloud({5}, 5, 0), bad, 0), manibench::InvalidArgument);
}

}  // namespace
}  // namespace manibench
