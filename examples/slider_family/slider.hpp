// The Slider family (a template for a multi-file task family built outside
// manibench's tree): a block on a horizontal rail must stop at a target.
// Its objects are rails of different lengths and blocks of different
// masses, split into train and test; one task, one scripted expert.
//
//   slider_objects.cpp  the object catalog: ids per split, each object's URDF
//   slider_task.cpp     Slider-v0 (sdk::Task)
//   slider_expert.cpp   slider_expert (sdk::Policy)
//   register.cpp        the one file that registers them and names the library
//   tests/              the catalog's unit test; CMakeLists.txt adds an
//                       evaluation of the expert through the installed host
#pragma once

#include <manibench/sdk.hpp>

#include <string>
#include <vector>

namespace slider {

namespace sdk = manibench::sdk;

// One object: a rail and its block.
struct Rail {
  std::string id;
  double half_length = 0.5;  // m: the joint's limits are +-half_length
  double block_mass = 0.5;   // kg
};

// Object ids of a split ("train" or "test"); an Error for another split.
std::vector<std::string> listRails(const std::string& split);
// The object of an id listed above; an Error (MB_NOT_FOUND) otherwise.
Rail getRail(const std::string& id);
// Its URDF: a fixed rail link, a block on one prismatic joint "slide".
std::string makeRailUrdf(const Rail& rail);

class SliderTask : public sdk::Task {
 public:
  sdk::TaskSpec describe() const override;
  std::vector<std::string> listObjects(const std::string& split) const override { return listRails(split); }
  void buildScene(sdk::SceneView& scene, const std::string& object_id) override;
  void reset(sdk::SceneView& scene, uint64_t seed) override;
  void observe(const sdk::SceneView& scene, Eigen::Map<Eigen::VectorXd> out) override;
  double computeReward(const sdk::SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) override;
  std::vector<sdk::Condition> evaluateSuccess(const sdk::SceneView& scene) override;

 private:
  Rail rail_;
  mb_id articulation_ = -1;
  double target_ = 0;
};

class SliderExpert : public sdk::Policy {
 public:
  explicit SliderExpert(const sdk::PolicyContext& context);
  Eigen::VectorXd act(const sdk::Observation& o) override;

 private:
  uint32_t position_, velocity_, target_;  // offsets of the segments, by name
};

}  // namespace slider
