// mobile_panda: the composite controller of the mobile Panda robots
// (assets/robots/, supplement B.7). Action layout, all normalized to [-1, 1]:
//   0 base_forward  base velocity along the robot's own x  (+-0.5 m/s)
//   1 base_left     base velocity along the robot's own y  (+-0.5 m/s)
//   2 base_yaw      yaw rate                               (+-3.14 rad/s)
//   3 lift          lift velocity                          (+-0.5 m/s)
//   then per arm (right before left): its 7 joint velocities (+-3.14 rad/s)
//   and one gripper action (finger position target, -1 closed .. +1 open).
// Base x/y are egocentric: they are rotated by the current root_yaw into the
// world-aligned root_x/root_y joints. All velocities pass the shared low-pass
// filter and a damping drive; the fingers get a position drive. Joints are
// found by name among the task's actuated joints. Configuration: see
// MobilePandaSettings (mobile_panda_common.hpp).
#include "mobile_panda_common.hpp"

#include <memory>

namespace manibench::controllers {
namespace {

using namespace manibench::sdk;  // Config, ControllerContext, SceneView, ...

class MobilePandaController : public sdk::Controller, public sdk::Stateful {
 public:
  MobilePandaController(const Config& config, const ControllerContext& context)
      : context_(context), settings_(config, "mobile_panda"), joints_(context, "mobile_panda") {
    stage_ = makeVelocityStage(config, context, joints_);
  }

  ControllerSpec describe() const override {
    ControllerSpec spec;
    spec.flags = MB_CONTROLLER_BALANCE_PASSIVE_FORCES;
    spec.action = describeBaseActions(settings_);
    for (const PandaArm& arm : joints_.arms) {
      for (std::size_t slot : arm.joints)
        spec.action.push_back({context_.joints[slot].name, 1,
                               "joint velocity (rad/s, action 1 = " +
                                   formatNumber(settings_.arm_max) + ")"});
      spec.action.push_back(describeGripperAction(settings_, arm.side));
    }
    return spec;
  }

  void reset(const SceneView&) override { stage_->reset(); }

  void compute(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action,
               std::vector<DriveCommand>& drives) override {
    const std::vector<PandaArm>& arms = joints_.arms;
    Eigen::VectorXd velocity(4 + kPandaArmJoints * Eigen::Index(arms.size()));
    velocity.head<4>() = calcBaseVelocity(settings_, action);
    Eigen::Index a = 4;  // next action index
    Eigen::Index v = 4;  // next filtered velocity
    std::vector<double> finger_targets;
    for (std::size_t i = 0; i < arms.size(); ++i) {
      for (int j = 0; j < kPandaArmJoints; ++j) velocity[v++] = action[a++] * settings_.arm_max;
      finger_targets.push_back(calcFingerTarget(settings_, action[a++]));
    }
    const Eigen::VectorXd& filtered = stage_->filter(velocity);
    setBaseDrives(scene, context_, joints_, settings_, filtered.head<4>(), drives);
    v = 4;
    for (std::size_t i = 0; i < arms.size(); ++i) {
      for (int j = 0; j < kPandaArmJoints; ++j)
        setDampingDrive(drives[arms[i].joints[j]], filtered[v++], settings_.arm_damping[j]);
      setGripperDrives(arms[i], settings_, finger_targets[i], drives);
    }
  }
  void saveState(sdk::StateWriter& out) const override { stage_->saveState(out); }
  void restoreState(sdk::StateReader& in) override { stage_->restoreState(in); }

 private:
  ControllerContext context_;
  MobilePandaSettings settings_;
  MobilePandaJoints joints_;
  std::unique_ptr<VelocityStage> stage_;
};

}  // namespace
}  // namespace manibench::controllers

MANIBENCH_REGISTER_CONTROLLER(manibench::controllers::MobilePandaController, "mobile_panda",
                              "mobile Panda robots: egocentric base, lift, arm joint velocities, one "
                              "gripper action per arm (B.7)");
