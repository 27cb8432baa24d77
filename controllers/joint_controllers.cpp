// Joint-space controllers of supplement B.7.
//
// joint_velocity: action in [-1, 1] scaled to each joint's maximum velocity,
//   smoothed by a first-order low-pass filter (exponential moving average),
//   then tracked by a damping drive (stiffness 0). The host balances gravity
//   and Coriolis forces by inverse dynamics (MB_CONTROLLER_BALANCE_PASSIVE_FORCES).
// joint_position: action in [-1, 1] mapped onto each joint's range as a
//   position target; a PID on the position error gives the velocity target
//   of the same velocity stage.
//
// Configuration (YAML, all optional):
//   damping: 100          drive damping, N m s/rad (ManiSkill's arm value)
//   cutoff_hz: 40         low-pass cutoff; ManiSkill: 40 Hz at 100 Hz control
//   max_velocity: 3.14    rad/s or m/s for action 1; default: the joint's
//                         URDF velocity limit, else 3.14
//   kp: 10, ki: 0, kd: 0  (joint_position only)
#include "velocity_stage.hpp"

#include <algorithm>
#include <cmath>

namespace manibench::controllers {
namespace {

using namespace manibench::sdk;  // Config, ControllerContext, SceneView, ...

// The velocity stage of both joint controllers: per-joint scale, low-pass
// filter, one damping drive per context joint.
class JointVelocityStage {
 public:
  JointVelocityStage(const Config& config, const ControllerContext& context)
      : damping_(requirePositive(config, "damping", 100.0)),
        filter_(context.joints.size(), readLowPassAlpha(config, context.control_frequency)) {
    for (const auto& joint : context.joints) {
      const double fallback = joint.velocity_limit > 0 ? joint.velocity_limit : 3.14;
      max_velocity_.push_back(requirePositive(config, "max_velocity", fallback));
    }
  }
  double getMaxVelocity(std::size_t joint) const { return max_velocity_[joint]; }
  void reset() { filter_.reset(); }
  void saveState(sdk::StateWriter& out) const { filter_.saveState(out); }
  void restoreState(sdk::StateReader& in) { filter_.restoreState(in); }
  // `velocity` in joint units; writes one damping drive per joint.
  void apply(const Eigen::VectorXd& velocity, std::vector<DriveCommand>& drives) {
    const Eigen::VectorXd& filtered = filter_.filter(velocity);
    for (std::size_t j = 0; j < drives.size(); ++j)
      setDampingDrive(drives[j], filtered[Eigen::Index(j)], damping_);
  }

 private:
  double damping_;
  VelocityStage filter_;
  std::vector<double> max_velocity_;
};

std::vector<Segment> perJointSegments(const ControllerContext& context, const std::string& what) {
  std::vector<Segment> segments;
  for (const auto& joint : context.joints) segments.push_back({joint.name, 1, what});
  return segments;
}

class JointVelocityController : public sdk::Controller, public sdk::Stateful {
 public:
  JointVelocityController(const Config& config, const ControllerContext& context)
      : context_(context), stage_(config, context) {}

  ControllerSpec describe() const override {
    return {perJointSegments(context_, "velocity target / max velocity"),
            MB_CONTROLLER_BALANCE_PASSIVE_FORCES};
  }
  void reset(const SceneView&) override { stage_.reset(); }
  void compute(const SceneView&, Eigen::Map<const Eigen::VectorXd> action,
               std::vector<DriveCommand>& drives) override {
    Eigen::VectorXd velocity(action.size());
    for (Eigen::Index j = 0; j < action.size(); ++j)
      velocity[j] = action[j] * stage_.getMaxVelocity(std::size_t(j));
    stage_.apply(velocity, drives);
  }
  void saveState(sdk::StateWriter& out) const override { stage_.saveState(out); }
  void restoreState(sdk::StateReader& in) override { stage_.restoreState(in); }

 private:
  ControllerContext context_;
  JointVelocityStage stage_;
};

class JointPositionController : public sdk::Controller, public sdk::Stateful {
 public:
  JointPositionController(const Config& config, const ControllerContext& context)
      : context_(context),
        stage_(config, context),
        kp_(requirePositive(config, "kp", 10.0)),
        ki_(config.get<double>("ki", 0.0)),
        kd_(config.get<double>("kd", 0.0)),
        dt_(1.0 / context.control_frequency) {
    for (const auto& joint : context.joints) {
      const bool limited = std::isfinite(joint.lower) && std::isfinite(joint.upper);
      lower_.push_back(limited ? joint.lower : -kPi);
      upper_.push_back(limited ? joint.upper : kPi);
    }
    integral_ = previous_error_ = Eigen::VectorXd::Zero(Eigen::Index(context.joints.size()));
  }

  ControllerSpec describe() const override {
    return {perJointSegments(context_, "position target over the joint range, -1 = lower limit"),
            MB_CONTROLLER_BALANCE_PASSIVE_FORCES};
  }
  void reset(const SceneView&) override {
    stage_.reset();
    integral_.setZero();
    previous_error_.setZero();
    first_step_ = true;
  }
  void compute(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action,
               std::vector<DriveCommand>& drives) override {
    const Eigen::VectorXd q = scene.getJointPositions(context_.articulation);
    Eigen::VectorXd velocity(action.size());
    for (Eigen::Index j = 0; j < action.size(); ++j) {
      const std::size_t i = std::size_t(j);
      const double target = lower_[i] + 0.5 * (action[j] + 1.0) * (upper_[i] - lower_[i]);
      const double error = target - q[Eigen::Index(context_.joints[i].index)];
      integral_[j] += error * dt_;
      const double derivative = first_step_ ? 0.0 : (error - previous_error_[j]) / dt_;
      previous_error_[j] = error;
      const double limit = stage_.getMaxVelocity(i);
      velocity[j] = std::clamp(kp_ * error + ki_ * integral_[j] + kd_ * derivative, -limit, limit);
    }
    first_step_ = false;
    stage_.apply(velocity, drives);
  }
  void saveState(sdk::StateWriter& out) const override {
    stage_.saveState(out);
    out.writeMatrix(integral_);
    out.writeMatrix(previous_error_);
    out.write<uint8_t>(first_step_);
  }
  void restoreState(sdk::StateReader& in) override {
    stage_.restoreState(in);
    const Eigen::Index joints = integral_.size();
    in.readMatrix(integral_);
    in.readMatrix(previous_error_);
    first_step_ = in.read<uint8_t>() != 0;
    if (integral_.size() != joints || previous_error_.size() != joints)
      throw sdk::Error("joint_position state: PID terms for another number of joints",
                                  MB_INVALID_ARGUMENT);
  }

 private:
  ControllerContext context_;
  JointVelocityStage stage_;
  double kp_, ki_, kd_, dt_;
  std::vector<double> lower_, upper_;
  Eigen::VectorXd integral_, previous_error_;
  bool first_step_ = true;
};

}  // namespace
}  // namespace manibench::controllers

MANIBENCH_REGISTER_CONTROLLER(manibench::controllers::JointVelocityController, "joint_velocity",
                              "joint velocity targets, low-pass filtered, damping drive, gravity balanced (B.7)");
MANIBENCH_REGISTER_CONTROLLER(manibench::controllers::JointPositionController, "joint_position",
                              "joint position targets through a PID onto joint_velocity (B.7)");
MANIBENCH_PLUGIN_LIBRARY("manibench_controllers", "0.1.0");
