// Slider-v0: the block starts at rest at 0; the target is drawn per
// episode inside the rail (sdk::Random: the same resets with every
// standard library).
#include "slider.hpp"

#include <cmath>

namespace slider {

sdk::TaskSpec SliderTask::describe() const {
  sdk::TaskSpec spec;
  spec.observation = {{"position", 1, "block position (m)"},
                      {"velocity", 1, "block velocity (m/s)"},
                      {"target", 1, "target position (m)"}};
  spec.success_conditions = {"at_target", "success"};
  spec.robot_articulation = "rail";
  spec.actuated_joints = {"slide"};
  spec.max_episode_steps = 80;
  return spec;
}

void SliderTask::buildScene(sdk::SceneView& scene, const std::string& object_id) {
  rail_ = getRail(object_id);
  sdk::Pose root;
  root.position.z() = 0.5;
  articulation_ = scene.addUrdfString(makeRailUrdf(rail_), "", "rail", root, true);
}

void SliderTask::reset(sdk::SceneView& scene, uint64_t seed) {
  sdk::Random rng(seed);
  target_ = rng.uniform(-0.8, 0.8) * rail_.half_length;
  scene.setJointPositions(articulation_, Eigen::VectorXd::Zero(1));
  scene.setJointVelocities(articulation_, Eigen::VectorXd::Zero(1));
}

void SliderTask::observe(const sdk::SceneView& scene, Eigen::Map<Eigen::VectorXd> out) {
  out << scene.getJointPositions(articulation_)[0], scene.getJointVelocities(articulation_)[0], target_;
}

double SliderTask::computeReward(const sdk::SceneView& scene, Eigen::Map<const Eigen::VectorXd>) {
  return -std::abs(scene.getJointPositions(articulation_)[0] - target_);
}

std::vector<sdk::Condition> SliderTask::evaluateSuccess(const sdk::SceneView& scene) {
  const double error = std::abs(scene.getJointPositions(articulation_)[0] - target_);
  const double speed = std::abs(scene.getJointVelocities(articulation_)[0]);
  const bool at_target = error < 0.01;
  return {{at_target, error}, {at_target && speed < 0.01, speed}};
}

}  // namespace slider
