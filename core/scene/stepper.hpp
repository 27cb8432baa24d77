// Time stepping of a scene's Simbody system, behind one small interface.
// Four implementations, chosen by PhysicsSettings::integrator:
//  - ImplicitEulerStepper (implicit_euler_stepper.cpp): fixed step,
//    linearly implicit in the stiff forces (implicit_terms.hpp);
//  - CPodesStepper (cpodes_stepper.cpp): SUNDIALS CPODES (BDF, Newton,
//    dense difference-quotient Jacobian) driven through SimTK::CPodes;
//  - Simbody's own RK-Merson and semi-explicit Euler (simbody_stepper.cpp).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "Simbody.h"
#include "manibench/scene.hpp"

namespace manibench {
namespace scene_detail {

class Stepper {
 public:
  virtual ~Stepper() = default;
  // The current state. Callers realize the stages they read.
  virtual const SimTK::State& getState() const = 0;
  // For cache invalidation when forces defined outside the state change
  // (drive commands); the stepper continues without a restart.
  virtual SimTK::State& updState() = 0;
  // Advances to exactly `t_end` (no interpolation), taking at most
  // `step_limit` internal steps; returns false if it stopped at the limit
  // (call again to continue). Throws std::runtime_error when the method
  // fails (step size too small, repeated convergence failures).
  virtual bool stepTo(double t_end, int step_limit) = 0;
  // Counters since construction.
  virtual IntegratorStatistics getStatistics() const = 0;
};

// Simbody's RK-Merson or semi-explicit Euler integrator; a constraint
// tolerance of 0 keeps Simbody's default.
std::unique_ptr<Stepper> makeSimbodyStepper(const SimTK::System& system,
                                            const SimTK::State& initial,
                                            const PhysicsSettings& settings,
                                            double constraint_tolerance);

struct CPodesOptions {
  double accuracy = 1e-2;       // relative tolerance; absolute is a tenth of it
  // BDF above order 2 is not A-stable: lightly damped stiff modes (a body
  // held by its friction springs) then grow instead of decaying.
  int max_order = 2;
  // Newton convergence test, as a fraction of the error tolerance. CPODES'
  // default 0.1 is 20% faster on the cabinet scenes but lets a 1 g cube
  // bounce on the floor and slows a Panda joint's measured step response;
  // 0.01 (Simbody's choice) passes both.
  double newton_coefficient = 0.01;
  // Newton iterations before a step counts as not converging, for systems
  // without free bodies or constraints (the others keep CPODES' default
  // of 3). Each such failure costs a new difference-quotient Jacobian (one
  // evaluation per state variable). Measured: 5 takes 18% fewer
  // evaluations for the cabinet expert and 8% under random actions, but
  // the heap of 12 free bodies in tests/contact_scenes.hpp runs 2.5x
  // slower with 4 or 5 than with 3.
  int max_newton_iterations = 5;
  double constraint_tolerance = 1e-3;
};

// Why not SimTK::CPodesIntegrator: measured on the cabinet scenes it
//  - copies the whole SimTK::State (every cache entry) for each evaluation
//    of the equations of motion, dozens per control step;
//  - projects onto the constraint manifold after every step even when the
//    system has no constraints and no quaternions (a position
//    realization per step for nothing).
// CPodesStepper evaluates in one persistent State and projects only when
// the system has constraints or quaternions. It refreshes auto-update
// discrete variables (the friction anchors) at the end of each stepTo()
// and at least every 10 ms of simulated time within one.
std::unique_ptr<Stepper> makeCPodesStepper(const SimTK::System& system,
                                           const SimTK::State& initial,
                                           const CPodesOptions& options);

class ImplicitForce;

struct ImplicitEulerOptions {
  double step = 2e-3;  // s; each stepTo() lands on its end in equal steps no longer
  // Mimic couplings (holonomic constraints) are projected to this after
  // each step; 0 keeps Simbody's default.
  double constraint_tolerance = 0;
};

// `forces`: every force element whose stiffness the step treats
// implicitly; the rest of the system's forces are explicit. They must
// outlive the stepper.
std::unique_ptr<Stepper> makeImplicitEulerStepper(const SimTK::MultibodySystem& system,
                                                  const SimTK::State& initial,
                                                  std::vector<const ImplicitForce*> forces,
                                                  const ImplicitEulerOptions& options);

}  // namespace scene_detail
}  // namespace manibench
