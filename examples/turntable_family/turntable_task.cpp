// Turntable-v0: the rod starts at rest at heading 0; the target heading is
// drawn per episode (sdk::Random: the same resets with every standard
// library). Success: within 0.02 rad of it and slower than 0.02 rad/s.
#include "turntable.hpp"

#include <cmath>

namespace turntable {

sdk::TaskSpec TurntableTask::describe() const {
  sdk::TaskSpec spec;
  spec.observation = {{"heading", 1, "rod heading (rad)"},
                      {"turn_rate", 1, "its rate (rad/s)"},
                      {"target_heading", 1, "where it must stop (rad)"}};
  spec.success_conditions = {"on_heading", "success"};
  spec.robot_articulation = "turntable";
  spec.actuated_joints = {"hinge"};
  spec.max_episode_steps = 100;
  return spec;
}

void TurntableTask::buildScene(sdk::SceneView& scene, const std::string& object_id) {
  arm_ = getArm(object_id);
  sdk::Pose base;
  base.position.z() = 0.3;
  articulation_ = scene.addUrdfString(makeArmUrdf(arm_), "", "turntable", base, true);
}

void TurntableTask::reset(sdk::SceneView& scene, uint64_t seed) {
  sdk::Random rng(seed);
  target_ = rng.uniform(-2.0, 2.0);
  scene.setJointPositions(articulation_, Eigen::VectorXd::Zero(1));
  scene.setJointVelocities(articulation_, Eigen::VectorXd::Zero(1));
}

void TurntableTask::observe(const sdk::SceneView& scene, Eigen::Map<Eigen::VectorXd> out) {
  out[0] = scene.getJointPositions(articulation_)[0];
  out[1] = scene.getJointVelocities(articulation_)[0];
  out[2] = target_;
}

double TurntableTask::computeReward(const sdk::SceneView& scene, Eigen::Map<const Eigen::VectorXd>) {
  return -std::abs(scene.getJointPositions(articulation_)[0] - target_);
}

std::vector<sdk::Condition> TurntableTask::evaluateSuccess(const sdk::SceneView& scene) {
  const double miss = std::abs(scene.getJointPositions(articulation_)[0] - target_);
  const double rate = std::abs(scene.getJointVelocities(articulation_)[0]);
  return {{miss < 0.02, miss}, {miss < 0.02 && rate < 0.02, rate}};
}

}  // namespace turntable
