// Reach: a 2-link arm on a pedestal moves its fingertip to a target point in
// its plane. Objects are arm geometries (link lengths); the test split holds
// lengths the train split never has. The smallest complete task family:
// copy it to start a new one.
#pragma once

#include <manibench/kit/object_ids.hpp>
#include <manibench/sdk.hpp>

#include <string>

namespace reach {

// The family is written in the kit's and the SDK's names (Error, Pose,
// SceneView, Config; NumberedIds for its object ids).
using namespace manibench::kit;
namespace sdk = manibench::sdk;

// Arm geometry of one object id.
struct ArmGeometry {
  double upper_length;
  double fore_length;
};

ArmGeometry getArmGeometry(const std::string& object_id);

// Shoulder position in the world: the arm moves in the x-z plane through it.
inline const Eigen::Vector3d kShoulder(0.0, 0.0, 1.0);

// Observation layout, shared with the expert.
struct ObservationLayout {
  static constexpr uint32_t kJointPositions = 0;   // 2
  static constexpr uint32_t kJointVelocities = 2;  // 2
  static constexpr uint32_t kTip = 4;              // 3
  static constexpr uint32_t kTarget = 7;           // 3
  static constexpr uint32_t kLinkLengths = 10;     // 2
  static constexpr uint32_t kShoulder = 12;        // 3
  static constexpr uint32_t kDim = 15;
};

class ReachTask : public sdk::Task {
 public:
  explicit ReachTask(const Config& config);

  sdk::TaskSpec describe() const override;
  std::vector<std::string> listObjects(const std::string& split) const override;
  void buildScene(SceneView& scene, const std::string& object_id) override;
  void reset(SceneView& scene, uint64_t seed) override;
  void observe(const SceneView& scene, Eigen::Map<Eigen::VectorXd> out) override;
  double computeReward(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) override;
  std::vector<sdk::Condition> evaluateSuccess(const SceneView& scene) override;

 private:
  double reach_tolerance_;   // m
  double static_speed_;      // m/s
  uint32_t hold_steps_;      // consecutive steps both must hold
  ArmGeometry geometry_{};
  mb_id robot_ = -1;
  mb_id tip_ = -1;
  Eigen::Vector3d target_ = Eigen::Vector3d::Zero();
};

class ReachExpert : public sdk::Policy {
 public:
  explicit ReachExpert(const sdk::PolicyContext& context);
  Eigen::VectorXd act(const sdk::Observation& observation) override;

 private:
  Eigen::Index action_dim_;
};

}  // namespace reach
