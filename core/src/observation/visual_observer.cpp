// The pointcloud and rgbd observations: render every camera, then turn the
// pixels into one world-frame cloud (subsampled as supplement D.1) or stack
// them along the channel axis as ManiSkill does.
#include <manibench/visual_observer.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace manibench {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// One camera row's mask bytes, K per pixel, `stride` bytes apart: the
// pixel's segment picks its packed bytes (none where nothing was hit or at
// the far plane), written as one K-byte store.
template <std::size_t K>
void writeMaskRow(const std::uint32_t* segment, const float* depth, std::size_t width,
                  std::uint32_t visual_count, const std::uint64_t* mask_bytes, std::uint8_t* out,
                  std::size_t stride) {
  for (std::size_t col = 0; col < width; ++col) {
    const std::uint32_t s = segment[col];
    const std::uint64_t bytes =
        mask_bytes[s <= visual_count ? s : 0u] & (0 - std::uint64_t(depth[col] < 1.0f));
    std::memcpy(out + stride * col, &bytes, K);
  }
}

using MaskRowWriter = void (*)(const std::uint32_t*, const float*, std::size_t, std::uint32_t,
                               const std::uint64_t*, std::uint8_t*, std::size_t);
constexpr std::array<MaskRowWriter, 9> kMaskRowWriters = {
    nullptr,         &writeMaskRow<1>, &writeMaskRow<2>, &writeMaskRow<3>, &writeMaskRow<4>,
    &writeMaskRow<5>, &writeMaskRow<6>, &writeMaskRow<7>, &writeMaskRow<8>};
}  // namespace

VisualObserver::VisualObserver(const Scene& scene, const ObservationOptions& options,
                               const SegmentationMasks& masks, const std::string& task_name)
    : scene_(scene), options_(options), masks_(masks), cameras_(scene, options.cameras, task_name) {}

// The renderer reads the scene: it goes first (a member, so with this).
VisualObserver::~VisualObserver() = default;

SceneRenderer& VisualObserver::updRenderer() {
  if (!renderer_)
    renderer_ = std::make_unique<SceneRenderer>(scene_, options_.lighting, options_.render);
  return *renderer_;
}

const std::vector<CameraImages>& VisualObserver::renderCameras(
    const std::vector<std::pair<CameraSpec, Pose>>& extra) {
  SceneRenderer& renderer = updRenderer();
  const std::size_t n = cameras_.getCount();
  images_.resize(n + extra.size());
  for (std::size_t i = 0; i < n; ++i)
    renderer.render(cameras_.getMount(i).spec, cameras_.calcCameraPose(i), images_[i]);
  for (std::size_t i = 0; i < extra.size(); ++i)
    renderer.render(extra[i].first, extra[i].second, images_[n + i]);
  return images_;
}

void VisualObserver::fusePointCloud(const std::vector<CameraImages>& images, std::size_t count,
                                    PointCloud& out) const {
  const uint32_t k = masks_.getCount();
  out.clear();
  out.mask_count = k;
  std::vector<int> pixels;
  for (std::size_t i = 0; i < count && i < images.size(); ++i) {
    const CameraImages& image = images[i];
    const Eigen::Matrix3Xf points = calcCameraPoints(image, /*world=*/true, &pixels);
    for (Eigen::Index j = 0; j < points.cols(); ++j) {
      const std::size_t p = std::size_t(pixels[std::size_t(j)]);
      out.xyz.insert(out.xyz.end(), {points(0, j), points(1, j), points(2, j)});
      for (std::size_t c = 0; c < 3; ++c) out.rgb.push_back(image.rgba[4 * p + c] / 255.0f);
      const std::uint64_t bits = masks_.calcPixelMasks(image, p);
      for (uint32_t m = 0; m < k; ++m) out.masks.push_back((bits >> m) & 1u);
    }
  }
}

void VisualObserver::observe(uint64_t sample_seed, VisualObservation& out) {
  out.mode = options_.mode;
  if (!isVisualMode(options_.mode)) return;
  Clock::time_point start = Clock::now();
  SceneRenderer& renderer = updRenderer();
  const std::size_t n = cameras_.getCount();
  raw_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    renderer.draw(cameras_.getMount(i).spec, cameras_.calcCameraPose(i));
  for (std::size_t i = 0; i < n; ++i) renderer.readBack(cameras_.getMount(i).spec, raw_[i]);
  times_.render += secondsSince(start);
  start = Clock::now();
  out.mask_count = masks_.getCount();
  updateSegmentBits();
  if (options_.mode == ObservationMode::PointCloud)
    assemblePointCloud(sample_seed, out.points);
  else
    assembleImages(out);
  times_.assembly += secondsSince(start);
}

void VisualObserver::updateSegmentBits() {
  const std::vector<std::uint64_t>& masks = masks_.getVisualMasks();
  const std::size_t visuals = scene_.getVisualShapes().size();
  segment_bits_.assign(visuals + 1, 0);
  std::copy_n(masks.begin(), std::min(masks.size(), visuals), segment_bits_.begin() + 1);
  segment_mask_bytes_.assign(segment_bits_.size(), 0);
  for (std::size_t s = 0; s < segment_bits_.size(); ++s) {
    std::uint8_t bytes[8] = {};
    for (std::size_t m = 0; m < 8; ++m) bytes[m] = (segment_bits_[s] >> m) & 1u;
    std::memcpy(&segment_mask_bytes_[s], bytes, 8);
  }
}

void VisualObserver::assemblePointCloud(uint64_t sample_seed, PointCloud& out) {
  const PointCloudSampling& sampling = options_.pointcloud;
  // The ground plane's pixels lie on it within a few micrometres (see
  // docs/rendering.md): when it is clearly below ground_height, none of
  // them can be sampled, so they are dropped here rather than by height,
  // one at a time (most of a view can be floor). Otherwise their heights
  // decide, as every other background pixel's.
  constexpr double kGroundMargin = 1e-4;  // m; the renderer is good to ~3 um
  const bool ground_is_background =
      !(scene_.getGroundHeight() < double(sampling.ground_height) - kGroundMargin);
  // Classify every pixel once: no hit, a mask's, or background (a visual
  // in no mask, or the ground).
  sampler_.clear();
  camera_starts_.clear();
  uint32_t start = 0;
  for (const RawCameraImages& raw : raw_) {
    camera_starts_.push_back(start);
    const std::size_t width = std::size_t(raw.width);
    const std::uint32_t visual_count = raw.visual_count;
    for (int row = 0; row < raw.height; ++row) {
      const std::size_t base = raw.getIndex(row, 0);
      const std::uint32_t* segment = raw.segment.data() + base;
      const float* depth = raw.depth.data() + base;
      const uint32_t first = start + uint32_t(row) * uint32_t(width);
      for (std::size_t col = 0; col < width; ++col) {
        const std::uint32_t s = segment[col];
        if (s == 0 || !(depth[col] < 1.0f)) continue;
        if (s <= visual_count) {
          const std::uint64_t bits = segment_bits_[s];
          if (bits != 0)
            sampler_.addMasked(first + uint32_t(col), bits);
          else
            sampler_.addBackground(first + uint32_t(col));
        } else if (s == RawCameraImages::kGroundSegment && ground_is_background) {
          sampler_.addBackground(first + uint32_t(col));
        }
      }
    }
    start += uint32_t(width * std::size_t(raw.height));
  }
  const std::vector<uint32_t>& chosen =
      sampler_.select(sampling, sample_seed, [this, &sampling](uint32_t index) {
        std::size_t camera = 0, pixel = 0;
        return calcSamplePoint(index, camera, pixel).z() > sampling.ground_height;
      });
  // Unproject only the chosen pixels, straight into the observation.
  const uint32_t k = masks_.getCount();
  const std::size_t size =
      sampling.pad ? std::max<std::size_t>(chosen.size(), sampling.total) : chosen.size();
  out.mask_count = k;
  out.xyz.assign(3 * size, 0.0f);
  out.rgb.assign(3 * size, 0.0f);
  out.masks.assign(std::size_t(k) * size, 0);
  for (std::size_t j = 0; j < chosen.size(); ++j) {
    std::size_t camera = 0, pixel = 0;
    const Eigen::Vector3f point = calcSamplePoint(chosen[j], camera, pixel);
    const RawCameraImages& raw = raw_[camera];
    for (std::size_t c = 0; c < 3; ++c) {
      out.xyz[3 * j + c] = point[Eigen::Index(c)];
      out.rgb[3 * j + c] = raw.rgba[4 * pixel + c] / 255.0f;
    }
    const std::uint32_t segment = raw.segment[pixel];
    const std::uint64_t bits = segment <= raw.visual_count ? segment_bits_[segment] : 0;
    for (uint32_t m = 0; m < k; ++m) out.masks[std::size_t(k) * j + m] = (bits >> m) & 1u;
  }
}

Eigen::Vector3f VisualObserver::calcSamplePoint(uint32_t index, std::size_t& camera,
                                                std::size_t& pixel) const {
  camera = std::size_t(std::upper_bound(camera_starts_.begin(), camera_starts_.end(), index) -
                       camera_starts_.begin()) - 1;
  const RawCameraImages& raw = raw_[camera];
  const uint32_t offset = index - camera_starts_[camera];
  const int row = int(offset / uint32_t(raw.width)), col = int(offset % uint32_t(raw.width));
  pixel = raw.getIndex(row, col);
  const Eigen::Matrix3d rotation = raw.camera_to_world.linear();
  const Eigen::Vector3d translation = raw.camera_to_world.translation();
  return calcPixelPoint(raw.intrinsic, rotation, translation, row, col,
                        calcLinearDepth(raw.depth[pixel], raw.near, raw.far));
}

void VisualObserver::assembleImages(VisualObservation& out) const {
  // x / 255.0f for every byte: the same floats as the division, without it.
  static const std::array<float, 256> kByteToUnit = [] {
    std::array<float, 256> table{};
    for (int i = 0; i < 256; ++i) table[std::size_t(i)] = float(i) / 255.0f;
    return table;
  }();
  const uint32_t k = masks_.getCount();
  const std::size_t cameras = raw_.size();
  const std::size_t h = std::size_t(raw_.front().height), w = std::size_t(raw_.front().width);
  out.camera_count = static_cast<uint32_t>(cameras);
  out.height = static_cast<uint32_t>(h);
  out.width = static_cast<uint32_t>(w);
  out.rgb.resize(h * w * 3 * cameras);
  out.depth.resize(h * w * cameras);
  out.masks.resize(h * w * k * cameras);
  // Row by row (the output rows of all cameras stay in cache), each
  // camera's row from its GL row (bottom-up) in one sweep per channel kind,
  // with no copy in between; the sweeps are branch-free so that they
  // vectorize. Depth is linearized here, where a pixel was hit.
  for (std::size_t row = 0; row < h; ++row) {
    const std::size_t p0 = row * w;
    for (std::size_t c = 0; c < cameras; ++c) {
      const RawCameraImages& raw = raw_[c];
      const std::size_t base = raw.getIndex(int(row), 0);
      const std::uint8_t* color = raw.rgba.data() + 4 * base;
      const std::uint32_t* segment = raw.segment.data() + base;
      const float* depth = raw.depth.data() + base;
      float* rgb = out.rgb.data() + p0 * 3 * cameras + 3 * c;
      std::size_t col = 0;
#if defined(__SSE2__)
      // Four bytes to four floats, divided by 255 (IEEE division: the same
      // floats as the table); r, g as one 8-byte store and b as one more.
      const __m128 k255 = _mm_set1_ps(255.0f);
      const __m128i zero = _mm_setzero_si128();
      for (; col < w; ++col) {
        std::uint32_t word;
        std::memcpy(&word, color + 4 * col, 4);
        const __m128i bytes = _mm_cvtsi32_si128(int(word));
        const __m128i ints = _mm_unpacklo_epi16(_mm_unpacklo_epi8(bytes, zero), zero);
        const __m128 unit = _mm_div_ps(_mm_cvtepi32_ps(ints), k255);
        float* pixel = rgb + 3 * cameras * col;
        _mm_storel_pi(reinterpret_cast<__m64*>(pixel), unit);
        _mm_store_ss(pixel + 2, _mm_movehl_ps(unit, unit));
      }
#endif
      for (; col < w; ++col) {
        rgb[3 * cameras * col + 0] = kByteToUnit[color[4 * col + 0]];
        rgb[3 * cameras * col + 1] = kByteToUnit[color[4 * col + 1]];
        rgb[3 * cameras * col + 2] = kByteToUnit[color[4 * col + 2]];
      }
      const std::uint32_t visual_count = raw.visual_count;
      // calcLinearDepth's terms, and the hit test without branches (the
      // pixels' order is the image's, not the branch predictor's).
      const double two_nf = 2 * raw.near * raw.far, sum = raw.far + raw.near,
                   difference = raw.far - raw.near;
      float* depth_out = out.depth.data() + p0 * cameras + c;
      col = 0;
#if defined(__SSE2__)
      // Two pixels per division, the scalar loop's operations in its order
      // (so the same floats as calcLinearDepth).
      const __m128d two = _mm_set1_pd(2.0), one = _mm_set1_pd(1.0), two_nf_v = _mm_set1_pd(two_nf),
                    sum_v = _mm_set1_pd(sum), difference_v = _mm_set1_pd(difference);
      for (; col + 2 <= w; col += 2) {
        const __m128d d = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(
            reinterpret_cast<const __m128i*>(depth + col))));
        const __m128d window = _mm_sub_pd(_mm_mul_pd(two, d), one);
        const __m128d z = _mm_div_pd(two_nf_v, _mm_sub_pd(sum_v, _mm_mul_pd(window, difference_v)));
        float zf[4];
        _mm_storeu_ps(zf, _mm_cvtpd_ps(z));
        for (std::size_t i = 0; i < 2; ++i) {
          const std::uint32_t s = segment[col + i];
          const bool hit = (s - 1u < visual_count || s == RawCameraImages::kGroundSegment) &
                           (depth[col + i] < 1.0f);
          depth_out[cameras * (col + i)] = hit ? zf[i] : 0.0f;
        }
      }
#endif
      for (; col < w; ++col) {
        const std::uint32_t s = segment[col];
        const bool hit = (s - 1u < visual_count || s == RawCameraImages::kGroundSegment) &
                         (depth[col] < 1.0f);
        const float z = static_cast<float>(two_nf / (sum - (2.0 * depth[col] - 1.0) * difference));
        depth_out[cameras * col] = hit ? z : 0.0f;
      }
      if (k == 0) continue;
      std::uint8_t* masks = out.masks.data() + p0 * k * cameras + k * c;
      if (k < kMaskRowWriters.size()) {
        kMaskRowWriters[k](segment, depth, w, visual_count, segment_mask_bytes_.data(), masks,
                           k * cameras);
        continue;
      }
      for (std::size_t col = 0; col < w; ++col) {
        const std::uint32_t s = segment[col];
        // Pixels that hit no visual (nothing, the ground, the far plane)
        // are in no mask: segment_bits_[0] is 0.
        const std::uint64_t bits =
            segment_bits_[s <= visual_count ? s : 0u] & (0 - std::uint64_t(depth[col] < 1.0f));
        std::uint8_t* pixel_masks = masks + k * cameras * col;
        for (uint32_t m = 0; m < k; ++m) pixel_masks[m] = (bits >> m) & 1u;
      }
    }
  }
}

}  // namespace manibench
