// The per-row kernels of the rgbd observation (VisualObserver::assembleImages):
// one camera row of GL pixels into the stacked layout, where a camera's
// values of one pixel are `stride` elements apart from the next pixel's.
//
// Each kernel gives exactly the floats of its scalar definition (IEEE
// division and conversions, the same operations in the same order), so the
// observation does not depend on which instruction set ran it: SSE2 always
// (x86-64's baseline), AVX2 where the processor has it, chosen at run time.
// tests/observation/image_rows_test.cpp checks every variant against the
// scalar definitions.
#pragma once

#include <cstddef>
#include <cstdint>

namespace manibench::image_rows {

// Which variant the dispatching functions below run.
enum class InstructionSet { Scalar, Sse2, Avx2 };
InstructionSet getBestInstructionSet();  // of this processor (and build)

// rgb[stride * col + i] = rgba[4 * col + i] / 255.0f for i = 0, 1, 2.
// With `pad`, rgb[stride * col + 3] may be written too (with anything), as
// one 16-byte store: for a camera whose pixels are followed by another's
// that are written after.
void convertRgbRow(const std::uint8_t* rgba, std::size_t width, float* rgb, std::size_t stride,
                   bool pad, InstructionSet set = getBestInstructionSet());

// rgb[stride * col + i] = rgba[4 * col + i] for i = 0, 1, 2: the bytes of
// observation.rgb_dtype uint8. With `pad` (another camera's bytes follow,
// written after), rgb[stride * col + 3] may be written too, so that a
// pixel is one 4-byte store; so may it with stride 3 (one camera: the
// next pixel's red follows), except after the row's last pixel.
void copyRgbRow(const std::uint8_t* rgba, std::size_t width, std::uint8_t* rgb,
                std::size_t stride, bool pad);

// out[stride * col] = calcLinearDepth(depth[col], near, far) where the pixel
// hit a visual (segments 1..visual_count) or the ground (kGroundSegment)
// before the far plane, else 0; and mask_index[col] = the segment where it
// hit a visual, else 0 (the masks' lookup index, for writeMaskRow: the
// depth row is read once for both).
void linearizeDepthRow(const std::uint32_t* segment, const float* depth, std::size_t width,
                       std::uint32_t visual_count, double near, double far, float* out,
                       std::size_t stride, std::uint32_t* mask_index,
                       InstructionSet set = getBestInstructionSet());

// The mask bytes of one output row of all cameras, in output order:
// out[(col * cameras + c) * k + m] is byte m of mask_bytes[mask_indices[c][col]]
// (byte m: 0 or 1, bit m of the segment's masks; mask_bytes[0] is 0).
// mask_indices[c] is camera c's row of linearizeDepthRow's mask_index. k
// at most 8.
void writeMaskRow(const std::uint32_t* const* mask_indices, std::size_t cameras,
                  std::size_t width, std::uint32_t k, const std::uint64_t* mask_bytes,
                  std::uint8_t* out);

// The point cloud's candidates of one row (VisualObserver::assemblePointCloud):
// the columns whose pixel hit a visual before the far plane or, with
// `ground_counts`, the ground before it, in increasing order, into
// `columns` (room for `width`). Returns how many. Four pixels per SSE2
// test: most of a view is sky or floor, which then costs one predictable
// branch per four pixels instead of two or three data-dependent ones per
// pixel (those were most of the pointcloud assembly).
std::size_t findCandidateColumns(const std::uint32_t* segment, const float* depth,
                                 std::size_t width, std::uint32_t visual_count,
                                 bool ground_counts, std::uint32_t* columns);

}  // namespace manibench::image_rows
