// What scripted policies (the families' experts) share: reading positions
// and quaternions out of a state vector, clipping actions, wrapping angles.
#pragma once

#include <manibench/sdk/numbers.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace manibench::sdk {

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

}  // namespace manibench::sdk
