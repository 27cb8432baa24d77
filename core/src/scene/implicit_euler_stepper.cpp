// The fixed-step, linearly implicit Euler stepper (see implicit_terms.hpp
// for the equations).
//
// Why: CPODES' cost follows how smooth the motion is. Under a learning
// agent's jerky commands (a new random velocity target each 10 ms on
// drives damped at 100-1000) its BDF history is useless after every tick,
// Newton stalls and each stall costs a difference-quotient Jacobian of one
// evaluation per state variable: 835 evaluations per cabinet env step
// against 72 under the smooth scripted expert. Here every step costs one
// evaluation of the equations of motion, one mass matrix and one small
// dense factorization, whatever the actions. Stability comes from the
// implicit treatment of everything stiff (drives, joint damping, friction
// and stops, contact springs and dampers), as PhysX's drives and MuJoCo's
// implicit integrators do; accuracy is first order, at 2 ms by default
// (ManiSkill's 500 Hz), measured against CPODES in docs/performance.md.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "scene/implicit_terms.hpp"
#include "scene/stepper.hpp"

namespace manibench {
namespace scene_detail {
namespace {

// Saturating forces (drives with an effort limit) whose side of the limit
// keeps changing get this many solves per step; after that the last one
// stands (each solve is a factorization of the nu x nu matrix).
constexpr int kMaxSaturationSolves = 8;


class ImplicitEulerStepper final : public Stepper {
 public:
  ImplicitEulerStepper(const SimTK::MultibodySystem& system, const SimTK::State& initial,
                       std::vector<const ImplicitForce*> forces,
                       const ImplicitEulerOptions& options)
      : system_(system),
        matter_(system.getMatterSubsystem()),
        forces_(std::move(forces)),
        options_(options),
        state_(initial) {
    system_.realize(state_, SimTK::Stage::Model);
    // Quaternions drift off unit length, constraints off their manifold.
    quaternions_ = state_.getNQ() != state_.getNU();
    constrained_ = state_.getNYErr() > 0;
  }

  const SimTK::State& getState() const override { return state_; }
  SimTK::State& updState() override { return state_; }

  bool stepTo(double t_end, int step_limit) override {
    for (int k = 0; k < step_limit; ++k) {
      const double remaining = t_end - state_.getTime();
      // Equal steps no longer than options_.step that land on t_end; the
      // slack keeps rounding from adding a sliver of a step.
      if (!(remaining > 1e-12 * std::max(1.0, std::abs(t_end)))) {
        state_.updTime() = t_end;
        return true;
      }
      const double steps = std::ceil(remaining / options_.step - 1e-9);
      takeStep(steps <= 1 ? remaining : remaining / steps);
      if (steps <= 1) {
        state_.updTime() = t_end;  // exactly, not t + remaining rounded
        return true;
      }
    }
    return false;
  }

  IntegratorStatistics getStatistics() const override { return statistics_; }

 private:
  void takeStep(double h) {
    const int nu = state_.getNU();
    // The force elements keep their linearization from their last
    // evaluation: make sure that was at this state.
    state_.invalidateAllCacheAtOrAbove(SimTK::Stage::Dynamics);
    system_.realize(state_, SimTK::Stage::Acceleration);
    ++statistics_.realizations;

    matter_.calcM(state_, simbody_mass_);
    mass_.resize(nu, nu);
    for (int col = 0; col < nu; ++col)
      for (int row = 0; row < nu; ++row) mass_(row, col) = simbody_mass_(row, col);
    terms_.reset(nu);
    for (const ImplicitForce* force : forces_) force->addImplicitTerms(state_, terms_);

    // F = M a with a = udot, the explicit acceleration (Simbody's O(n)
    // forward dynamics). Solved directly for du rather than for its
    // difference from the explicit step h a: at absurd stiffness (h^2 k /
    // m ~ 1e25) that difference cancels two huge numbers.
    u_ = state_.getU();
    udot_ = state_.getUDot();
    Eigen::Map<const Eigen::VectorXd> u(&u_[0], nu), a(&udot_[0], nu);
    base_matrix_ = mass_;
    base_matrix_ += h * terms_.damping + (h * h) * terms_.stiffness;
    base_rhs_.noalias() = h * (mass_ * a);
    base_rhs_.noalias() -= (h * h) * (terms_.stiffness * u);
    solveWithSaturation(h, u);

    // The friction anchors (auto-update discrete variables) this state's
    // evaluation computed hold from the next step on. Taken before q and u
    // change, which would invalidate them.
    state_.autoUpdateDiscreteVariables();
    for (int i = 0; i < nu; ++i) u_[i] += du_[i];
    state_.updU() = u_;
    // Position stays realized when only u changes: q+ = q + h N(q) u+.
    matter_.multiplyByN(state_, false, u_, qdot_);
    state_.updQ() += h * qdot_;
    state_.updTime() += h;
    if (quaternions_) {
      system_.realize(state_, SimTK::Stage::Time);  // as normalizeQuaternions needs
      matter_.normalizeQuaternions(state_);
    }
    if (constrained_) project();
    ++statistics_.steps;
    ++statistics_.attempts;
  }

  // Solves (base + saturating terms) du = rhs into du_. A saturating force
  // acts linearly in the solve if its law stays within the limit at the
  // step's end, else as its limit; the sides are guessed from the start and
  // corrected until consistent (an active-set iteration, at most
  // kMaxSaturationSolves factorizations).
  void solveWithSaturation(double h, const Eigen::Map<const Eigen::VectorXd>& u) {
    std::vector<SaturatingForce>& saturating = terms_.saturating;
    side_.assign(saturating.size(), 0);
    for (std::size_t i = 0; i < saturating.size(); ++i) {
      const SaturatingForce& f = saturating[i];
      if (f.unclamped > f.limit) side_[i] = 1;
      if (f.unclamped < -f.limit) side_[i] = -1;
    }
    for (int solve = 1;; ++solve) {
      matrix_ = base_matrix_;
      rhs_ = base_rhs_;
      for (std::size_t i = 0; i < saturating.size(); ++i) {
        const SaturatingForce& f = saturating[i];
        // M a holds what the force element applied; replace it with the
        // side's force.
        if (side_[i] == 0) {
          matrix_(f.u, f.u) += h * f.damping + h * h * f.stiffness;
          rhs_[f.u] += h * (f.unclamped - f.applied) - h * h * f.stiffness * u[f.u];
        } else {
          rhs_[f.u] += h * (side_[i] * f.limit - f.applied);
        }
      }
      solve_.compute(matrix_);
      if (solve_.info() == Eigen::Success) {
        du_ = solve_.solve(rhs_);
      } else {
        // Not positive definite (a negative damping or stiffness from a
        // plugin's drive): LU still gives the step.
        du_ = matrix_.partialPivLu().solve(rhs_);
      }
      ++statistics_.iterations;
      if (saturating.empty() || solve == kMaxSaturationSolves) return;
      bool consistent = true;
      for (std::size_t i = 0; i < saturating.size(); ++i) {
        const SaturatingForce& f = saturating[i];
        const double at_end =
            f.unclamped - f.damping * du_[f.u] - f.stiffness * h * (u[f.u] + du_[f.u]);
        // A linear force beyond its limit saturates on that side; a
        // saturated one whose law is back within the limit (or beyond the
        // other one: it overshot) acts linearly again, never flipping
        // straight to the other side.
        int side = side_[i];
        if (side == 0)
          side = at_end > f.limit ? 1 : at_end < -f.limit ? -1 : 0;
        else if (side * at_end < f.limit)
          side = 0;
        if (side != side_[i]) {
          side_[i] = side;
          consistent = false;
        }
      }
      if (consistent) return;
    }
  }

  // Mimic couplings: back onto the constraint manifold, positions then
  // speeds (as Simbody's own integrators do after each step).
  void project() {
    const double tolerance =
        options_.constraint_tolerance > 0 ? options_.constraint_tolerance : -1;  // -1: Simbody's
    system_.realize(state_, SimTK::Stage::Position);
    system_.projectQ(state_, tolerance);
    system_.realize(state_, SimTK::Stage::Velocity);
    system_.projectU(state_, tolerance);
    ++statistics_.projections;
  }

  const SimTK::MultibodySystem& system_;
  const SimTK::SimbodyMatterSubsystem& matter_;
  std::vector<const ImplicitForce*> forces_;
  ImplicitEulerOptions options_;
  SimTK::State state_;
  bool quaternions_ = false, constrained_ = false;
  IntegratorStatistics statistics_;

  // Scratch, kept between steps.
  SimTK::Vector u_, udot_, qdot_;
  SimTK::Matrix simbody_mass_;
  Eigen::MatrixXd mass_;
  ImplicitTerms terms_;
  Eigen::MatrixXd base_matrix_, matrix_;
  Eigen::VectorXd base_rhs_, rhs_, du_;
  std::vector<int> side_;
  Eigen::LLT<Eigen::MatrixXd> solve_;
};

}  // namespace

std::unique_ptr<Stepper> makeImplicitEulerStepper(const SimTK::MultibodySystem& system,
                                                  const SimTK::State& initial,
                                                  std::vector<const ImplicitForce*> forces,
                                                  const ImplicitEulerOptions& options) {
  return std::make_unique<ImplicitEulerStepper>(system, initial, std::move(forces), options);
}

}  // namespace scene_detail
}  // namespace manibench
