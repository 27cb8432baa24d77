// What the linearly implicit Euler step (implicit_euler_stepper.cpp) needs
// of the stiff forces besides their value at the start of a step: how they
// change with the generalized speeds and positions during the step.
//
// A step of size h from (q, u) solves
//   (M + h D + h^2 K) du = h (F - h K u),   u+ = u + du,   q+ = q + h N(q) u+
// where F = M udot is the net generalized force at the start, D = -dF/du the
// damping and K = -(dF/dq) N the stiffness, both in the space of u. Forces
// left out of D and K (gravity, Coriolis, balancing) are explicit; stiff
// ones put in stay stable at any step size.
//
// Force elements describe D and K in two sparse forms, which the stepper
// assembles per contact island (tree_structure.hpp): joint-space terms on
// the diagonal, and contact points whose 3 x 3 damping C and stiffness K
// act on the relative velocity of the two bodies' material points there
// (J^T C J with J that velocity's Jacobian).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "Simbody.h"

namespace manibench {
namespace scene_detail {

// A one-dof generalized force whose linear law saturates at +-limit (a
// drive with an effort limit). It stays out of the diagonal: each step the
// stepper finds whether, at the step's end, the law lies within the limit
// (it then acts linearly, implicit) or beyond it (a constant +-limit).
// Deciding it at the start instead makes a damping drive chatter between
// its two limits whenever one step's velocity change crosses the linear
// band (12 N m on a Panda wrist: 2.4 rad/s per 2 ms step against a band of
// 0.12 rad/s).
struct SaturatingForce {
  int u = 0;             // index of its generalized speed
  double applied = 0;    // what the force element applied (clamped)
  double unclamped = 0;  // the linear law at the step's start
  double damping = 0;    // -d(law)/du
  double stiffness = 0;  // -d(law)/dq
  double limit = 0;      // > 0
};

// A contact point's force law, linearized: the force on B changes by
// -damping v - stiffness x for a velocity v and a displacement x of B's
// material point at `point` relative to A's (Ground frame).
//
// A point whose friction slides at the step's start (its stick law, a
// tangential spring to the anchor and a damper on the slip, beyond mu fn)
// applied the capped force, constant along its direction: the stepper
// checks, as for a SaturatingForce, whether the stick law is back within
// the limit at the step's end (the capped force would have stopped or
// reversed the slip: a light body, a caster wheel of 7e-6 kg m^2, else
// chatters between +-48 rad/s) and then steps the point as sticking.
struct PointCoupling {
  SimTK::MobilizedBodyIndex body_a, body_b;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Matrix3d damping, stiffness;  // symmetric, positive semidefinite
  bool sliding = false;
  // Sliding points only: the tangential forces on B at the start, capped
  // (applied) and of the stick law; the stick law's tangential damping and
  // stiffness (its linearization is damping/stiffness plus these outside
  // the capped direction: stick_damping, stick_stiffness in full); mu fn.
  Eigen::Vector3d slide_force = Eigen::Vector3d::Zero(), stick_force = Eigen::Vector3d::Zero();
  Eigen::Matrix3d stick_damping = Eigen::Matrix3d::Zero(), stick_stiffness = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d tangent_damping = Eigen::Matrix3d::Zero(), tangent_stiffness = Eigen::Matrix3d::Zero();
  double limit = 0;
};

struct ImplicitTerms {
  Eigen::VectorXd damping;    // per u: -dF_u/du_u of joint-space forces
  Eigen::VectorXd stiffness;  // per u: -dF_u/dq_u
  std::vector<PointCoupling> points;
  std::vector<SaturatingForce> saturating;

  void reset(int nu) {
    damping.setZero(nu);
    stiffness.setZero(nu);
    points.clear();
    saturating.clear();
  }
};

// A force element that linearizes itself for the implicit step.
class ImplicitForce {
 public:
  virtual ~ImplicitForce() = default;
  // `state` is realized through Dynamics, and this element's force was
  // evaluated at it (the stepper invalidates Dynamics before realizing).
  virtual void addImplicitTerms(const SimTK::State& state, ImplicitTerms& terms) const = 0;
};

}  // namespace scene_detail
}  // namespace manibench
