// The rgbd row kernels (core/observation/image_rows.hpp): every
// instruction-set variant this processor runs gives exactly the scalar
// definitions' floats and bytes, writes nothing it should not, and handles
// the widths that leave a tail after the vector loop.
#include "image_rows.hpp"

#include <manibench/renderer.hpp>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace manibench {
namespace {

using image_rows::InstructionSet;

// An instruction set this processor runs, named for the test's trace.
struct NamedSet {
  InstructionSet set;
  std::string name;
};

std::vector<NamedSet> getRunnableSets() {
  std::vector<NamedSet> sets = {{InstructionSet::Scalar, "scalar"}};
  const InstructionSet best = image_rows::getBestInstructionSet();
  if (best == InstructionSet::Sse2 || best == InstructionSet::Avx2) sets.push_back({InstructionSet::Sse2, "sse2"});
  if (best == InstructionSet::Avx2) sets.push_back({InstructionSet::Avx2, "avx2"});
  return sets;
}

constexpr std::uint32_t kVisualCount = 20;
const std::vector<std::size_t> kWidths = {1, 2, 3, 4, 5, 7, 8, 9, 400};

// Segments that sit on every edge of the hit test, and window depths from
// the near plane to the far plane (1: nothing hit) and just below it.
struct Row {
  std::vector<std::uint8_t> rgba;
  std::vector<std::uint32_t> segment;
  std::vector<float> depth;
};
Row makeRow(std::size_t width, std::mt19937& random) {
  static const std::uint32_t kSegments[] = {0,  1,  2,  kVisualCount - 1, kVisualCount,
                                            kVisualCount + 1, RawCameraImages::kGroundSegment,
                                            RawCameraImages::kGroundSegment - 1, 0x80000000u, 7};
  static const float kDepths[] = {0.0f, 0.25f, 0.5f, 0.9f, 0.999f, std::nextafter(1.0f, 0.0f),
                                  1.0f};
  Row row;
  row.rgba.resize(4 * width);
  for (std::uint8_t& byte : row.rgba) byte = std::uint8_t(random());
  for (std::size_t col = 0; col < width; ++col) {
    row.segment.push_back(kSegments[random() % std::size(kSegments)]);
    const bool any = random() % 2 == 0;
    row.depth.push_back(any ? std::uniform_real_distribution<float>(0.0f, 1.0f)(random)
                            : kDepths[random() % std::size(kDepths)]);
  }
  return row;
}

bool isHitByDefinition(std::uint32_t segment, float depth) {
  RawCameraImages image;
  image.width = image.height = 1;
  image.segment = {segment};
  image.depth = {depth};
  image.visual_count = kVisualCount;
  return image.isHit(0);
}

// Every byte value in every channel: the AVX2 variant multiplies and
// corrects instead of dividing, which is exact only because it is for each
// of these 256 inputs.
TEST(ImageRows, RgbOfEveryByteValueIsTheQuotient) {
  for (const auto& [set, name] : getRunnableSets()) {
    SCOPED_TRACE(name);
    std::vector<std::uint8_t> rgba(4 * 256);
    for (std::size_t col = 0; col < 256; ++col)
      for (std::size_t i = 0; i < 4; ++i) rgba[4 * col + i] = std::uint8_t(col + 85 * i);
    std::vector<float> rgb(3 * 256 + 1);
    image_rows::convertRgbRow(rgba.data(), 256, rgb.data(), 3, /*pad=*/false, set);
    for (std::size_t col = 0; col < 256; ++col)
      for (std::size_t i = 0; i < 3; ++i)
        ASSERT_EQ(rgb[3 * col + i], float(rgba[4 * col + i]) / 255.0f)
            << "byte " << int(rgba[4 * col + i]);
  }
}

TEST(ImageRows, RgbIsEachByteOver255InEveryVariant) {
  std::mt19937 random(1);
  const float kCanary = -7.0f;
  for (const auto& [set, name] : getRunnableSets())
    for (std::size_t width : kWidths)
      for (bool pad : {false, true}) {
        SCOPED_TRACE(name + " width " + std::to_string(width) + (pad ? " pad" : ""));
        const Row row = makeRow(width, random);
        const std::size_t stride = 9;  // three cameras' rgb
        std::vector<float> rgb(stride * width + 4, kCanary);
        image_rows::convertRgbRow(row.rgba.data(), width, rgb.data(), stride, pad, set);
        for (std::size_t col = 0; col < width; ++col) {
          for (std::size_t i = 0; i < 3; ++i)
            ASSERT_EQ(rgb[stride * col + i], float(row.rgba[4 * col + i]) / 255.0f)
                << "column " << col << " channel " << i;
          // Only a padded row may write the fourth float; nothing further.
          if (!pad) {
            ASSERT_EQ(rgb[stride * col + 3], kCanary) << "column " << col;
          }
          for (std::size_t i = 4; i < stride; ++i) ASSERT_EQ(rgb[stride * col + i], kCanary);
        }
      }
}

TEST(ImageRows, RgbBytesAreTheRendererBytes) {
  std::mt19937 random(5);
  const std::uint8_t kCanary = 0xA5;
  for (std::size_t width : kWidths)
    for (std::size_t stride : {std::size_t(3), std::size_t(9)})
      for (bool pad : {false, true}) {
        SCOPED_TRACE("width " + std::to_string(width) + " stride " + std::to_string(stride) +
                     (pad ? " pad" : ""));
        const Row row = makeRow(width, random);
        std::vector<std::uint8_t> rgb(stride * width + 4, kCanary);
        image_rows::copyRgbRow(row.rgba.data(), width, rgb.data(), stride, pad);
        for (std::size_t col = 0; col < width; ++col) {
          for (std::size_t i = 0; i < 3; ++i)
            ASSERT_EQ(rgb[stride * col + i], row.rgba[4 * col + i]) << "column " << col;
          // The fourth byte: written only with pad, or where the next
          // pixel's red follows (stride 3) and is written after.
          if (!pad && stride > 3) {
            ASSERT_EQ(rgb[stride * col + 3], kCanary) << "column " << col;
          }
          for (std::size_t i = 4; i < stride; ++i) ASSERT_EQ(rgb[stride * col + i], kCanary);
        }
        if (!pad) {
          ASSERT_EQ(rgb[stride * width], kCanary) << "nothing past the row";
        }
      }
}

TEST(ImageRows, DepthIsTheLinearDepthOfHitPixelsInEveryVariant) {
  std::mt19937 random(2);
  const double near = 0.01, far = 10.0;
  const float kCanary = -7.0f;
  std::size_t hits = 0, misses = 0;
  for (const auto& [set, name] : getRunnableSets())
    for (std::size_t width : kWidths) {
      SCOPED_TRACE(name + " width " + std::to_string(width));
      const Row row = makeRow(width, random);
      const std::size_t stride = 3;
      std::vector<float> out(stride * width, kCanary);
      const std::uint32_t kIndexCanary = 0xDEADBEEF;
      std::vector<std::uint32_t> mask_index(width + 1, kIndexCanary);
      image_rows::linearizeDepthRow(row.segment.data(), row.depth.data(), width, kVisualCount,
                                    near, far, out.data(), stride, mask_index.data(), set);
      ASSERT_EQ(mask_index[width], kIndexCanary);
      for (std::size_t col = 0; col < width; ++col) {
        const bool hit = isHitByDefinition(row.segment[col], row.depth[col]);
        ++(hit ? hits : misses);
        const float expected = hit ? calcLinearDepth(row.depth[col], near, far) : 0.0f;
        ASSERT_EQ(out[stride * col], expected)
            << "column " << col << " segment " << row.segment[col] << " depth " << row.depth[col];
        ASSERT_EQ(out[stride * col + 1], kCanary);
        ASSERT_EQ(out[stride * col + 2], kCanary);
        // The masks' index: the segment of a visual hit before the far plane.
        const std::uint32_t s = row.segment[col];
        const bool in_visual = s >= 1 && s <= kVisualCount && row.depth[col] < 1.0f;
        ASSERT_EQ(mask_index[col], in_visual ? s : 0u)
            << "column " << col << " segment " << s << " depth " << row.depth[col];
      }
    }
  // The rows exercise both sides of the test.
  EXPECT_GT(hits, 100u);
  EXPECT_GT(misses, 100u);
}

TEST(ImageRows, MaskBytesAreTheSegmentsMasksInOutputOrder) {
  std::mt19937 random(3);
  // Segment s is in mask m when bit m of (s * 37) is set; segment 0 in none.
  std::vector<std::uint64_t> mask_bytes(kVisualCount + 1, 0);
  for (std::uint32_t s = 1; s <= kVisualCount; ++s)
    for (std::uint32_t m = 0; m < 8; ++m)
      mask_bytes[s] |= std::uint64_t(((s * 37) >> m) & 1u) << (8 * m);
  const std::uint8_t kCanary = 0xAB;
  for (std::uint32_t k = 1; k <= 8; ++k)
    for (std::size_t cameras = 1; cameras <= 3; ++cameras)
      for (std::size_t width : kWidths) {
        SCOPED_TRACE("k " + std::to_string(k) + " cameras " + std::to_string(cameras) +
                     " width " + std::to_string(width));
        std::vector<Row> rows;
        std::vector<std::vector<std::uint32_t>> indices;
        std::vector<const std::uint32_t*> index_rows;
        std::vector<float> depth_out(width);
        for (std::size_t c = 0; c < cameras; ++c) {
          rows.push_back(makeRow(width, random));
          indices.emplace_back(width);
          image_rows::linearizeDepthRow(rows[c].segment.data(), rows[c].depth.data(), width,
                                        kVisualCount, 0.01, 10.0, depth_out.data(), 1,
                                        indices[c].data());
          index_rows.push_back(indices[c].data());
        }
        const std::size_t bytes = k * cameras * width;
        std::vector<std::uint8_t> out(bytes + 8, kCanary);
        image_rows::writeMaskRow(index_rows.data(), cameras, width, k, mask_bytes.data(),
                                 out.data());
        for (std::size_t col = 0; col < width; ++col)
          for (std::size_t c = 0; c < cameras; ++c) {
            const std::uint32_t s = rows[c].segment[col];
            const bool in_visual = s >= 1 && s <= kVisualCount && rows[c].depth[col] < 1.0f;
            for (std::uint32_t m = 0; m < k; ++m)
              ASSERT_EQ(out[(col * cameras + c) * k + m], in_visual ? ((s * 37) >> m) & 1u : 0u)
                  << "column " << col << " camera " << c << " mask " << m;
          }
        for (std::size_t i = bytes; i < out.size(); ++i) ASSERT_EQ(out[i], kCanary) << i;
      }
}

TEST(ImageRows, CandidateColumnsAreTheHitPixelsInOrder) {
  std::mt19937 random(4);
  std::size_t found = 0;
  for (bool ground_counts : {false, true})
    for (std::size_t width : kWidths) {
      SCOPED_TRACE(std::string(ground_counts ? "ground counts" : "visuals only") + " width " +
                   std::to_string(width));
      const Row row = makeRow(width, random);
      std::vector<std::uint32_t> expected;
      for (std::size_t col = 0; col < width; ++col) {
        const std::uint32_t s = row.segment[col];
        const bool visual = s >= 1 && s <= kVisualCount && row.depth[col] < 1.0f;
        if (ground_counts ? isHitByDefinition(s, row.depth[col]) : visual)
          expected.push_back(std::uint32_t(col));
      }
      std::vector<std::uint32_t> columns(width + 1, 0xDEADBEEF);
      const std::size_t count = image_rows::findCandidateColumns(
          row.segment.data(), row.depth.data(), width, kVisualCount, ground_counts,
          columns.data());
      ASSERT_EQ(std::vector<std::uint32_t>(columns.begin(), columns.begin() + count), expected);
      ASSERT_EQ(columns[width], 0xDEADBEEF);
      found += count;
    }
  EXPECT_GT(found, 100u);
}

}  // namespace
}  // namespace manibench
