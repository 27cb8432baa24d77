// What the visual observation modes are made of: cameras, lights, the
// point-cloud sampling and the renderer's options (the `observation`,
// `cameras` and `lights` keys). The modes themselves and what an
// observation holds are in observation_mode.hpp, which does not need the
// renderer.
#pragma once

#include <manibench/geometry.hpp>
#include <manibench/observation_mode.hpp>
#include <manibench/renderer.hpp>

#include <string>
#include <vector>

namespace manibench {

// A camera of the visual observation modes: mounted on a link (it moves
// with it) or fixed in the world.
struct CameraMount {
  CameraSpec spec;           // name, image size, fovy, near and far
  std::string articulation;  // empty: fixed in the world
  std::string link;          // empty: the articulation's root
  Pose pose;                 // in the mount frame (SAPIEN: +x optical axis, +z up)
  std::string source;        // where it was configured, for errors
};

// What the observation of an environment is made of (the `observation`,
// `cameras` and `lights` keys of the configuration).
struct ObservationOptions {
  // State: the task's vector only. PointCloud and Rgbd add, from every
  // camera, a fused world-frame point cloud subsampled as supplement D.1
  // or the stacked images (see VisualObservation). Only these two modes
  // create a renderer (and so touch EGL), lazily.
  ObservationMode mode = ObservationMode::State;
  RgbDtype rgb_dtype = RgbDtype::Float32;  // Rgbd's rgb (VisualObservation)
  std::vector<CameraMount> cameras;  // names unique; Rgbd: all of one size
  LightingSpec lighting;
  PointCloudSampling pointcloud;
  RenderOptions render;
};

// Throws InvalidArgument, naming the camera and where it was
// configured, for options no scene could honour: a visual mode without a
// camera, duplicate camera names, a link without its articulation, an empty
// image, Rgbd cameras of different sizes, masked_total above total.
void validateObservationOptions(const ObservationOptions& options);

}  // namespace manibench
