// What the window shows, as an image: the scene from the free camera or
// one of the task's cameras, drawn by the environment's own SceneRenderer
// (EGL, offscreen) and read back; optionally its segmentation masks in
// colours, or the point cloud the policy gets (the supplement D.1 sample)
// splatted from the same camera. No window or GL context of the viewer's
// is involved: window.cpp uploads the result as a texture.
#pragma once

#include <manibench/environment.hpp>
#include <manibench/pointcloud.hpp>
#include <manibench/renderer.hpp>
#include <manibench/visual_observer.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "free_camera.hpp"

namespace manibench::viewer {

struct ViewSettings {
  int camera = -1;      // -1: the free camera; else the index of a task camera
  bool masks = false;   // segmentation masks in colours instead of the colour image
  bool points = false;  // the point cloud instead of the image
};

// The composed image, rows from the BOTTOM up (OpenGL's order, as
// RawCameraImages), RGBA.
struct ViewImage {
  int width = 0, height = 0;
  const std::vector<std::uint8_t>* rgba = nullptr;
  std::string camera;  // the camera's name
};

class ViewComposer {
 public:
  ViewComposer() = default;
  ViewComposer(const ViewComposer&) = delete;
  ViewComposer& operator=(const ViewComposer&) = delete;
  ~ViewComposer();

  // Renders the view of `env`'s current state. The free camera is drawn at
  // `width` x `height`; a task camera at its own size. `episode` changes
  // whenever the environment was reset or restored (the scene may have
  // been rebuilt: the point-cloud observer follows it).
  const ViewImage& compose(Environment& env, uint64_t episode, const ViewSettings& settings,
                           const FreeCamera& camera, int width, int height);

  // Mask m's colour in the masks view (saturated, never grey: the pixels
  // in no mask are grey).
  static std::array<std::uint8_t, 3> getMaskColor(std::size_t mask);
  // The cloud drawn last (empty until points were shown).
  const PointCloud& getPointCloud() const { return cloud_; }
  // Seconds of the last compose(): drawing and reading back (points: the
  // cloud's own rendering when the step is new), then composing (masks,
  // points).
  double getRenderSeconds() const { return render_seconds_; }
  double getComposeSeconds() const { return compose_seconds_; }

 private:
  const PointCloud& updPointCloud(Environment& env, uint64_t episode);
  void composeMasks(const Environment& env);
  void composePoints(const PointCloud& cloud, const CameraSpec& spec, const Pose& pose, bool masks);

  RawCameraImages raw_;
  std::vector<std::uint8_t> composed_;
  std::vector<float> point_depth_;
  ViewImage image_;
  // The D.1 sample when the environment's mode is not pointcloud: an
  // observer of its own, in that mode, over the environment's scene.
  ObservationOptions cloud_options_;
  std::unique_ptr<VisualObserver> cloud_observer_;
  VisualObservation cloud_observation_;
  uint64_t cloud_episode_ = ~0ull;
  uint32_t cloud_step_ = ~0u;
  PointCloud cloud_;
  double render_seconds_ = 0, compose_seconds_ = 0;
};

}  // namespace manibench::viewer
