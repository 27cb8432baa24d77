// What a network is trained on and for: the task, the observation mode and
// layout, the action layout. A demonstration set has one (read from its
// file and the environment it describes), a checkpoint stores one, and the
// host hands the policy plugin one (sdk::PolicyContext). Two that differ are
// an error naming both, field by field: a network never silently runs on
// observations it was not trained for.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace YAML {
class Node;
}

namespace manibench::learning {

// Anything the learning module refuses: bad options, files that do not
// match, a checkpoint of another task, a loss that is not finite. The
// message names the file, option or iteration.
class LearningError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SpecSegment {
  SpecSegment() = default;
  SpecSegment(std::string name_, uint32_t offset_, uint32_t size_, std::string description_ = {})
      : name(std::move(name_)), offset(offset_), size(size_), description(std::move(description_)) {}
  std::string name;
  uint32_t offset = 0;
  uint32_t size = 0;
  // The task's words for it, where the layout came from a live environment
  // (not written to checkpoints; planRobotFrameInputs reads it).
  std::string description;
  bool operator==(const SpecSegment& o) const {
    return name == o.name && offset == o.offset && size == o.size;
  }
};

struct ObservationSpec {
  std::string task;        // the registered task (not a fixed-object id)
  std::string mode;        // "state" | "pointcloud" | "rgbd"
  std::string controller;  // the controller the actions are for
  // The vector part: the task's state vector in the state mode, the
  // robot's own state (agent) in the visual modes.
  uint32_t state_dim = 0;
  std::vector<SpecSegment> state_segments;
  uint32_t action_dim = 0;
  std::vector<SpecSegment> action_segments;
  // pointcloud: points per observation and segmentation masks per point.
  uint32_t point_count = 0;
  uint32_t mask_count = 0;
  std::vector<std::string> mask_names;

  bool isPointCloud() const { return mode == "pointcloud"; }
  // One line: "OpenCabinetDrawer-v0, pointcloud (1200 points, 3 masks),
  // agent 38 [qpos 13, qvel 13, ...], action 13 [base 4, arm 7, ...],
  // controller mobile_panda_ee".
  std::string describe() const;
  // Throws LearningError naming both sides (`this_name`: "the checkpoint
  // run/checkpoints/iter_5000.pt", `other_name`: "the host") with the
  // first field that differs, when they are not interchangeable. The
  // controller is compared only when both name one, the point cloud's
  // size only when both know it (the host's context does not say).
  void checkSame(const ObservationSpec& other, const std::string& this_name,
                 const std::string& other_name) const;

  void writeYaml(YAML::Node& node) const;
  static ObservationSpec readYaml(const YAML::Node& node);
};

}  // namespace manibench::learning
