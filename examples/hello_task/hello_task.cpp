// HelloSlider-v0: a block on a horizontal rail must stop at a target
// position. The smallest useful task: one joint, three observation values.
#include <manibench/sdk.hpp>

#include "rail.hpp"

#include <cmath>

namespace {

namespace sdk = manibench::sdk;

using hello_task::kRailUrdf;

class HelloSlider : public sdk::Task {
 public:
  sdk::TaskSpec describe() const override {
    sdk::TaskSpec spec;
    spec.observation = {{"position", 1, "block position (m)"},
                        {"velocity", 1, "block velocity (m/s)"},
                        {"target", 1, "target position (m)"}};
    spec.success_conditions = {"at_target", "success"};
    spec.robot_articulation = "rail";
    spec.actuated_joints = {"slide"};
    spec.max_episode_steps = 60;
    return spec;
  }
  void buildScene(sdk::SceneView& scene, const std::string&) override {
    sdk::Pose root;
    root.position.z() = 0.5;
    rail_ = scene.addUrdfString(kRailUrdf, "", "rail", root, true);
  }
  void reset(sdk::SceneView& scene, uint64_t seed) override {
    // sdk::Random (sdk/random.hpp), not std::mt19937_64 with a
    // std::uniform_real_distribution: the standard leaves a distribution's
    // output to the library, so resets would differ between libstdc++ and
    // libc++; Random's numbers are the same everywhere.
    sdk::Random rng(seed);
    target_ = rng.uniform(-0.4, 0.4);
    scene.setJointPositions(rail_, Eigen::VectorXd::Zero(1));
  }
  void observe(const sdk::SceneView& scene, Eigen::Map<Eigen::VectorXd> out) override {
    out << scene.getJointPositions(rail_)[0], scene.getJointVelocities(rail_)[0], target_;
  }
  double computeReward(const sdk::SceneView& scene, Eigen::Map<const Eigen::VectorXd>) override {
    return -std::abs(scene.getJointPositions(rail_)[0] - target_);
  }
  std::vector<sdk::Condition> evaluateSuccess(const sdk::SceneView& scene) override {
    const double error = std::abs(scene.getJointPositions(rail_)[0] - target_);
    const double speed = std::abs(scene.getJointVelocities(rail_)[0]);
    const bool at_target = error < 0.01;
    return {{at_target, error}, {at_target && speed < 0.01, speed}};
  }

 private:
  mb_id rail_ = -1;
  double target_ = 0;
};

class HelloExpert : public sdk::Policy {
 public:
  explicit HelloExpert(const sdk::PolicyContext&) {}
  Eigen::VectorXd act(const sdk::Observation& o) override {
    const double command = 4.0 * (o.state[2] - o.state[0]);  // proportional
    return Eigen::VectorXd::Constant(1, std::clamp(command, -1.0, 1.0));
  }
};

}  // namespace

MANIBENCH_REGISTER_TASK(HelloSlider, "HelloSlider-v0", "a block on a rail stops at a target");
MANIBENCH_REGISTER_POLICY(HelloExpert, "hello_expert", "proportional control for HelloSlider-v0");
MANIBENCH_PLUGIN_LIBRARY("hello_task", "1.0.0");
