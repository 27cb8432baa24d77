#include "joint_forces.hpp"

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

// The drive law before its effort limit.
double calcDriveLaw(const DriveCommand& d, double q, double u) {
  return d.stiffness * (d.position_target - q) + d.damping * (d.velocity_target - u) + d.force;
}

// A limit stop's force, and its stiffness (-df/dq) and damping (-df/du)
// where it pushes. Beyond the upper limit by x > 0: f = min(0, -k x (1 + d
// u)); below the lower one (x < 0): f = max(0, -k x (1 - d u)).
struct StopForce {
  double force = 0, stiffness = 0, damping = 0;
};
StopForce calcStopForce(const JointSlot& slot, double q, double u) {
  StopForce stop;
  if (q > slot.upper) {
    const double x = q - slot.upper, factor = 1 + kLimitDissipation * u;
    if (factor > 0) {
      stop.force = -kLimitStiffness * x * factor;
      stop.stiffness = kLimitStiffness * factor;
      stop.damping = kLimitStiffness * x * kLimitDissipation;
    }
  } else if (q < slot.lower) {
    const double x = q - slot.lower, factor = 1 - kLimitDissipation * u;
    if (factor > 0) {
      stop.force = -kLimitStiffness * x * factor;
      stop.stiffness = kLimitStiffness * factor;
      stop.damping = -kLimitStiffness * x * kLimitDissipation;
    }
  }
  return stop;
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

void JointForces::ensureIndices(const SimTK::State& state) const {
  if (!q_index_.empty() || slots_.empty()) return;
  // Coordinate indices are fixed once the model stage is realized; reading
  // the state vectors directly avoids a subsystem lookup per joint.
  for (const JointSlot& slot : slots_) {
    const SimTK::MobilizedBody& mobod = matter_.getMobilizedBody(slot.mobod);
    q_index_.push_back(mobod.getFirstQIndex(state));
    u_index_.push_back(mobod.getFirstUIndex(state));
  }
}

void JointForces::calcForce(const SimTK::State& state,
                            SimTK::Vector_<SimTK::SpatialVec>&,
                            SimTK::Vector_<SimTK::Vec3>&,
                            SimTK::Vector& mobility_forces) const {
  const JointControls& c = controls_;
  ensureIndices(state);
  // Balancing: the generalized force that would hold udot = 0 against
  // gravity and Coriolis/centrifugal terms (inverse dynamics, O(n)).
  if (std::find(c.balanced.begin(), c.balanced.end(), 1) != c.balanced.end())
    matter_.calcResidualForceIgnoringConstraints(state, no_mobility_forces_,
                                                 gravity_.getBodyForces(state), no_udot_,
                                                 residual_);
  const SimTK::Vector& q = state.getQ();
  const SimTK::Vector& u = state.getU();
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const JointSlot& slot = slots_[i];
    const double qi = q[q_index_[i]];
    const double ui = u[u_index_[i]];
    double tau = calcStopForce(slot, qi, ui).force;
    if (c.driven[i]) tau += clampEffort(calcDriveLaw(c.drives[i], qi, ui), slot.effort_limit);
    tau -= c.damping[i] * ui;
    if (c.friction[i] != 0) tau -= c.friction[i] * std::tanh(ui / kFrictionSpeed);
    if (c.balanced[i]) tau += residual_[u_index_[i]];
    mobility_forces[u_index_[i]] += tau;
  }
}

void JointForces::addImplicitTerms(const SimTK::State& state, ImplicitTerms& terms) const {
  const JointControls& c = controls_;
  ensureIndices(state);
  const SimTK::Vector& q = state.getQ();
  const SimTK::Vector& u = state.getU();
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const JointSlot& slot = slots_[i];
    const int k = u_index_[i];
    const double qi = q[q_index_[i]];
    const double ui = u[k];
    const StopForce stop = calcStopForce(slot, qi, ui);
    double damping = stop.damping + c.damping[i];
    double stiffness = stop.stiffness;
    if (c.friction[i] > 0) {
      // Coulomb friction saturates at +-friction, as a drive at its effort
      // limit: linearized at the step's start (as the slope of tanh), a
      // sliding joint's friction would be explicit, and on a light link
      // one step's impulse h f / I can exceed its speed: it then flips the
      // speed's sign every step instead of stopping (a caster's swivel,
      // 1e-5 kg m^2 under 0.05 N m: +-1.4 rad/s for ever). As a saturating
      // force the step decides at its end whether friction slides (+-f)
      // or holds (the stiff linear law of slope f / kFrictionSpeed).
      SaturatingForce friction;
      friction.u = k;
      friction.applied = -c.friction[i] * std::tanh(ui / kFrictionSpeed);
      friction.unclamped = -c.friction[i] / kFrictionSpeed * ui;
      friction.damping = c.friction[i] / kFrictionSpeed;
      friction.limit = c.friction[i];
      terms.saturating.push_back(friction);
    }
    if (c.driven[i]) {
      const DriveCommand& d = c.drives[i];
      if (slot.effort_limit > 0) {
        SaturatingForce drive;
        drive.u = k;
        drive.unclamped = calcDriveLaw(d, qi, ui);
        drive.applied = clampEffort(drive.unclamped, slot.effort_limit);
        drive.damping = d.damping;
        drive.stiffness = d.stiffness;
        drive.limit = slot.effort_limit;
        if (std::isfinite(drive.unclamped)) terms.saturating.push_back(drive);
      } else {
        damping += d.damping;
        stiffness += d.stiffness;
      }
    }
    terms.damping[k] += damping;
    terms.stiffness[k] += stiffness;
  }
}

}  // namespace scene_detail
}  // namespace manibench
