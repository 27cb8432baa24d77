// State inputs re-expressed in the robot base's frame (`train --robot-frame`).
//
// Why: the mobile Panda's base and arm actions are velocities in the base's
// own frame, while the tasks' state vectors give the objects and the robot
// in the world's. Going to a world goal means rotating the world offset by
// the base's yaw, a product of the inputs an MLP has to learn from the data
// on every object. Measured on MoveBucket-v0's demonstrations (an MLP
// 3 x 256, 20k iterations, 6 of the 30 train objects held out): the held-out
// MSE went from .0073 to .0064 with these inputs appended, and on the base's
// three actions from .0036 to .0027.
//
// The features are appended to the world-frame state (which stays in the
// input). Which segments, decided once from the environment's observation
// layout when a training starts and then stored with the network (so a
// checkpoint never depends on how a task words its descriptions):
//   - the frame: `base_position` (x, y, world) and `base_yaw` (required);
//   - every segment named `*_pose` of 7 values (position, quaternion wxyz):
//     the position as a point, the quaternion turned by -yaw (w >= 0);
//   - every other segment whose description says `world`: of 2 values, a
//     planar vector (the base's velocity); of 3k values, k points when its
//     unit is metres (`(m)`), else k vectors (velocities, axes). A point is
//     shifted by the base's position and turned by -yaw; a vector only turned.
#pragma once

#include <manibench/learning/spec.hpp>

#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace manibench::learning {

struct RobotFrameInputs {
  enum class Kind { Points, Vectors, PlanarVector, Pose };
  struct Entry {
    std::string segment;
    Kind kind = Kind::Points;
    uint32_t offset = 0, size = 0;
    bool operator==(const Entry& o) const {
      return segment == o.segment && kind == o.kind && offset == o.offset && size == o.size;
    }
  };
  uint32_t base_position = 0, base_yaw = 0;  // offsets of the frame's segments
  std::vector<Entry> entries;                // empty: the option is off

  bool isEnabled() const { return !entries.empty(); }
  int64_t calcDim() const;
  // "12 segments, 69 values: fingertip_positions (4 points), ..."
  std::string describe() const;
  void writeYaml(YAML::Node node) const;  // a handle: fills the node it refers to
  static RobotFrameInputs readYaml(const YAML::Node& node);
  bool operator==(const RobotFrameInputs& o) const {
    return base_position == o.base_position && base_yaw == o.base_yaw && entries == o.entries;
  }
};

// The plan for `spec`'s state layout, by the rules above. Throws
// LearningError when the layout has no base frame or nothing to re-express.
RobotFrameInputs planRobotFrameInputs(const ObservationSpec& spec);

// [N, S] float states -> [N, calcDim()] features, in float32 as the network
// sees them (the same function builds the training batches and the acting
// policy's input).
torch::Tensor calcRobotFrameFeatures(const RobotFrameInputs& inputs, const torch::Tensor& state);

}  // namespace manibench::learning
