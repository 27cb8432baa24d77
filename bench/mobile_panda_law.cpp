#include "mobile_panda_law.hpp"

#include <manibench/sdk/numbers.hpp>

#include <cmath>
#include <stdexcept>

namespace manibench::bench {
namespace {

// controllers/mobile_panda_common.hpp, MobilePandaSettings' defaults.
constexpr double kBaseMax = 0.5, kYawMax = 3.14, kLiftMax = 0.5, kArmMax = 3.14;  // per action 1
constexpr double kBaseDamping = 1000;
constexpr double kArmDamping[7] = {200, 300, 200, 100, 100, 100, 100};
constexpr double kGripperStiffness = 5000, kGripperDamping = 800;
constexpr double kGripperClosed = 0.0, kGripperOpen = 0.04;
constexpr double kCutoffHz = 40;  // velocity_stage.hpp

// velocity_stage.hpp's calcLowPassAlpha, the same expression.
double calcLowPassAlpha(double cutoff_hz, double sample_hz) {
  using sdk::kPi;
  const double y = 1.0 - std::cos(2.0 * kPi * cutoff_hz / sample_hz);
  return -y + std::sqrt(y * y + 2.0 * y);
}

DriveCommand makeDampingDrive(double velocity, double damping) {
  DriveCommand d;
  d.velocity_target = velocity;
  d.damping = damping;
  return d;
}

}  // namespace

const std::vector<std::string>& MobilePandaLaw::getJointNames() {
  static const std::vector<std::string> names = {
      "root_x", "root_y", "root_yaw", "lift",
      "right_panda_joint1", "right_panda_joint2", "right_panda_joint3", "right_panda_joint4",
      "right_panda_joint5", "right_panda_joint6", "right_panda_joint7",
      "right_panda_finger_joint1", "right_panda_finger_joint2"};
  return names;
}

MobilePandaLaw::MobilePandaLaw(double control_frequency)
    : alpha_(calcLowPassAlpha(kCutoffHz, control_frequency)), filtered_(Eigen::VectorXd::Zero(11)) {}

void MobilePandaLaw::reset() { filtered_.setZero(); }

void MobilePandaLaw::compute(const Eigen::VectorXd& action, double yaw,
                             std::vector<DriveCommand>& commands) {
  if (action.size() != kActionDim)
    throw std::invalid_argument("mobile_panda law: the action needs 12 values");
  // The same operations in the same order as the controller, so that the
  // commands are bit-identical.
  Eigen::VectorXd velocity(11);
  velocity.head<4>() = Eigen::Vector4d(action[0] * kBaseMax, action[1] * kBaseMax,
                                       action[2] * kYawMax, action[3] * kLiftMax);
  for (int j = 0; j < 7; ++j) velocity[4 + j] = action[4 + j] * kArmMax;
  const double finger = kGripperClosed + 0.5 * (action[11] + 1.0) * (kGripperOpen - kGripperClosed);
  filtered_ = alpha_ * velocity + (1.0 - alpha_) * filtered_;

  commands.assign(13, DriveCommand{});
  const double c = std::cos(yaw), sn = std::sin(yaw);
  commands[0] = makeDampingDrive(c * filtered_[0] - sn * filtered_[1], kBaseDamping);
  commands[1] = makeDampingDrive(sn * filtered_[0] + c * filtered_[1], kBaseDamping);
  commands[2] = makeDampingDrive(filtered_[2], kBaseDamping);
  commands[3] = makeDampingDrive(filtered_[3], kBaseDamping);
  for (int j = 0; j < 7; ++j) commands[4 + j] = makeDampingDrive(filtered_[4 + j], kArmDamping[j]);
  for (int f = 11; f < 13; ++f) {
    commands[f].position_target = finger;
    commands[f].stiffness = kGripperStiffness;
    commands[f].damping = kGripperDamping;
  }
}

}  // namespace manibench::bench
