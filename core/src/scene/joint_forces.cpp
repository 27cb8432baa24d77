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
  // Balancing: the generalized force that would hold udot = 0 against
  // gravity and Coriolis/centrifugal terms (inverse dynamics, O(n)).
  SimTK::Vector residual;
  if (std::find(c.balanced.begin(), c.balanced.end(), 1) != c.balanced.end())
    matter_.calcResidualForceIgnoringConstraints(
        state, SimTK::Vector(), gravity_.getBodyForces(state), SimTK::Vector(),
        residual);

  for (std::size_t i = 0; i < slots_.size(); ++i) {
    if (!c.driven[i] && !c.balanced[i] && c.damping[i] == 0 && c.friction[i] == 0)
      continue;
    const SimTK::MobilizedBody& mobod = matter_.getMobilizedBody(slots_[i].mobod);
    const double q = mobod.getOneQ(state, 0);
    const double u = mobod.getOneU(state, 0);
    double tau = 0;
    if (c.driven[i]) {
      const DriveCommand& d = c.drives[i];
      tau = clampEffort(d.stiffness * (d.position_target - q) +
                            d.damping * (d.velocity_target - u) + d.force,
                        slots_[i].effort_limit);
    }
    tau -= c.damping[i] * u;
    if (c.friction[i] != 0) tau -= c.friction[i] * std::tanh(u / kFrictionSpeed);
    if (c.balanced[i]) tau += residual[mobod.getFirstUIndex(state)];
    mobod.applyOneMobilityForce(state, 0, tau, mobility_forces);
  }
}

}  // namespace scene_detail
}  // namespace manibench
