// The observation module (core/observation): the task's segmentation
// masks on a scene, the cameras mounted on it, and the VisualObserver that
// renders them into the pointcloud and rgbd observations. An Environment
// makes one of each per scene it builds.
#pragma once

#include <manibench/observation.hpp>
#include <manibench/renderer.hpp>
#include <manibench/scene.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace manibench {

// The task's segmentation masks (mb_task_info.masks) on one scene: per visual
// of Scene::getVisualShapes(), bit m set when the visual belongs to mask m.
// A task fills them through add_to_mask while it builds its scene.
class SegmentationMasks {
 public:
  static constexpr std::size_t kMaxMasks = 64;
  // Throws SceneError for more than kMaxMasks names.
  explicit SegmentationMasks(std::vector<std::string> names = {});

  const std::vector<std::string>& getNames() const { return names_; }
  uint32_t getCount() const { return static_cast<uint32_t>(names_.size()); }
  // add_to_mask: the visuals of `link` of `articulation` whose <visual name>
  // contains `visual_name_part` (all of them when it is empty; every visual
  // of the articulation when link < 0) join mask `mask`. Throws SceneError
  // naming the mask, articulation, link and part when the call is wrong or
  // matches no visual.
  void addVisuals(const Scene& scene, uint32_t mask, int articulation, int link,
                  const std::string& visual_name_part);
  // Per visual, as far as add_to_mask reached; later visuals are in no mask.
  const std::vector<std::uint64_t>& getVisualMasks() const { return visual_masks_; }
  // Bit m set when `pixel` of `image` shows a visual of mask m.
  std::uint64_t calcPixelMasks(const CameraImages& image, std::size_t pixel) const;

 private:
  std::vector<std::string> names_;
  std::vector<std::uint64_t> visual_masks_;
};

// "'robot', 'cabinet'" (or "none"): the articulations of `scene`, for
// errors about one it lacks.
std::string describeArticulations(const Scene& scene);

// The cameras of ObservationOptions, resolved on one scene: where each is
// mounted and its world pose at the scene's current state.
class CameraRig {
 public:
  // Resolves every mount on `scene` (built, maybe not yet finalized; it
  // must outlive the rig); throws SceneError naming the camera, where it
  // was configured and the articulation or link the scene lacks.
  CameraRig(const Scene& scene, const std::vector<CameraMount>& cameras,
            const std::string& task_name);

  std::size_t getCount() const { return cameras_.size(); }
  const CameraMount& getMount(std::size_t index) const { return cameras_.at(index); }
  // World pose of camera `index` at the current state.
  Pose calcCameraPose(std::size_t index) const;

 private:
  const Scene& scene_;
  std::vector<CameraMount> cameras_;
  std::vector<int> links_;  // per camera: link id, -1 root, -2 world
  std::vector<int> articulations_;
};

// The one third-person view, of videos (`render --video`, `demos replay
// --video`) and of Python's render(): a width x height camera (fovy 1 rad,
// far 20 m) from the robot's side of the task's objects, 45 degrees to its
// right and 24 degrees above, looking at the middle of every visual shape
// (robot and objects, where they are now) and as near as keeps them all
// in the frame (the root of `articulation`, or the origin, when nothing is
// drawn).
struct ThirdPersonView {
  CameraSpec camera;
  Pose pose;
};
ThirdPersonView calcThirdPersonView(const Scene& scene, const std::string& articulation, int width,
                                    int height);

// Renders the cameras of one scene and assembles the visual observation
// from the images. The scene, the options and the masks must outlive it.
class VisualObserver {
 public:
  VisualObserver(const Scene& scene, const ObservationOptions& options,
                 const SegmentationMasks& masks, const std::string& task_name);
  ~VisualObserver();
  VisualObserver(const VisualObserver&) = delete;
  VisualObserver& operator=(const VisualObserver&) = delete;

  const ObservationOptions& getOptions() const { return options_; }
  const SegmentationMasks& getMasks() const { return masks_; }
  const CameraRig& getCameras() const { return cameras_; }
  // The renderer of the scene, created on first use (the scene must be
  // finalized by then).
  SceneRenderer& updRenderer();
  // Renders every camera at the current state (the visual modes do this at
  // each step; `render` and third-person videos call it in any mode). One
  // entry per options' camera, plus `extra` cameras fixed in the world, in
  // that order.
  const std::vector<CameraImages>& renderCameras(
      const std::vector<std::pair<CameraSpec, Pose>>& extra = {});
  // The world-frame points of the first `count` of `images` (pixels that
  // hit something), with color and the task's masks: the cloud that the
  // pointcloud mode subsamples.
  void fusePointCloud(const std::vector<CameraImages>& images, std::size_t count,
                      PointCloud& out) const;
  // The visual observation of the current state in the options' mode
  // (nothing in State). `sample_seed` fixes the point-cloud sample. Throws
  // RenderError when rendering fails. Every camera is drawn before any is
  // read back; the pixels are then converted once, straight into `out`:
  // a point cloud classifies them (hit, masks, background) and unprojects
  // only the D.1 sample, rgbd writes each pixel's channels in one pass.
  void observe(uint64_t sample_seed, VisualObservation& out);

  // Seconds observe() has spent since the observer was made (manibench
  // bench's stage table): drawing the cameras and reading their pixels
  // back, then assembling the observation from those pixels.
  struct Times {
    double render = 0, assembly = 0;
  };
  const Times& getTimes() const { return times_; }

 private:
  // The mask bits of each renderer segment value (visual + 1; 0: none).
  void updateSegmentBits();
  void assemblePointCloud(uint64_t sample_seed, PointCloud& out);
  // World point of sample index `index` (camera start + row * width + col).
  Eigen::Vector3f calcSamplePoint(uint32_t index, std::size_t& camera, std::size_t& pixel) const;
  void assembleImages(VisualObservation& out);

  const Scene& scene_;
  const ObservationOptions& options_;
  const SegmentationMasks& masks_;
  CameraRig cameras_;
  std::unique_ptr<SceneRenderer> renderer_;
  std::vector<CameraImages> images_;
  // observe()'s buffers, kept from step to step.
  std::vector<RawCameraImages> raw_;
  std::vector<std::uint64_t> segment_bits_;  // see updateSegmentBits
  // Per segment value, its mask bytes (byte m: in mask m) packed into 8
  // bytes in memory order, for up to 8 masks: the rgbd masks of a pixel are
  // then one store.
  std::vector<std::uint64_t> segment_mask_bytes_;
  // rgbd: per camera, one row's mask lookup indices (image_rows.hpp).
  std::vector<std::uint32_t> mask_index_rows_;
  std::vector<uint32_t> camera_starts_;  // per camera: its first sample index
  std::vector<uint32_t> candidate_columns_;  // pointcloud: one row's candidates
  PointCloudSampler sampler_;
  Times times_;
};

}  // namespace manibench
