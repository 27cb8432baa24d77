// Pieces shared by the controllers of this library (supplement B.7): the
// configuration checks and the velocity stage (first-order low-pass filter,
// then a damping drive per joint).
#pragma once

#include <manibench/sdk.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace manibench::controllers {

using sdk::kPi;

// Smoothing factor of an exponential moving average whose -3 dB point is
// `cutoff_hz` when sampled at `sample_hz` (first-order IIR design).
inline double calcLowPassAlpha(double cutoff_hz, double sample_hz) {
  const double y = 1.0 - std::cos(2.0 * kPi * cutoff_hz / sample_hz);
  return -y + std::sqrt(y * y + 2.0 * y);
}

inline double requirePositive(const sdk::Config& config, const std::string& key, double fallback) {
  const double value = config.get<double>(key, fallback);
  if (!(value > 0) || !std::isfinite(value))
    throw sdk::Error("controller configuration: '" + key + "' must be a positive number, got " +
                         std::to_string(value),
                     MB_INVALID_ARGUMENT);
  return value;
}

// The low-pass filter's alpha from `cutoff_hz` (default 40 Hz, ManiSkill's
// value at 100 Hz control); the cutoff must lie below the Nyquist frequency.
inline double readLowPassAlpha(const sdk::Config& config, double control_frequency) {
  const double cutoff = requirePositive(config, "cutoff_hz", 40.0);
  if (config.has("cutoff_hz") && cutoff >= control_frequency / 2)
    throw sdk::Error("controller configuration: cutoff_hz must be below half the control frequency (" +
                         std::to_string(control_frequency / 2) + " Hz)",
                     MB_INVALID_ARGUMENT);
  return calcLowPassAlpha(cutoff, control_frequency);
}

// tau = damping (velocity - qdot): tracks a velocity without a position goal.
inline void setDampingDrive(sdk::DriveCommand& drive, double velocity, double damping) {
  drive.position_target = 0;
  drive.stiffness = 0;
  drive.velocity_target = velocity;
  drive.damping = damping;
  drive.force = 0;
}

// Filters velocity targets (joint units) with an exponential moving average;
// the state persists across control steps until reset().
class VelocityStage {
 public:
  VelocityStage(std::size_t size, double alpha)
      : alpha_(alpha), filtered_(Eigen::VectorXd::Zero(Eigen::Index(size))) {}
  void reset() { filtered_.setZero(); }
  const Eigen::VectorXd& filter(const Eigen::VectorXd& velocity) {
    filtered_ = alpha_ * velocity + (1.0 - alpha_) * filtered_;
    return filtered_;
  }
  // The filter's memory is episode state (sdk::Stateful).
  void saveState(sdk::StateWriter& out) const { out.writeMatrix(filtered_); }
  void restoreState(sdk::StateReader& in) {
    const Eigen::Index size = filtered_.size();
    in.readMatrix(filtered_);
    if (filtered_.size() != size)
      throw sdk::Error("controller state: a filter of " + std::to_string(filtered_.size()) +
                           " values for " + std::to_string(size) + " joints",
                       MB_INVALID_ARGUMENT);
  }

 private:
  double alpha_;
  Eigen::VectorXd filtered_;
};

}  // namespace manibench::controllers
