#include "scene/joint_forces.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

namespace manibench {
namespace scene_detail {
namespace {

// Clamps to [-limit, limit] but lets NaN through, so that a NaN command
// makes the simulation diverge visibly instead of saturating quietly.
double clampEffort(double tau, double limit) {
  if (limit <= 0 || std::isnan(tau)) return tau;
  return std::max(-limit, std::min(limit, tau));
}

}  // namespace

JointForces::JointForces(const SimTK::SimbodyMatterSubsystem& matter,
                         const SimTK::Force::Gravity& gravity,
                         std::vector<JointSlot> slots, JointControls controls)
    : matter_(matter),
      gravity_(gravity),
      slots_(std::move(slots)),
      controls_(std::move(controls)) {
  assert(controls_.drives.size() == slots_.size());
  assert(controls_.driven.size() == slots_.size());
  assert(controls_.balanced.size() == slots_.size());
  assert(controls_.damping.size() == slots_.size());
  assert(controls_.friction.size() == slots_.size());
}

void JointForces::calcForce(const SimTK::State& state,
                            SimTK::Vector_<SimTK::SpatialVec>&,
                            SimTK::Vector_<SimTK::Vec3>&,
                            SimTK::Vector& mobility_forces) const {
  const JointControls& c = controls_;
  if (q_index_.empty()) {
    // Coordinate indices are fixed once the model stage is realized; reading
    // the state vectors directly avoids a subsystem lookup per joint.
    for (const JointSlot& slot : slots_) {
      const SimTK::MobilizedBody& mobod = matter_.getMobilizedBody(slot.mobod);
      q_index_.push_back(mobod.getFirstQIndex(state));
      u_index_.push_back(mobod.getFirstUIndex(state));
    }
  }
  // Balancing: the generalized force that would hold udot = 0 against
  // gravity and Coriolis/centrifugal terms (inverse dynamics, O(n)).
  if (std::find(c.balanced.begin(), c.balanced.end(), 1) != c.balanced.end())
    matter_.calcResidualForceIgnoringConstraints(state, no_mobility_forces_,
                                                 gravity_.getBodyForces(state), no_udot_,
                                                 residual_);
  const SimTK::Vector& q = state.getQ();
  const SimTK::Vector& u = state.getU();
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (!c.driven[i] && !c.balanced[i] && c.damping[i] == 0 && c.friction[i] == 0)
      continue;
    const double qi = q[q_index_[i]];
    const double ui = u[u_index_[i]];
    double tau = 0;
    if (c.driven[i]) {
      const DriveCommand& d = c.drives[i];
      tau = clampEffort(d.stiffness * (d.position_target - qi) +
                            d.damping * (d.velocity_target - ui) + d.force,
                        slots_[i].effort_limit);
    }
    tau -= c.damping[i] * ui;
    if (c.friction[i] != 0) tau -= c.friction[i] * std::tanh(ui / kFrictionSpeed);
    if (c.balanced[i]) tau += residual_[u_index_[i]];
    mobility_forces[u_index_[i]] += tau;
  }
}

}  // namespace scene_detail
}  // namespace manibench
