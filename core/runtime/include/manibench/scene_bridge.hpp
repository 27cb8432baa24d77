// The host's implementation of mb_scene_api over a Scene: what a task or
// controller plugin sees of the physics, with the phase rules of the
// per-step contract (abi.h) enforced.
#pragma once

#include <manibench/abi.h>
#include <manibench/scene.hpp>

namespace manibench {

class SegmentationMasks;

// One per Scene. Phases guard misuse: adds (and add_to_mask) only while
// building, setters only in resets.
class SceneBridge {
 public:
  // `masks` (may be null: the task then has no masks to add to) collects
  // the task's add_to_mask calls; it must outlive the bridge's building.
  explicit SceneBridge(Scene& scene, SegmentationMasks* masks = nullptr);
  ~SceneBridge();
  SceneBridge(const SceneBridge&) = delete;
  SceneBridge& operator=(const SceneBridge&) = delete;

  static const mb_scene_api* getApi();
  mb_scene* getHandle();
  void setBuilding(bool building);
  void setStateChangesAllowed(bool allowed);

 private:
  mb_scene* handle_;
};

// The ABI's frozen record of a joint; `name` must outlive the record.
mb_joint_info makeJointInfo(const JointDescription& joint, const char* name);

}  // namespace manibench
