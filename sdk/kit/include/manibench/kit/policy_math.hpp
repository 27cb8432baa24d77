// What scripted policies (the families' experts) share: reading positions
// and quaternions out of a state vector, clipping actions, wrapping angles,
// and turning the velocities a policy wants into the mobile Panda
// controllers' actions.
#pragma once

#include <manibench/kit/common.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace manibench::kit {

// The 3 values of `state` from `at`.
inline Eigen::Vector3d getVector3(const Eigen::VectorXd& state, uint32_t at) { return state.segment<3>(at); }
// The quaternion stored w, x, y, z from `at` (the observations' order),
// normalized.
inline Eigen::Quaterniond getQuaternion(const Eigen::VectorXd& state, uint32_t at) {
  return Eigen::Quaterniond(state[at], state[at + 1], state[at + 2], state[at + 3]).normalized();
}
// An action value within [-1, 1].
inline double clipUnit(double x) { return std::clamp(x, -1.0, 1.0); }
// `v` (a vector or an expression), shortened to length `most` when longer.
template <class Derived>
typename Derived::PlainObject clipNorm(const Eigen::MatrixBase<Derived>& v, double most) {
  using Plain = typename Derived::PlainObject;
  const Plain value = v;
  const double n = value.norm();
  return n > most ? Plain(value * (most / n)) : value;
}
// An angle in [-pi, pi].
inline double wrapAngle(double a) { return std::remainder(a, 2 * kPi); }

// What action 1 means to the mobile Panda controllers in their default
// configuration (controllers/ takes its defaults from here): base speed per
// axis, yaw rate and lift speed (mobile_panda and mobile_panda_ee), the
// end effector's linear and angular speed (mobile_panda_ee).
struct MobilePandaSpeeds {
  static constexpr double kBase = 0.5;       // m/s
  static constexpr double kYaw = 3.14;       // rad/s
  static constexpr double kLift = 0.5;       // m/s
  static constexpr double kEeLinear = 0.5;   // m/s
  static constexpr double kEeAngular = 1.57; // rad/s
};

// The base's four actions from `at` (forward, left, yaw, lift) for a
// base-frame velocity, a yaw rate and a lift rate, clipped to [-1, 1].
inline void setBaseAction(Eigen::VectorXd& action, uint32_t at, const Eigen::Vector2d& base_local,
                          double yaw_rate, double lift_rate) {
  action[at] = clipUnit(base_local.x() / MobilePandaSpeeds::kBase);
  action[at + 1] = clipUnit(base_local.y() / MobilePandaSpeeds::kBase);
  action[at + 2] = clipUnit(yaw_rate / MobilePandaSpeeds::kYaw);
  action[at + 3] = clipUnit(lift_rate / MobilePandaSpeeds::kLift);
}

// An arm's end-effector actions (mobile_panda_ee: three linear from
// `linear_at`, three angular from `angular_at`, in the base frame) for the
// TCP's world-frame velocities; `base_rotation` turns base into world.
inline void setEeAction(Eigen::VectorXd& action, uint32_t linear_at, uint32_t angular_at,
                        const Eigen::Matrix3d& base_rotation, const Eigen::Vector3d& linear,
                        const Eigen::Vector3d& angular) {
  const Eigen::Vector3d linear_local = base_rotation.transpose() * linear;
  const Eigen::Vector3d angular_local = base_rotation.transpose() * angular;
  for (int i = 0; i < 3; ++i) {
    action[linear_at + i] = clipUnit(linear_local[i] / MobilePandaSpeeds::kEeLinear);
    action[angular_at + i] = clipUnit(angular_local[i] / MobilePandaSpeeds::kEeAngular);
  }
}

}  // namespace manibench::kit
