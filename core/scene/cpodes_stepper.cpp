#include "stepper.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace manibench {
namespace scene_detail {
namespace {

// Simulated time between refreshes of the discrete variables (friction
// anchors) inside one stepTo(); an environment's control tick (10 ms)
// refreshes them anyway. Refreshing at every internal step costs one more
// force evaluation per step (~15% of a cabinet step) for no measured gain.
constexpr double kDiscreteUpdateInterval = 0.01;  // s

class CPodesStepper final : public Stepper, private SimTK::CPodesSystem {
 public:
  CPodesStepper(const SimTK::System& system, const SimTK::State& initial,
                const CPodesOptions& options)
      : system_(system),
        options_(options),
        state_(initial),
        cpodes_(SimTK::CPodes::ExplicitODE, SimTK::CPodes::BDF, SimTK::CPodes::Newton) {
    system_.realize(state_, SimTK::Stage::Acceleration);
    ++accept_realizations_;
    const int ny = state_.getNY();
    // Quaternions (nq > nu) drift off unit length and constraints drift
    // off their manifold unless projected; other systems need no projection.
    project_ = state_.getNQ() != state_.getNU() || state_.getNYErr() > 0;
    absolute_tolerance_ = 0.1 * options_.accuracy;
    check(cpodes_.init(*this, state_.getTime(), SimTK::Vector(state_.getY()),
                       SimTK::Vector(state_.getYDot()), SimTK::CPodes::ScalarScalar,
                       options_.accuracy, &absolute_tolerance_),
          "init");
    check(cpodes_.setErrHandlerFn(), "setErrHandlerFn");
    check(cpodes_.lapackDense(ny), "lapackDense");
    check(cpodes_.setMaxOrd(options_.max_order), "setMaxOrd");
    check(cpodes_.setNonlinConvCoef(options_.newton_coefficient), "setNonlinConvCoef");
    check(cpodes_.setMaxNonlinIters(project_ ? 3 : options_.max_newton_iterations),
          "setMaxNonlinIters");
    if (project_) check(cpodes_.projDefine(), "projDefine");
    y_ = state_.getY();
    yp_.resize(ny);
  }

  const SimTK::State& getState() const override { return state_; }
  SimTK::State& updState() override { return state_; }

  bool stepTo(double t_end, int step_limit) override {
    const double t = state_.getTime();
    if (!(t_end > t)) return true;
    check(cpodes_.setStopTime(t_end), "setStopTime");
    double t_last = t;
    for (int k = 0; k < step_limit; ++k) {
      if (update_discrete_) {
        // The step just accepted computed the next values (friction
        // anchors); they hold from here on.
        state_.autoUpdateDiscreteVariables();
        update_discrete_ = false;
      }
      SimTK::Real t_reached = 0;
      const int result = cpodes_.step(t_end, &t_reached, y_, yp_, SimTK::CPodes::OneStepTstop);
      if (result == SimTK::CPodes::TooClose) {
        // t_end is within rounding of the current time: only the clock moves.
        state_.updY() = y_;
        state_.updTime() = t_end;
        system_.realize(state_, SimTK::Stage::Acceleration);
        return true;
      }
      if (result < 0) {
        // Leave the last accepted state for the diagnosis.
        state_.updY() = y_;
        state_.updTime() = t_last;
        std::ostringstream message;
        message << "CPODES failed at t=" << t_last << " s ("
                << (last_error_.empty() ? std::string("code ") + std::to_string(result)
                                        : last_error_)
                << ")";
        throw std::runtime_error(message.str());
      }
      // The evaluations of the step left trial values in state_. Where the
      // discrete variables are due (friction anchors: each call's end, at
      // least every kDiscreteUpdateInterval) put the accepted values back
      // and realize their forces, which compute the updates; accelerations
      // only where the caller gets control.
      t_last = t_reached;
      const bool done = result == SimTK::CPodes::TstopReturn || t_reached >= t_end;
      if (done || t_reached - last_discrete_update_ >= kDiscreteUpdateInterval) {
        state_.updY() = y_;
        state_.updTime() = t_reached;
        system_.realize(state_, SimTK::Stage::Dynamics);
        ++accept_realizations_;
        update_discrete_ = true;
        last_discrete_update_ = t_reached;
      }
      if (done) {
        system_.realize(state_, SimTK::Stage::Acceleration);
        return true;
      }
    }
    // Stopped at the step limit: the caller gets the last accepted state.
    state_.updY() = y_;
    state_.updTime() = t_last;
    system_.realize(state_, SimTK::Stage::Acceleration);
    return false;
  }

  IntegratorStatistics getStatistics() const override {
    auto get = [this](int (SimTK::CPodes::*query)(int*)) {
      int value = 0;
      (cpodes_.*query)(&value);
      return static_cast<std::int64_t>(value);
    };
    IntegratorStatistics s;
    s.steps = get(&SimTK::CPodes::getNumSteps);
    s.error_test_failures = get(&SimTK::CPodes::getNumErrTestFails);
    s.convergence_test_failures = get(&SimTK::CPodes::getNumNonlinSolvConvFails);
    s.attempts = s.steps + s.error_test_failures + s.convergence_test_failures;
    s.iterations = get(&SimTK::CPodes::getNumNonlinSolvIters);
    s.jacobians = get(&SimTK::CPodes::dlsGetNumJacEvals);
    s.realizations = get(&SimTK::CPodes::getNumFctEvals) +
                     get(&SimTK::CPodes::dlsGetNumFctEvals) + accept_realizations_;
    if (project_) s.projections = get(&SimTK::CPodes::getProjNumProj);
    return s;
  }

 private:
  // CPODES' callbacks evaluate in state_ itself: setting y and t
  // invalidates its cache, so nothing stale is read and nothing is copied.
  int explicitODE(SimTK::Real t, const SimTK::Vector& y, SimTK::Vector& ydot) const override {
    state_.updY() = y;
    state_.updTime() = t;
    try {
      system_.realize(state_, SimTK::Stage::Acceleration);
    } catch (const std::exception& e) {
      last_error_ = e.what();
      return SimTK::CPodes::RecoverableError;  // CPODES retries with a smaller step
    }
    ydot = state_.getYDot();
    return SimTK::CPodes::Success;
  }

  int project(SimTK::Real t, const SimTK::Vector& y, SimTK::Vector& correction, SimTK::Real,
              SimTK::Vector& error_estimate) const override {
    state_.updY() = y;
    state_.updTime() = t;
    const int nq = state_.getNQ(), nu = state_.getNU();
    SimTK::ProjectOptions options(options_.constraint_tolerance);
    options.setOption(SimTK::ProjectOptions::LocalOnly);
    options.setOption(SimTK::ProjectOptions::DontThrow);
    const bool with_error = error_estimate.size() > 0;
    SimTK::Vector q_error, u_error;
    if (with_error) {
      q_error = error_estimate(0, nq);
      u_error = error_estimate(nq, nu);
    }
    try {
      SimTK::ProjectResults results;
      system_.realize(state_, SimTK::Stage::Position);
      system_.projectQ(state_, q_error, options, results);
      if (results.getExitStatus() != SimTK::ProjectResults::Succeeded)
        return SimTK::CPodes::RecoverableError;
      results.clear();
      system_.realize(state_, SimTK::Stage::Velocity);
      system_.projectU(state_, u_error, options, results);
      if (results.getExitStatus() != SimTK::ProjectResults::Succeeded)
        return SimTK::CPodes::RecoverableError;
    } catch (const std::exception& e) {
      last_error_ = e.what();
      return SimTK::CPodes::RecoverableError;
    }
    if (with_error) {
      error_estimate(0, nq) = q_error;
      error_estimate(nq, nu) = u_error;
    }
    correction = state_.getY() - y;
    return SimTK::CPodes::Success;
  }

  void errorHandler(int code, const char* module, const char* function, char* message) const override {
    std::ostringstream text;
    text << (function != nullptr ? function : "CPODES") << ": "
         << (message != nullptr ? message : "") << " (" << (module != nullptr ? module : "")
         << " code " << code << ")";
    last_error_ = text.str();
  }

  void check(int result, const char* call) const {
    if (result < 0)
      throw std::runtime_error(std::string("CPODES ") + call + " failed (code " +
                               std::to_string(result) + ")" +
                               (last_error_.empty() ? "" : ": " + last_error_));
  }

  const SimTK::System& system_;
  CPodesOptions options_;
  mutable SimTK::State state_;
  mutable SimTK::CPodes cpodes_;
  SimTK::Real absolute_tolerance_ = 0;
  bool project_ = false;
  bool update_discrete_ = false;
  double last_discrete_update_ = -SimTK::Infinity;
  std::int64_t accept_realizations_ = 0;
  mutable std::string last_error_;
  SimTK::Vector y_, yp_;
};

}  // namespace

std::unique_ptr<Stepper> makeCPodesStepper(const SimTK::System& system,
                                           const SimTK::State& initial,
                                           const CPodesOptions& options) {
  return std::make_unique<CPodesStepper>(system, initial, options);
}

}  // namespace scene_detail
}  // namespace manibench
