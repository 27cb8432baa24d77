// The pointcloud and rgbd observations: render every camera, then fuse the
// images into one world-frame cloud (subsampled as supplement D.1) or stack
// them along the channel axis as ManiSkill does.
#include <manibench/visual_observer.hpp>

#include <chrono>

namespace manibench {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}
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
  // Render: drawing and readback, with the renderer's conversion of the
  // pixels (row order, depth, ids); assembly: what is made of them.
  Clock::time_point start = Clock::now();
  const std::vector<CameraImages>& images = renderCameras();
  times_.render += secondsSince(start);
  start = Clock::now();
  out.mask_count = masks_.getCount();
  if (options_.mode == ObservationMode::PointCloud) {
    fusePointCloud(images, images.size(), raw_points_);
    out.points = samplePointCloud(raw_points_, options_.pointcloud, sample_seed);
  } else {
    stackImages(images, out);
  }
  times_.assembly += secondsSince(start);
}

void VisualObserver::stackImages(const std::vector<CameraImages>& images,
                                 VisualObservation& out) const {
  const uint32_t k = masks_.getCount();
  const std::size_t cameras = images.size();
  const std::size_t h = std::size_t(images.front().height), w = std::size_t(images.front().width);
  out.camera_count = static_cast<uint32_t>(cameras);
  out.height = static_cast<uint32_t>(h);
  out.width = static_cast<uint32_t>(w);
  out.rgb.resize(h * w * 3 * cameras);
  out.depth.resize(h * w * cameras);
  out.masks.resize(h * w * k * cameras);
  for (std::size_t c = 0; c < cameras; ++c) {
    const CameraImages& image = images[c];
    for (std::size_t p = 0; p < h * w; ++p) {
      for (std::size_t ch = 0; ch < 3; ++ch)
        out.rgb[p * 3 * cameras + 3 * c + ch] = image.rgba[4 * p + ch] / 255.0f;
      out.depth[p * cameras + c] = image.depth[p];
      const std::uint64_t bits = masks_.calcPixelMasks(image, p);
      for (uint32_t m = 0; m < k; ++m)
        out.masks[p * k * cameras + k * c + m] = (bits >> m) & 1u;
    }
  }
}

}  // namespace manibench
