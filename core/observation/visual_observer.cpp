// The pointcloud and rgbd observations: render every camera, then turn the
// pixels into one world-frame cloud (subsampled as supplement D.1) or stack
// them along the channel axis as ManiSkill does.
#include <manibench/stopwatch.hpp>
#include <manibench/visual_observer.hpp>

#include "image_rows.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cassert>
#include <cstring>

namespace manibench {

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
    candidate_columns_.resize(std::max(candidate_columns_.size(), width));
    for (int row = 0; row < raw.height; ++row) {
      const std::size_t base = raw.getIndex(row, 0);
      const std::uint32_t* segment = raw.segment.data() + base;
      const float* depth = raw.depth.data() + base;
      const uint32_t first = start + uint32_t(row) * uint32_t(width);
      const std::size_t count = image_rows::findCandidateColumns(
          segment, depth, width, visual_count, ground_is_background, candidate_columns_.data());
      for (std::size_t j = 0; j < count; ++j) {
        const std::uint32_t col = candidate_columns_[j];
        // A visual's, or the ground's (its segment is above visual_count).
        const std::uint32_t s = segment[col];
        const std::uint64_t bits = s <= visual_count ? segment_bits_[s] : 0;
        if (bits != 0)
          sampler_.addMasked(first + col, bits);
        else
          sampler_.addBackground(first + col);
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

void VisualObserver::assembleImages(VisualObservation& out) {
  const uint32_t k = masks_.getCount();
  const std::size_t cameras = raw_.size();
  const std::size_t h = std::size_t(raw_.front().height), w = std::size_t(raw_.front().width);
  out.camera_count = static_cast<uint32_t>(cameras);
  out.height = static_cast<uint32_t>(h);
  out.width = static_cast<uint32_t>(w);
  // One of the two rgb layouts (observation.rgb_dtype); the other is empty.
  const bool bytes = options_.rgb_dtype == RgbDtype::Uint8;
  out.rgb.resize(bytes ? 0 : h * w * 3 * cameras);
  out.rgb_bytes.resize(bytes ? h * w * 3 * cameras : 0);
  out.depth.resize(h * w * cameras);
  out.masks.resize(h * w * k * cameras);
  mask_index_rows_.resize(cameras * w);
  const image_rows::InstructionSet set = image_rows::getBestInstructionSet();
  std::array<const std::uint32_t*, 16> index_row_array{};
  std::vector<const std::uint32_t*> index_row_vector;
  const std::uint32_t** index_rows = index_row_array.data();
  if (cameras > index_row_array.size()) {
    index_row_vector.resize(cameras);
    index_rows = index_row_vector.data();
  }
  for (std::size_t c = 0; c < cameras; ++c) index_rows[c] = mask_index_rows_.data() + c * w;
  // One scene, so one segment numbering for every camera.
  assert(std::all_of(raw_.begin(), raw_.end(), [&](const RawCameraImages& raw) {
    return raw.visual_count == raw_.front().visual_count;
  }));
  // Row by row (the output rows of all cameras stay in cache), each
  // camera's row from its GL row (bottom-up), with no copy in between.
  for (std::size_t row = 0; row < h; ++row) {
    const std::size_t p0 = row * w;
    for (std::size_t c = 0; c < cameras; ++c) {
      const RawCameraImages& raw = raw_[c];
      const std::size_t base = raw.getIndex(int(row), 0);
      // A camera's fourth float (or byte) is the next camera's red, written after.
      if (bytes)
        image_rows::copyRgbRow(raw.rgba.data() + 4 * base, w,
                               out.rgb_bytes.data() + p0 * 3 * cameras + 3 * c, 3 * cameras,
                               /*pad=*/c + 1 < cameras);
      else
        image_rows::convertRgbRow(raw.rgba.data() + 4 * base, w,
                                  out.rgb.data() + p0 * 3 * cameras + 3 * c, 3 * cameras,
                                  /*pad=*/c + 1 < cameras, set);
      image_rows::linearizeDepthRow(raw.segment.data() + base, raw.depth.data() + base, w,
                                    raw.visual_count, raw.near, raw.far,
                                    out.depth.data() + p0 * cameras + c, cameras,
                                    mask_index_rows_.data() + c * w, set);
    }
    if (k == 0) continue;
    std::uint8_t* masks = out.masks.data() + p0 * k * cameras;
    if (k <= 8) {
      image_rows::writeMaskRow(index_rows, cameras, w, k, segment_mask_bytes_.data(), masks);
      continue;
    }
    // Pixels that hit no visual (nothing, the ground, the far plane) have
    // index 0, in no mask: segment_bits_[0] is 0.
    for (std::size_t c = 0; c < cameras; ++c)
      for (std::size_t col = 0; col < w; ++col) {
        const std::uint64_t bits = segment_bits_[index_rows[c][col]];
        std::uint8_t* pixel_masks = masks + k * (col * cameras + c);
        for (uint32_t m = 0; m < k; ++m) pixel_masks[m] = (bits >> m) & 1u;
      }
  }
}

}  // namespace manibench
