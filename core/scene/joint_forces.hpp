// Every per-joint generalized force of a scene in one Force::Custom: drives,
// passive damping, Coulomb friction, limit stops and passive-force
// balancing. One element per scene keeps the per-evaluation cost to a single
// loop and a single inverse-dynamics pass, however many joints are
// balanced, and gives the implicit step every joint's derivatives in one
// place.
#pragma once

#include <limits>
#include <vector>

#include "Simbody.h"
#include "manibench/scene.hpp"
#include "implicit_terms.hpp"

namespace manibench {
namespace scene_detail {

// Coulomb friction is tanh(qdot / kFrictionSpeed) * friction (implicit_euler
// steps it as the linear law of the same slope, saturating at +-friction):
// a joint loaded below its friction creeps at well under this speed (rad/s
// or m/s).
// Smaller values stiffen the ODE (slope friction / kFrictionSpeed); 1e-2
// keeps it within what the drive dampings already demand of CPodes.
constexpr double kFrictionSpeed = 1e-2;

// Joint limit stops, Hunt-Crossley-like (as Simbody's MobilityLinearStop):
// beyond a limit by x, f = -k x (1 + d qdot) towards the range, never
// pulling. 1e5 keeps a 1 kg slider within 0.1 mm of its limit under
// gravity, a 10 N m load within 0.1 mrad. d = 10 makes hitting a stop
// practically inelastic; with d = 1 a slider resting on its stop kept
// chattering at CPodes' default accuracy.
constexpr double kLimitStiffness = 1e5;     // N/m or N m/rad
constexpr double kLimitDissipation = 10.0;  // s/m or s/rad

// A movable joint as the force element sees it. Joints are numbered across
// the scene: articulation a's joint j is slot joint_offset[a] + j.
struct JointSlot {
  SimTK::MobilizedBodyIndex mobod;
  double effort_limit = 0;  // 0: unlimited
  double lower = -std::numeric_limits<double>::infinity();  // limit stops
  double upper = std::numeric_limits<double>::infinity();
};

// The values a controller or task changes during an episode. They live
// outside the SimTK::State (drives change every control tick and must not
// restart the integrator) and travel with SceneState instead.
struct JointControls {
  std::vector<DriveCommand> drives;
  std::vector<char> driven;    // joint has a drive command
  std::vector<char> balanced;  // gravity/Coriolis cancelled on this joint
  std::vector<double> damping;
  std::vector<double> friction;
};

class JointForces : public SimTK::Force::Custom::Implementation, public ImplicitForce {
 public:
  JointForces(const SimTK::SimbodyMatterSubsystem& matter,
              const SimTK::Force::Gravity& gravity,
              std::vector<JointSlot> slots, JointControls controls);

  const JointControls& getControls() const { return controls_; }
  // Callers must invalidate the state's Dynamics stage after a change.
  JointControls& updControls() { return controls_; }

  void calcForce(const SimTK::State& state,
                 SimTK::Vector_<SimTK::SpatialVec>& body_forces,
                 SimTK::Vector_<SimTK::Vec3>& particle_forces,
                 SimTK::Vector& mobility_forces) const override;
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override {
    return 0;
  }
  // Drives (saturating ones as SaturatingForce), damping, friction (as
  // SaturatingForce) and stops, each on its own joint: diagonal entries only.
  void addImplicitTerms(const SimTK::State& state, ImplicitTerms& terms) const override;

 private:
  void ensureIndices(const SimTK::State& state) const;

  const SimTK::SimbodyMatterSubsystem& matter_;
  SimTK::Force::Gravity gravity_;  // a handle to the scene's gravity element
  std::vector<JointSlot> slots_;
  JointControls controls_;
  // Filled on the first evaluation (see calcForce); scratch after that.
  mutable std::vector<SimTK::QIndex> q_index_;
  mutable std::vector<SimTK::UIndex> u_index_;
  mutable SimTK::Vector residual_, no_mobility_forces_, no_udot_;
};

}  // namespace scene_detail
}  // namespace manibench
