// Simbody's own error-controlled RK-Merson and fixed-step semi-explicit
// Euler integrators behind the Stepper interface.
#include <stdexcept>

#include "stepper.hpp"

namespace manibench {
namespace scene_detail {
namespace {

class SimbodyStepper final : public Stepper {
 public:
  SimbodyStepper(const SimTK::System& system, const SimTK::State& initial,
                 const PhysicsSettings& settings, double constraint_tolerance) {
    // SimTK::Integrator's destructor is not virtual: own the concrete type.
    if (settings.integrator == Integrator::RkMerson) {
      rk_merson_ = std::make_unique<SimTK::RungeKuttaMersonIntegrator>(system);
      integrator_ = rk_merson_.get();
      integrator_->setAccuracy(settings.accuracy);
    } else {
      euler_ = std::make_unique<SimTK::SemiExplicitEulerIntegrator>(system, settings.fixed_step);
      integrator_ = euler_.get();
    }
    if (constraint_tolerance > 0) integrator_->setConstraintTolerance(constraint_tolerance);
    // Land exactly on each control tick so that commands switch there.
    integrator_->setAllowInterpolation(false);
    integrator_->initialize(initial);
  }

  const SimTK::State& getState() const override { return integrator_->getState(); }
  SimTK::State& updState() override { return integrator_->updAdvancedState(); }

  bool stepTo(double t_end, int step_limit) override {
    integrator_->setInternalStepLimit(step_limit);
    while (integrator_->getTime() < t_end) {
      const SimTK::Integrator::SuccessfulStepStatus status = integrator_->stepTo(t_end);
      if (status == SimTK::Integrator::EndOfSimulation)
        throw std::runtime_error("the integrator ended the simulation");
      if (status == SimTK::Integrator::ReachedStepLimit) return integrator_->getTime() >= t_end;
    }
    return true;
  }

  IntegratorStatistics getStatistics() const override {
    IntegratorStatistics s;
    s.steps = integrator_->getNumStepsTaken();
    s.attempts = integrator_->getNumStepsAttempted();
    s.realizations = integrator_->getNumRealizations();
    s.iterations = integrator_->getNumIterations();
    s.projections = integrator_->getNumProjections();
    s.error_test_failures = integrator_->getNumErrorTestFailures();
    s.convergence_test_failures = integrator_->getNumConvergenceTestFailures();
    return s;
  }

 private:
  std::unique_ptr<SimTK::RungeKuttaMersonIntegrator> rk_merson_;
  std::unique_ptr<SimTK::SemiExplicitEulerIntegrator> euler_;
  SimTK::Integrator* integrator_ = nullptr;
};

}  // namespace

std::unique_ptr<Stepper> makeSimbodyStepper(const SimTK::System& system,
                                            const SimTK::State& initial,
                                            const PhysicsSettings& settings,
                                            double constraint_tolerance) {
  return std::make_unique<SimbodyStepper>(system, initial, settings, constraint_tolerance);
}

}  // namespace scene_detail
}  // namespace manibench
