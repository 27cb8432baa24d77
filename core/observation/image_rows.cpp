// The rgbd observation's row kernels (image_rows.hpp): scalar definitions,
// an SSE2 variant and, where the compiler can target it, an AVX2 variant
// chosen at run time (with FMA). Profiling the rgbd bench put its time in the divisions
// (byte / 255 and the depth linearization, kept as divisions so that every
// variant gives the scalar floats), in the branch that zeroes missed pixels,
// and in the mask bytes' two stores per pixel.
#include "image_rows.hpp"

#include <manibench/renderer.hpp>

#include <cassert>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define MANIBENCH_HAVE_AVX2_VARIANT 1
#endif

namespace manibench::image_rows {

namespace {

bool isHit(std::uint32_t segment, float depth, std::uint32_t visual_count) {
  return (segment - 1u < visual_count || segment == RawCameraImages::kGroundSegment) &
         (depth < 1.0f);
}

std::uint32_t calcMaskIndex(std::uint32_t segment, float depth, std::uint32_t visual_count) {
  return (segment - 1u < visual_count) & (depth < 1.0f) ? segment : 0u;
}

void convertRgbRowScalar(const std::uint8_t* rgba, std::size_t begin, std::size_t width,
                         float* rgb, std::size_t stride) {
  for (std::size_t col = begin; col < width; ++col)
    for (std::size_t i = 0; i < 3; ++i) rgb[stride * col + i] = float(rgba[4 * col + i]) / 255.0f;
}

void linearizeDepthRowScalar(const std::uint32_t* segment, const float* depth, std::size_t begin,
                             std::size_t width, std::uint32_t visual_count, double near,
                             double far, float* out, std::size_t stride,
                             std::uint32_t* mask_index) {
  for (std::size_t col = begin; col < width; ++col) {
    out[stride * col] =
        isHit(segment[col], depth[col], visual_count) ? calcLinearDepth(depth[col], near, far) : 0.0f;
    mask_index[col] = calcMaskIndex(segment[col], depth[col], visual_count);
  }
}

#if defined(__SSE2__)
// Four bytes to four floats, divided by 255; r, g as one 8-byte store and b
// as one more.
template <bool kPad>
void convertRgbRowSse2(const std::uint8_t* rgba, std::size_t width, float* rgb,
                       std::size_t stride) {
  const __m128 k255 = _mm_set1_ps(255.0f);
  const __m128i zero = _mm_setzero_si128();
  for (std::size_t col = 0; col < width; ++col) {
    std::uint32_t word;
    std::memcpy(&word, rgba + 4 * col, 4);
    const __m128i bytes = _mm_cvtsi32_si128(int(word));
    const __m128i ints = _mm_unpacklo_epi16(_mm_unpacklo_epi8(bytes, zero), zero);
    const __m128 unit = _mm_div_ps(_mm_cvtepi32_ps(ints), k255);
    float* pixel = rgb + stride * col;
    if constexpr (kPad) {
      _mm_storeu_ps(pixel, unit);
    } else {
      _mm_storel_pi(reinterpret_cast<__m64*>(pixel), unit);
      _mm_store_ss(pixel + 2, _mm_movehl_ps(unit, unit));
    }
  }
}

// The tests of four pixels as lane masks: a visual's segment (segment - 1
// < visual_count unsigned; SSE2 compares signed: both sides offset by
// 2^31), the ground's, and window depth below 1 (the far plane).
struct HitMasks {
  __m128i visual_before_far;  // a visual's pixel: in its masks
  __m128 hit;                 // a visual's or the ground's: has a depth
};
HitMasks calcHitMasks(__m128i segments, __m128 depths, std::uint32_t visual_count) {
  const __m128i bias = _mm_set1_epi32(int(0x80000000u));
  const __m128i visual = _mm_cmplt_epi32(
      _mm_xor_si128(_mm_sub_epi32(segments, _mm_set1_epi32(1)), bias),
      _mm_set1_epi32(int(visual_count ^ 0x80000000u)));
  const __m128i ground =
      _mm_cmpeq_epi32(segments, _mm_set1_epi32(int(RawCameraImages::kGroundSegment)));
  const __m128i before_far = _mm_castps_si128(_mm_cmplt_ps(depths, _mm_set1_ps(1.0f)));
  return {_mm_and_si128(visual, before_far),
          _mm_castsi128_ps(_mm_and_si128(_mm_or_si128(visual, ground), before_far))};
}

void storeStrided(__m128 values, float* out, std::size_t stride) {
  _mm_store_ss(out, values);
  _mm_store_ss(out + stride, _mm_shuffle_ps(values, values, 1));
  _mm_store_ss(out + 2 * stride, _mm_movehl_ps(values, values));
  _mm_store_ss(out + 3 * stride, _mm_shuffle_ps(values, values, 3));
}

// calcLinearDepth's operations in its order on two doubles at a time; the
// hit test as a mask (no branch: the pixels' order is the image's, not the
// branch predictor's).
void linearizeDepthRowSse2(const std::uint32_t* segment, const float* depth, std::size_t width,
                           std::uint32_t visual_count, double near, double far, float* out,
                           std::size_t stride, std::uint32_t* mask_index) {
  const __m128d two = _mm_set1_pd(2.0), one = _mm_set1_pd(1.0),
                two_nf = _mm_set1_pd(2 * near * far), sum = _mm_set1_pd(far + near),
                difference = _mm_set1_pd(far - near);
  auto linearize = [&](__m128d d) {
    return _mm_div_pd(two_nf, _mm_sub_pd(sum, _mm_mul_pd(_mm_sub_pd(_mm_mul_pd(two, d), one),
                                                         difference)));
  };
  std::size_t col = 0;
  for (; col + 4 <= width; col += 4) {
    const __m128 d = _mm_loadu_ps(depth + col);
    const __m128i s = _mm_loadu_si128(reinterpret_cast<const __m128i*>(segment + col));
    const __m128 z = _mm_movelh_ps(_mm_cvtpd_ps(linearize(_mm_cvtps_pd(d))),
                                   _mm_cvtpd_ps(linearize(_mm_cvtps_pd(_mm_movehl_ps(d, d)))));
    const HitMasks masks = calcHitMasks(s, d, visual_count);
    storeStrided(_mm_and_ps(z, masks.hit), out + stride * col, stride);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(mask_index + col),
                     _mm_and_si128(s, masks.visual_before_far));
  }
  linearizeDepthRowScalar(segment, depth, col, width, visual_count, near, far, out, stride,
                          mask_index);
}
#endif

#if defined(MANIBENCH_HAVE_AVX2_VARIANT)
// byte / 255 without a division: the product with the rounded reciprocal,
// corrected once by its residual (Markstein: q + (x - q * 255) / 255 with
// fused operations). For every one of the 256 bytes this is the correctly
// rounded quotient, i.e. exactly float(byte) / 255.0f (checked by
// image_rows_test for all 256); a division was a third of the rgb row's time.
__attribute__((target("avx2,fma"))) inline __m256 divideBy255(__m256 x) {
  const __m256 k255 = _mm256_set1_ps(255.0f), reciprocal = _mm256_set1_ps(1.0f / 255.0f);
  const __m256 q = _mm256_mul_ps(x, reciprocal);
  return _mm256_fmadd_ps(_mm256_fnmadd_ps(q, k255, x), reciprocal, q);
}

// Two pixels per 8 floats.
template <bool kPad>
__attribute__((target("avx2,fma"))) void convertRgbRowAvx2(const std::uint8_t* rgba,
                                                           std::size_t width, float* rgb,
                                                           std::size_t stride) {
  std::size_t col = 0;
  for (; col + 2 <= width; col += 2) {
    const __m128i bytes = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(rgba + 4 * col));
    const __m256 unit = divideBy255(_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes)));
    const __m128 first = _mm256_castps256_ps128(unit), second = _mm256_extractf128_ps(unit, 1);
    float* pixel = rgb + stride * col;
    if constexpr (kPad) {
      _mm_storeu_ps(pixel, first);
      _mm_storeu_ps(pixel + stride, second);
    } else {
      _mm_storel_pi(reinterpret_cast<__m64*>(pixel), first);
      _mm_store_ss(pixel + 2, _mm_movehl_ps(first, first));
      pixel += stride;
      _mm_storel_pi(reinterpret_cast<__m64*>(pixel), second);
      _mm_store_ss(pixel + 2, _mm_movehl_ps(second, second));
    }
  }
  // Leave no upper register halves dirty for the SSE code that follows:
  // GCC put no vzeroupper before this call.
  _mm256_zeroupper();
  convertRgbRowScalar(rgba, col, width, rgb, stride);
}

// Four doubles per division.
__attribute__((target("avx2"))) void linearizeDepthRowAvx2(
    const std::uint32_t* segment, const float* depth, std::size_t width,
    std::uint32_t visual_count, double near, double far, float* out, std::size_t stride,
    std::uint32_t* mask_index) {
  const __m256d two = _mm256_set1_pd(2.0), one = _mm256_set1_pd(1.0),
                two_nf = _mm256_set1_pd(2 * near * far), sum = _mm256_set1_pd(far + near),
                difference = _mm256_set1_pd(far - near);
  std::size_t col = 0;
  for (; col + 4 <= width; col += 4) {
    const __m128 d = _mm_loadu_ps(depth + col);
    const __m128i s = _mm_loadu_si128(reinterpret_cast<const __m128i*>(segment + col));
    const __m256d window = _mm256_sub_pd(_mm256_mul_pd(two, _mm256_cvtps_pd(d)), one);
    const __m128 z = _mm256_cvtpd_ps(
        _mm256_div_pd(two_nf, _mm256_sub_pd(sum, _mm256_mul_pd(window, difference))));
    const HitMasks masks = calcHitMasks(s, d, visual_count);
    storeStrided(_mm_and_ps(z, masks.hit), out + stride * col, stride);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(mask_index + col),
                     _mm_and_si128(s, masks.visual_before_far));
  }
  _mm256_zeroupper();  // as in convertRgbRowAvx2
  linearizeDepthRowScalar(segment, depth, col, width, visual_count, near, far, out, stride,
                          mask_index);
}
#endif

// Every pixel's K bytes as one 8-byte store, in output order: the bytes past
// its K belong to pixels written after it. The pixels within 8 bytes of the
// row's end get exactly K (the row ends the buffer on the last row). With
// the lookup index ready (linearizeDepthRow), a pixel is a load, a table
// load and a store.
template <std::size_t K>
void writeMaskRowFor(const std::uint32_t* const* mask_indices, std::size_t cameras,
                     std::size_t width, const std::uint64_t* mask_bytes, std::uint8_t* out) {
  const std::size_t pixels = cameras * width;
  const std::size_t wide = pixels * K >= 8 ? (pixels * K - 8) / K + 1 : 0;
  // Columns whose every pixel is below `wide`.
  const std::size_t wide_columns = wide >= cameras ? (wide - cameras) / cameras + 1 : 0;
  std::uint8_t* pixel_out = out;
  std::size_t col = 0;
  for (; col < wide_columns; ++col)
    for (std::size_t c = 0; c < cameras; ++c, pixel_out += K)
      std::memcpy(pixel_out, &mask_bytes[mask_indices[c][col]], 8);
  for (std::size_t pixel = col * cameras; col < width; ++col)
    for (std::size_t c = 0; c < cameras; ++c, ++pixel, pixel_out += K)
      std::memcpy(pixel_out, &mask_bytes[mask_indices[c][col]], pixel < wide ? 8 : K);
}

}  // namespace

InstructionSet getBestInstructionSet() {
#if defined(MANIBENCH_HAVE_AVX2_VARIANT)
  // The AVX2 variants use FMA too (every AVX2 processor but a few of VIA's has it).
  static const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  if (avx2) return InstructionSet::Avx2;
#endif
#if defined(__SSE2__)
  return InstructionSet::Sse2;
#else
  return InstructionSet::Scalar;
#endif
}

void convertRgbRow(const std::uint8_t* rgba, std::size_t width, float* rgb, std::size_t stride,
                   bool pad, InstructionSet set) {
  switch (set) {
#if defined(MANIBENCH_HAVE_AVX2_VARIANT)
    case InstructionSet::Avx2:
      return pad ? convertRgbRowAvx2<true>(rgba, width, rgb, stride)
                 : convertRgbRowAvx2<false>(rgba, width, rgb, stride);
#endif
#if defined(__SSE2__)
    case InstructionSet::Sse2:
      return pad ? convertRgbRowSse2<true>(rgba, width, rgb, stride)
                 : convertRgbRowSse2<false>(rgba, width, rgb, stride);
#endif
    default:
      return convertRgbRowScalar(rgba, 0, width, rgb, stride);
  }
}

void copyRgbRow(const std::uint8_t* rgba, std::size_t width, std::uint8_t* rgb,
                std::size_t stride, bool pad) {
  // A pixel as one 4-byte store where the byte after its blue is written
  // later anyway; else 3 bytes. No instruction-set variants: this is a
  // load and a store per pixel, against the float rows' conversion.
  const std::size_t wide = pad ? width : stride == 3 && width > 0 ? width - 1 : 0;
  std::size_t col = 0;
  for (; col < wide; ++col) std::memcpy(rgb + stride * col, rgba + 4 * col, 4);
  for (; col < width; ++col) std::memcpy(rgb + stride * col, rgba + 4 * col, 3);
}

void linearizeDepthRow(const std::uint32_t* segment, const float* depth, std::size_t width,
                       std::uint32_t visual_count, double near, double far, float* out,
                       std::size_t stride, std::uint32_t* mask_index, InstructionSet set) {
  switch (set) {
#if defined(MANIBENCH_HAVE_AVX2_VARIANT)
    case InstructionSet::Avx2:
      return linearizeDepthRowAvx2(segment, depth, width, visual_count, near, far, out, stride,
                                   mask_index);
#endif
#if defined(__SSE2__)
    case InstructionSet::Sse2:
      return linearizeDepthRowSse2(segment, depth, width, visual_count, near, far, out, stride,
                                   mask_index);
#endif
    default:
      return linearizeDepthRowScalar(segment, depth, 0, width, visual_count, near, far, out,
                                     stride, mask_index);
  }
}

void writeMaskRow(const std::uint32_t* const* mask_indices, std::size_t cameras,
                  std::size_t width, std::uint32_t k, const std::uint64_t* mask_bytes,
                  std::uint8_t* out) {
  using Writer = void (*)(const std::uint32_t* const*, std::size_t, std::size_t,
                          const std::uint64_t*, std::uint8_t*);
  static constexpr Writer kWriters[] = {
      nullptr,             &writeMaskRowFor<1>, &writeMaskRowFor<2>, &writeMaskRowFor<3>,
      &writeMaskRowFor<4>, &writeMaskRowFor<5>, &writeMaskRowFor<6>, &writeMaskRowFor<7>,
      &writeMaskRowFor<8>};
  assert(k >= 1 && k <= 8 && "writeMaskRow: k from 1 to 8");
  kWriters[k](mask_indices, cameras, width, mask_bytes, out);
}

std::size_t findCandidateColumns(const std::uint32_t* segment, const float* depth,
                                 std::size_t width, std::uint32_t visual_count,
                                 bool ground_counts, std::uint32_t* columns) {
  std::size_t count = 0, col = 0;
#if defined(__SSE2__)
  for (; col + 4 <= width; col += 4) {
    const HitMasks masks =
        calcHitMasks(_mm_loadu_si128(reinterpret_cast<const __m128i*>(segment + col)),
                     _mm_loadu_ps(depth + col), visual_count);
    const __m128 candidate =
        ground_counts ? masks.hit : _mm_castsi128_ps(masks.visual_before_far);
    for (unsigned lanes = unsigned(_mm_movemask_ps(candidate)); lanes != 0; lanes &= lanes - 1)
      columns[count++] = std::uint32_t(col) + std::uint32_t(__builtin_ctz(lanes));
  }
#endif
  for (; col < width; ++col)
    if (ground_counts ? isHit(segment[col], depth[col], visual_count)
                      : calcMaskIndex(segment[col], depth[col], visual_count) != 0)
      columns[count++] = std::uint32_t(col);
  return count;
}

}  // namespace manibench::image_rows
