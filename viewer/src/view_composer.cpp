#include "view_composer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace manibench::viewer {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Saturated colours far from grey and from each other (mask 0 first: the
// tasks' first mask is the handle or the target link).
constexpr std::uint8_t kMaskColors[][3] = {
    {255, 64, 64}, {64, 200, 255}, {255, 210, 0}, {140, 255, 80},
    {220, 90, 255}, {255, 140, 40}, {0, 255, 190}, {255, 100, 180},
};

}  // namespace

ViewComposer::~ViewComposer() = default;

std::array<std::uint8_t, 3> ViewComposer::getMaskColor(std::size_t mask) {
  const std::uint8_t* c = kMaskColors[mask % (sizeof(kMaskColors) / sizeof(kMaskColors[0]))];
  return {c[0], c[1], c[2]};
}

const ViewImage& ViewComposer::compose(Environment& env, uint64_t episode,
                                       const ViewSettings& settings, const FreeCamera& camera,
                                       int width, int height) {
  const Clock::time_point start = Clock::now();
  VisualObserver& observer = env.updObserver();
  SceneRenderer& renderer = observer.updRenderer();
  const CameraRig& rig = observer.getCameras();
  const bool task_camera = settings.camera >= 0 && std::size_t(settings.camera) < rig.getCount();
  const CameraSpec spec = task_camera ? rig.getMount(std::size_t(settings.camera)).spec
                                      : camera.makeSpec(width, height);
  const Pose pose = task_camera ? rig.calcCameraPose(std::size_t(settings.camera)) : camera.calcPose();
  image_.width = spec.width;
  image_.height = spec.height;
  image_.camera = spec.name;
  if (settings.points) {
    // Points alone: the camera's image is not needed, only where it is.
    // (The cloud itself renders the task's cameras, once per step.)
    const PointCloud& cloud = updPointCloud(env, episode);
    render_seconds_ = secondsSince(start);
    const Clock::time_point compose_start = Clock::now();
    composePoints(cloud, spec, pose, settings.masks);
    image_.rgba = &composed_;
    compose_seconds_ = secondsSince(compose_start);
    return image_;
  }
  renderer.draw(spec, pose);
  // The segments and depth only for the masks: reading back the colour
  // alone took OpenCabinetDrawer-v0 at 1280x720 from 21.7 to 24.9 frames/s
  // and 27.8 to 26.2 ms of CPU a frame (medians of 5 alternated pairs,
  // llvmpipe, load 10-11).
  if (settings.masks)
    renderer.readBack(spec, raw_);
  else
    renderer.readBackColor(spec, raw_);
  render_seconds_ = secondsSince(start);

  const Clock::time_point compose_start = Clock::now();
  image_.rgba = &raw_.rgba;
  if (settings.masks) {
    composeMasks(env);
    image_.rgba = &composed_;
  }
  compose_seconds_ = secondsSince(compose_start);
  return image_;
}

void ViewComposer::composeMasks(const Environment& env) {
  const std::vector<std::uint64_t>& visual_masks = env.getObserver().getMasks().getVisualMasks();
  const std::size_t pixels = raw_.segment.size();
  composed_.resize(4 * pixels);
  for (std::size_t p = 0; p < pixels; ++p) {
    std::uint8_t* out = &composed_[4 * p];
    out[3] = 255;
    if (!raw_.isHit(p)) {
      out[0] = out[1] = out[2] = 0;
      continue;
    }
    const int visual = raw_.getVisual(p);
    const std::uint64_t bits =
        visual >= 0 && std::size_t(visual) < visual_masks.size() ? visual_masks[std::size_t(visual)] : 0;
    if (bits != 0) {
      const std::array<std::uint8_t, 3> c = getMaskColor(std::size_t(__builtin_ctzll(bits)));
      out[0] = c[0], out[1] = c[1], out[2] = c[2];
    } else {
      // Grey, a third of the pixel's brightness: the scene around the masks.
      const std::uint8_t* in = &raw_.rgba[4 * p];
      const auto grey = std::uint8_t((int(in[0]) + in[1] + in[2]) / 9);
      out[0] = out[1] = out[2] = grey;
    }
  }
}

const PointCloud& ViewComposer::updPointCloud(Environment& env, uint64_t episode) {
  if (env.getObservationMode() == ObservationMode::PointCloud) {
    cloud_ = env.getVisualObservation().points;
    return cloud_;
  }
  if (episode != cloud_episode_) {
    // The scene may be another: a new observer over it (its renderer
    // uploads the geometry once).
    cloud_observer_.reset();
    cloud_options_ = env.getOptions().observation;
    cloud_options_.mode = ObservationMode::PointCloud;
    cloud_observer_ = std::make_unique<VisualObserver>(
        env.getScene(), cloud_options_, env.getObserver().getMasks(), env.getTaskDescription().name);
    cloud_episode_ = episode;
    cloud_step_ = ~0u;
  }
  if (env.getElapsedSteps() != cloud_step_) {
    // The environment's own sample of (seed, step).
    cloud_observer_->observe(env.calcSampleSeed(), cloud_observation_);
    cloud_ = cloud_observation_.points;
    cloud_step_ = env.getElapsedSteps();
  }
  return cloud_;
}

void ViewComposer::composePoints(const PointCloud& cloud, const CameraSpec& spec, const Pose& pose, bool masks) {
  const int width = spec.width, height = spec.height;
  const std::size_t pixels = std::size_t(width) * std::size_t(height);
  composed_.assign(4 * pixels, 0);
  for (std::size_t p = 0; p < pixels; ++p) composed_[4 * p + 3] = 255;
  point_depth_.assign(pixels, INFINITY);
  const Eigen::Matrix3d rotation_t = pose.orientation.toRotationMatrix().transpose();
  const Eigen::Vector3d origin = pose.position;
  // The renderer's pinhole: square pixels, fovy over the height, centred.
  const double fy = (height / 2.0) / std::tan(spec.fovy / 2), fx = fy;
  const double cx = width / 2.0, cy = height / 2.0;
  // Splats of about 1/240 of the image height (3 px at 720).
  const int radius = std::max(1, height / 480);
  const std::size_t masks_per_point = cloud.mask_count;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d world(cloud.xyz[3 * i], cloud.xyz[3 * i + 1], cloud.xyz[3 * i + 2]);
    std::uint64_t bits = 0;
    for (std::size_t m = 0; m < masks_per_point; ++m)
      if (cloud.masks[i * masks_per_point + m]) bits |= 1ull << m;
    if (world.isZero() && bits == 0) continue;  // D.1's padding
    const Eigen::Vector3d p = rotation_t * (world - origin);  // x forward, y left, z up
    if (p.x() <= spec.near) continue;
    const double u = fx * (-p.y() / p.x()) + cx, v = fy * (-p.z() / p.x()) + cy;
    const int col = int(std::floor(u)), row = int(std::floor(v));
    std::uint8_t color[3];
    if (masks && bits != 0) {
      const std::array<std::uint8_t, 3> c = getMaskColor(std::size_t(__builtin_ctzll(bits)));
      std::copy(c.begin(), c.end(), color);
    } else {
      for (int c = 0; c < 3; ++c)
        color[c] = std::uint8_t(std::clamp(cloud.rgb[3 * i + std::size_t(c)], 0.0f, 1.0f) * 255.0f + 0.5f);
    }
    const auto depth = float(p.x());
    for (int r = row - radius; r <= row + radius; ++r) {
      if (r < 0 || r >= height) continue;
      for (int c = col - radius; c <= col + radius; ++c) {
        if (c < 0 || c >= width) continue;
        const std::size_t index = std::size_t(height - 1 - r) * std::size_t(width) + std::size_t(c);
        if (depth >= point_depth_[index]) continue;
        point_depth_[index] = depth;
        std::copy(color, color + 3, &composed_[4 * index]);
      }
    }
  }
}

}  // namespace manibench::viewer
