// The observation modes (ManiSkill's obs_mode) and what an observation of
// the visual modes holds. A mode is a name only at the edges (YAML, the
// command line, the ABI's mb_policy_context); inside the host it is
// ObservationMode. Below the renderer: the plugin adapters, the evaluation
// kit and trajectories use these without depending on rendering.
#pragma once

#include <manibench/pointcloud.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manibench {

enum class ObservationMode {
  State,       // the task's state vector only
  PointCloud,  // the robot's state, and a fused world-frame point cloud (D.1 sampling)
  Rgbd,        // the robot's state, and every camera's rgb, depth and masks
};

// "state", "pointcloud" or "rgbd": the name in YAML, on the command line
// and in mb_policy_context::observation_mode.
const char* toString(ObservationMode mode);
// The mode called `name`; nullopt for any other text.
std::optional<ObservationMode> findObservationMode(const std::string& name);
// Every mode's name, in enum order.
const std::vector<std::string>& getObservationModeNames();
// Whether the mode renders cameras (every mode but State).
inline bool isVisualMode(ObservationMode mode) { return mode != ObservationMode::State; }

// The rgb of the rgbd mode: floats in [0, 1] (ManiSkill's layout, the
// default) or the renderer's bytes in [0, 255] (4 times smaller, what image
// libraries expect; byte / 255.0f is the float exactly).
enum class RgbDtype { Float32, Uint8 };
// "float32" or "uint8": the name in YAML (observation.rgb_dtype).
const char* toString(RgbDtype dtype);
std::optional<RgbDtype> findRgbDtype(const std::string& name);
const std::vector<std::string>& getRgbDtypeNames();

// The visual part of an observation (mb_observation's ABI 1.1 fields).
struct VisualObservation {
  ObservationMode mode = ObservationMode::State;  // State: everything empty
  uint32_t mask_count = 0;
  // PointCloud: world-frame points of all cameras, subsampled (D.1).
  PointCloud points;
  // Rgbd: cameras stacked along the channel axis as ManiSkill does, row-
  // major height x width x channels (row 0 on top): rgb 3 per camera in
  // [0, 1] (rgb_dtype Float32) or as bytes in [0, 255] (Uint8: rgb_bytes,
  // and rgb is empty), depth 1 per camera (m along the optical axis; 0
  // where nothing was hit), masks mask_count per camera (0 or 1).
  uint32_t camera_count = 0;
  uint32_t height = 0, width = 0;
  std::vector<float> rgb;
  std::vector<std::uint8_t> rgb_bytes;
  std::vector<float> depth;
  std::vector<std::uint8_t> masks;
};

}  // namespace manibench
