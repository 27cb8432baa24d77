// mobile_panda_ee: the mobile Panda robots with end-effector velocity
// control of each arm (supplement B.7's delta-pose idea, as velocities).
// Action layout, all normalized to [-1, 1]:
//   0-3 base_forward, base_left, base_yaw, lift   exactly as mobile_panda
//   then per arm (right before left):
//     <side>_ee_linear  (3) TCP velocity along x, y, z of base_link, the
//                           robot's own frame that yaws with the base
//                           (action 1 = ee_linear_max, 0.5 m/s)
//     <side>_ee_angular (3) TCP angular velocity about base_link x, y, z
//                           (action 1 = ee_angular_max, 1.57 rad/s)
//     <side>_gripper    (1) as mobile_panda: -1 closed .. +1 open
// 11 values single-arm, 18 dual.
//
// Per arm and control step: the commanded twist moves a target pose of the
// TCP (link <side>_panda_tcp) held in body_link's frame (the lift's link,
// which carries the arms and is turned as base_link); the twist plus a
// proportional pull towards that target (ee_feedback_gain, so that the
// drives' lag and the damping below do not bend the path or let it drift)
// is solved for the 7 arm joints by damped least squares on the arm columns
// of the TCP Jacobian, qdot = J^T (J J^T + ik_damping^2 I)^-1 twist, scaled
// down as a whole when a joint would exceed arm_max_velocity. These joint
// velocities then take mobile_panda's path: low-pass filter, damping drive,
// passive forces balanced. The base and lift are driven separately (the arm
// solve sees only the arm's columns), so a moving base or lift carries the
// arm along and the TCP keeps its pose relative to them. A blocked TCP does
// not wind the target up: it stays within ee_max_position_error and
// ee_max_orientation_error of the TCP.
//
// Configuration: everything of mobile_panda (MobilePandaSettings) and
//   ee_linear_max: 0.5 (m/s)   ee_angular_max: 1.57 (rad/s)
//   ik_damping: 0.02           ee_feedback_gain: 10 (1/s; 0 = open loop)
//   ee_max_position_error: 0.02 (m)   ee_max_orientation_error: 0.1 (rad)
#include "mobile_panda_common.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <memory>

namespace manibench::controllers {
namespace {

using namespace manibench::sdk;  // Config, ControllerContext, SceneView, ...

constexpr int kActionsPerArm = 7;  // linear 3, angular 3, gripper 1

double requireNonNegative(const Config& config, const std::string& key, double fallback) {
  const double value = config.get<double>(key, fallback);
  if (!(value >= 0) || !std::isfinite(value))
    throw Error("mobile_panda_ee configuration: '" + key + "' must be a non-negative number, got " +
                    std::to_string(value),
                MB_INVALID_ARGUMENT);
  return value;
}

// Rotation vector (axis * angle) of `r`, angle in [0, pi].
Eigen::Vector3d calcRotationVector(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.axis() * aa.angle();
}

Eigen::Matrix3d fromRotationVector(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
}

class MobilePandaEeController : public sdk::Controller,
                                public sdk::Stateful,
                                public sdk::ControllerLayer {
 public:
  MobilePandaEeController(const Config& config, const ControllerContext& context)
      : context_(context),
        settings_(config, "mobile_panda_ee"),
        joints_(context, "mobile_panda_ee"),
        linear_max_(requirePositive(config, "ee_linear_max", manibench::kit::MobilePandaSpeeds::kEeLinear)),
        angular_max_(requirePositive(config, "ee_angular_max", manibench::kit::MobilePandaSpeeds::kEeAngular)),
        ik_damping_(requireNonNegative(config, "ik_damping", 0.02)),
        feedback_gain_(requireNonNegative(config, "ee_feedback_gain", 10.0)),
        max_position_error_(requirePositive(config, "ee_max_position_error", 0.02)),
        max_orientation_error_(requirePositive(config, "ee_max_orientation_error", 0.1)),
        targets_(joints_.arms.size(), Eigen::Isometry3d::Identity()) {
    stage_ = makeVelocityStage(config, context, joints_);
  }

  ControllerSpec describe() const override {
    ControllerSpec spec;
    spec.flags = MB_CONTROLLER_BALANCE_PASSIVE_FORCES;
    spec.action = describeBaseActions(settings_);
    for (const PandaArm& arm : joints_.arms) {
      spec.action.push_back({arm.side + "_ee_linear", 3,
                             "TCP velocity along base_link x, y, z (m/s, action 1 = " +
                                 formatNumber(linear_max_) + ")"});
      spec.action.push_back({arm.side + "_ee_angular", 3,
                             "TCP angular velocity about base_link x, y, z (rad/s, action 1 = " +
                                 formatNumber(angular_max_) + ")"});
      spec.action.push_back(describeGripperAction(settings_, arm.side));
    }
    return spec;
  }

  void reset(const SceneView& scene) override {
    stage_->reset();
    base_action_.resize(0);
    resolveLinks(scene);
    const Eigen::Isometry3d body_inverse = scene.getLinkPose(body_link_).toIsometry().inverse();
    for (std::size_t i = 0; i < tcp_links_.size(); ++i)
      targets_[i] = body_inverse * scene.getLinkPose(tcp_links_[i]).toIsometry();
  }

  void compute(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action,
               std::vector<DriveCommand>& drives) override {
    // abi.h's per-step contract: the host resets a controller before it
    // computes.
    if (tcp_links_.empty())
      throw Error("mobile_panda_ee: compute before reset (the host broke the per-step contract)",
                  MB_ERROR);
    const std::vector<PandaArm>& arms = joints_.arms;
    const double dt = 1.0 / context_.control_frequency;
    // body_link: base_link raised by the lift, so its axes are base_link's.
    const Eigen::Isometry3d body = scene.getLinkPose(body_link_).toIsometry();

    Eigen::VectorXd velocity(4 + kPandaArmJoints * Eigen::Index(arms.size()));
    velocity.head<4>() = calcBaseVelocity(settings_, action);
    // mobile_panda's action that makes these same drives (ControllerLayer):
    // base and grippers as given, the arm joints normalized.
    base_action_.resize(4 + (kPandaArmJoints + 1) * Eigen::Index(arms.size()));
    base_action_.head<4>() = action.head<4>();
    std::vector<double> finger_targets;
    for (std::size_t i = 0; i < arms.size(); ++i) {
      const Eigen::Index a = 4 + kActionsPerArm * Eigen::Index(i);
      const Eigen::Index b = 4 + (kPandaArmJoints + 1) * Eigen::Index(i);
      const Eigen::Vector3d linear = action.segment<3>(a) * linear_max_;
      const Eigen::Vector3d angular = action.segment<3>(a + 3) * angular_max_;
      finger_targets.push_back(calcFingerTarget(settings_, action[a + 6]));
      const Eigen::Matrix<double, kPandaArmJoints, 1> qdot = solveArm(scene, i, body, linear, angular, dt);
      // The joint velocities go on as mobile_panda's de-normalised action
      // (within 1 ulp of qdot), so that its action reproduces them exactly.
      for (int j = 0; j < kPandaArmJoints; ++j) {
        base_action_[b + j] = normalizeVelocity(qdot[j], settings_.arm_max);
        velocity[4 + kPandaArmJoints * Eigen::Index(i) + j] = base_action_[b + j] * settings_.arm_max;
      }
      base_action_[b + kPandaArmJoints] = action[a + 6];
    }
    const Eigen::VectorXd& filtered = stage_->filter(velocity);
    setBaseDrives(scene, context_, joints_, settings_, filtered.head<4>(), drives);
    Eigen::Index v = 4;
    for (std::size_t i = 0; i < arms.size(); ++i) {
      for (int j = 0; j < kPandaArmJoints; ++j)
        setDampingDrive(drives[arms[i].joints[j]], filtered[v++], settings_.arm_damping[j]);
      setGripperDrives(arms[i], settings_, finger_targets[i], drives);
    }
  }

  std::string getBaseController() const override { return "mobile_panda"; }
  Eigen::VectorXd getBaseAction() const override {
    if (base_action_.size() == 0)
      throw Error("mobile_panda_ee: no base action before the episode's first compute", MB_UNSUPPORTED);
    return base_action_;
  }

  // The filter and the integrated TCP targets (the links come from reset).
  void saveState(sdk::StateWriter& out) const override {
    stage_->saveState(out);
    out.write<uint64_t>(targets_.size());
    for (const Eigen::Isometry3d& target : targets_) out.writeMatrix(target.matrix());
  }
  void restoreState(sdk::StateReader& in) override {
    stage_->restoreState(in);
    if (in.read<uint64_t>() != targets_.size())
      throw Error("mobile_panda_ee state: TCP targets for another number of arms",
                  MB_INVALID_ARGUMENT);
    for (Eigen::Isometry3d& target : targets_) {
      Eigen::Matrix4d m;
      in.readMatrix(m);
      target.matrix() = m;
    }
  }

 private:
  void resolveLinks(const SceneView& scene) {
    if (!tcp_links_.empty()) return;
    try {
      body_link_ = scene.findLink(context_.articulation, "body_link");
      for (const PandaArm& arm : joints_.arms)
        tcp_links_.push_back(scene.findLink(context_.articulation, arm.side + "_panda_tcp"));
    } catch (const Error& e) {
      tcp_links_.clear();
      throw Error(std::string("mobile_panda_ee controller: ") + e.what() +
                      " (it needs body_link and <side>_panda_tcp)",
                  MB_INVALID_ARGUMENT);
    }
  }

  // Joint velocities of arm `i` for the commanded TCP twist (body frame,
  // whose axes are base_link's).
  Eigen::Matrix<double, kPandaArmJoints, 1> solveArm(const SceneView& scene, std::size_t i,
                                                     const Eigen::Isometry3d& body,
                                                     const Eigen::Vector3d& linear,
                                                     const Eigen::Vector3d& angular, double dt) {
    const PandaArm& arm = joints_.arms[i];
    Eigen::Isometry3d& target = targets_[i];
    // The target moves with the command; then it is kept near the TCP.
    target.translation() += linear * dt;
    target.linear() = fromRotationVector(angular * dt) * target.linear();
    const Eigen::Isometry3d tcp = body.inverse() * scene.getLinkPose(tcp_links_[i]).toIsometry();
    Eigen::Vector3d position_error = target.translation() - tcp.translation();
    Eigen::Vector3d orientation_error = calcRotationVector(target.linear() * tcp.linear().transpose());
    if (position_error.norm() > max_position_error_) {
      position_error *= max_position_error_ / position_error.norm();
      target.translation() = tcp.translation() + position_error;
    }
    if (orientation_error.norm() > max_orientation_error_) {
      orientation_error *= max_orientation_error_ / orientation_error.norm();
      target.linear() = fromRotationVector(orientation_error) * tcp.linear();
    }
    // Twist in the world frame, angular first as the Jacobian's rows.
    Eigen::Matrix<double, 6, 1> twist;
    twist.head<3>() = body.linear() * (angular + feedback_gain_ * orientation_error);
    twist.tail<3>() = body.linear() * (linear + feedback_gain_ * position_error);

    const Eigen::MatrixXd full = scene.calcLinkJacobian(context_.articulation, tcp_links_[i]);
    Eigen::Matrix<double, 6, kPandaArmJoints> j;
    for (int c = 0; c < kPandaArmJoints; ++c)
      j.col(c) = full.col(Eigen::Index(context_.joints[arm.joints[c]].index));
    const Eigen::Matrix<double, 6, 6> jjt =
        j * j.transpose() + ik_damping_ * ik_damping_ * Eigen::Matrix<double, 6, 6>::Identity();
    Eigen::Matrix<double, kPandaArmJoints, 1> qdot = j.transpose() * jjt.ldlt().solve(twist);
    // Only with ik_damping 0 at an exact singularity: hold rather than send NaN.
    if (!qdot.allFinite()) qdot.setZero();
    // Scaled as a whole, so that the TCP keeps its direction.
    const double fastest = qdot.cwiseAbs().maxCoeff();
    if (fastest > settings_.arm_max) qdot *= settings_.arm_max / fastest;
    return qdot;
  }

  ControllerContext context_;
  MobilePandaSettings settings_;
  MobilePandaJoints joints_;
  double linear_max_, angular_max_, ik_damping_, feedback_gain_;
  double max_position_error_, max_orientation_error_;
  mb_id body_link_ = -1;
  std::vector<mb_id> tcp_links_;            // per arm, once resolved
  std::vector<Eigen::Isometry3d> targets_;  // per arm: TCP target pose in body_link
  std::unique_ptr<VelocityStage> stage_;
  Eigen::VectorXd base_action_;  // mobile_panda's action of the last compute
};

}  // namespace
}  // namespace manibench::controllers

MANIBENCH_REGISTER_CONTROLLER(manibench::controllers::MobilePandaEeController, "mobile_panda_ee",
                              "mobile Panda robots: egocentric base, lift, TCP linear and angular "
                              "velocity per arm in the base frame, one gripper action per arm (B.7)");
