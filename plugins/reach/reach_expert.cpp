// Scripted expert for Reach-v0: analytic 2-link inverse kinematics in the
// arm's plane, then a proportional joint-velocity command.
#include "reach.hpp"

#include <algorithm>
#include <cmath>

namespace reach {

ReachExpert::ReachExpert(const sdk::PolicyContext& context) : action_dim_(context.action.dim) {
  if (context.task_name != "Reach-v0" || context.observation.dim != ObservationLayout::kDim ||
      action_dim_ != 2)
    throw Error("reach_expert only drives Reach-v0 with a 2-joint velocity action, not '" +
                    context.task_name + "'",
                MB_INVALID_ARGUMENT);
}

Eigen::VectorXd ReachExpert::act(const sdk::Observation& observation) {
  using L = ObservationLayout;
  const Eigen::VectorXd& s = observation.state;
  const Eigen::Vector2d q = s.segment<2>(L::kJointPositions);
  const Eigen::Vector3d target = s.segment<3>(L::kTarget);
  const Eigen::Vector3d shoulder = s.segment<3>(L::kShoulder);
  const double l1 = s[L::kLinkLengths], l2 = s[L::kLinkLengths + 1];

  // Rotation about +y by q takes x to (cos q, 0, -sin q): in the plane
  // coordinates (u, w) = (x, -z) the arm is the textbook planar 2-link arm.
  const double u = target.x() - shoulder.x();
  const double w = -(target.z() - shoulder.z());
  const double c2 = std::clamp((u * u + w * w - l1 * l1 - l2 * l2) / (2 * l1 * l2), -1.0, 1.0);
  Eigen::Vector2d best;
  double best_distance = INFINITY;
  for (const double sign : {1.0, -1.0}) {  // the two elbow solutions: take the nearer
    const double q2 = sign * std::acos(c2);
    const double q1 = std::atan2(w, u) - std::atan2(l2 * std::sin(q2), l1 + l2 * std::cos(q2));
    const Eigen::Vector2d candidate(q1, q2);
    const double d = (candidate - q).norm();
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  // Proportional velocity command, normalized by the controller's range.
  Eigen::VectorXd action = (2.0 * (best - q)).cwiseMax(-1.0).cwiseMin(1.0);
  return action;
}

}  // namespace reach
