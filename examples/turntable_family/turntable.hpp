// The Turntable family (a template for a multi-file task family built
// outside manibench's tree): an arm on a vertical hinge must turn to a
// target heading and stop there. Its objects are arms of three lengths
// and three masses, split into train and test; one task, one scripted
// expert.
//
//   turntable_objects.cpp  the object catalog: ids per split, each object's URDF
//   turntable_task.cpp     Turntable-v0 (sdk::Task)
//   turntable_expert.cpp   turntable_expert (sdk::Policy)
//   register.cpp           the one file that registers them and names the library
//   tests/                 the catalog's unit test; CMakeLists.txt adds an
//                          evaluation of the expert through the installed host
#pragma once

#include <manibench/sdk.hpp>

#include <string>
#include <vector>

namespace turntable {

namespace sdk = manibench::sdk;

// One object: a uniform rod turning about a vertical axis at one end.
struct Arm {
  std::string id;
  double length = 0.3;  // m
  double mass = 0.5;    // kg
};

// Object ids of a split ("train" or "test"); an Error for another split.
std::vector<std::string> listArms(const std::string& split);
// The object of an id listed above; an Error (MB_NOT_FOUND) otherwise.
Arm getArm(const std::string& id);
// Its URDF: a fixed base, the rod on one revolute joint "hinge" about z.
std::string makeArmUrdf(const Arm& arm);

class TurntableTask : public sdk::Task {
 public:
  sdk::TaskSpec describe() const override;
  std::vector<std::string> listObjects(const std::string& split) const override { return listArms(split); }
  void buildScene(sdk::SceneView& scene, const std::string& object_id) override;
  void reset(sdk::SceneView& scene, uint64_t seed) override;
  void observe(const sdk::SceneView& scene, Eigen::Map<Eigen::VectorXd> out) override;
  double computeReward(const sdk::SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) override;
  std::vector<sdk::Condition> evaluateSuccess(const sdk::SceneView& scene) override;

 private:
  Arm arm_;
  mb_id articulation_ = -1;
  double target_ = 0;  // rad
};

class TurntableExpert : public sdk::Policy {
 public:
  explicit TurntableExpert(const sdk::PolicyContext& context);
  Eigen::VectorXd act(const sdk::Observation& o) override;

 private:
  uint32_t heading_, target_;  // offsets of the observation's segments, by name
};

}  // namespace turntable
