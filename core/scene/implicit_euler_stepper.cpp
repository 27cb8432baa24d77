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
#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "implicit_terms.hpp"
#include "stepper.hpp"
#include "tree_structure.hpp"

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
        state_(initial),
        trees_(matter_, realizeModel(system, state_)) {
    // Quaternions drift off unit length, constraints off their manifold.
    quaternions_ = state_.getNQ() != state_.getNU();
    constrained_ = matter_.getNumConstraints() > 0;  // quaternions count in NYErr too
    island_of_tree_.resize(trees_.getNumTrees());
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
  // Trees joined by contact points, solved together.
  struct Island {
    std::vector<int> trees, offsets;  // tree-local u's of trees[i] start at offsets[i]
    int size = 0;
    std::vector<int> points, saturating;  // indices into terms_
  };

  static const SimTK::State& realizeModel(const SimTK::System& system, SimTK::State& state) {
    system.realize(state, SimTK::Stage::Model);
    return state;
  }

  void takeStep(double h) {
    const int nu = state_.getNU();
    // The force elements keep their linearization from their last
    // evaluation: make sure that was at this state.
    state_.invalidateAllCacheAtOrAbove(SimTK::Stage::Dynamics);
    calcNetForce();
    ++statistics_.realizations;
    trees_.update(state_);
    terms_.reset(nu);
    for (const ImplicitForce* force : forces_) force->addImplicitTerms(state_, terms_);

    u_ = state_.getU();
    findIslands();
    du_.resize(nu);
    for (const Island& island : islands_) solveIsland(island, h);

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

  // force_ = F = M udot, the net generalized force at the step's start
  // (applied minus Coriolis and gyroscopic). Without constraints, by
  // inverse dynamics at udot = 0 (one O(n) pass; Simbody's forward dynamics
  // would first build the articulated-body inertias, a 6 x 6 LAPACK inverse
  // per free body); with them, from the constrained accelerations.
  void calcNetForce() {
    if (constrained_) {
      system_.realize(state_, SimTK::Stage::Acceleration);
      matter_.multiplyByM(state_, state_.getUDot(), force_);
      return;
    }
    system_.realize(state_, SimTK::Stage::Dynamics);
    matter_.calcResidualForceIgnoringConstraints(
        state_, system_.getMobilityForces(state_, SimTK::Stage::Dynamics),
        system_.getRigidBodyForces(state_, SimTK::Stage::Dynamics), no_udot_, force_);
    force_ *= -1;
  }

  int findRoot(int tree) {
    while (tree_root_[tree] != tree) tree = tree_root_[tree] = tree_root_[tree_root_[tree]];
    return tree;
  }

  // Groups the trees into islands: union-find over the contact points
  // between two moving bodies.
  void findIslands() {
    const int trees = trees_.getNumTrees();
    tree_root_.resize(trees);
    for (int t = 0; t < trees; ++t) tree_root_[t] = t;
    for (const PointCoupling& p : terms_.points) {
      const int a = trees_.getTree(p.body_a), b = trees_.getTree(p.body_b);
      if (a >= 0 && b >= 0) tree_root_[findRoot(a)] = findRoot(b);
    }
    island_count_ = 0;
    std::fill(island_of_tree_.begin(), island_of_tree_.end(), -1);
    for (int t = 0; t < trees; ++t) {
      const int root = findRoot(t);
      if (island_of_tree_[root] < 0) {
        island_of_tree_[root] = island_count_++;
        if (static_cast<int>(islands_.size()) < island_count_) islands_.emplace_back();
        Island& island = islands_[island_of_tree_[root]];
        island.trees.clear();
        island.offsets.clear();
        island.points.clear();
        island.saturating.clear();
        island.size = 0;
      }
      island_of_tree_[t] = island_of_tree_[root];
      Island& island = islands_[island_of_tree_[t]];
      island.trees.push_back(t);
      island.offsets.push_back(island.size);
      island.size += static_cast<int>(trees_.getTreeU(t).size());
    }
    islands_.resize(island_count_);
    for (int i = 0; i < static_cast<int>(terms_.points.size()); ++i) {
      const PointCoupling& p = terms_.points[i];
      const int tree = trees_.getTree(p.body_b) >= 0 ? trees_.getTree(p.body_b)
                                                      : trees_.getTree(p.body_a);
      if (tree >= 0) islands_[island_of_tree_[tree]].points.push_back(i);
    }
    for (int i = 0; i < static_cast<int>(terms_.saturating.size()); ++i)
      islands_[island_of_tree_[trees_.getTreeOfU(terms_.saturating[i].u)]].saturating.push_back(i);
  }

  // The island-local index of global speed u (the island holds u's tree).
  int getLocalIndex(const Island& island, int u) const {
    const int tree = trees_.getTreeOfU(u);
    for (std::size_t i = 0; i < island.trees.size(); ++i)
      if (island.trees[i] == tree) return island.offsets[i] + trees_.getLocalIndexOfU(u);
    assert(false && "u belongs to the island");
    return -1;
  }

  // Assembles (M + h D + h^2 K) du = h (M a - h K u) over the island and
  // solves it into du_.
  void solveIsland(const Island& island, double h) {
    const int n = island.size;
    base_matrix_.setZero(n, n);
    local_u_.resize(n);
    base_rhs_.resize(n);
    for (std::size_t i = 0; i < island.trees.size(); ++i) {
      const std::vector<int>& tree_u = trees_.getTreeU(island.trees[i]);
      const int offset = island.offsets[i], size = static_cast<int>(tree_u.size());
      trees_.calcMassBlock(island.trees[i], base_matrix_.block(offset, offset, size, size));
      for (int k = 0; k < size; ++k) {
        local_u_[offset + k] = u_[tree_u[k]];
        base_rhs_[offset + k] = h * force_[tree_u[k]];
      }
    }
    // Solved for du directly, not for its difference from the explicit
    // step h M^-1 F: at absurd stiffness (h^2 k / m ~ 1e25) that difference
    // cancels huge numbers.
    for (std::size_t i = 0; i < island.trees.size(); ++i) {
      const std::vector<int>& tree_u = trees_.getTreeU(island.trees[i]);
      for (std::size_t k = 0; k < tree_u.size(); ++k) {
        const int local = island.offsets[i] + static_cast<int>(k), u = tree_u[k];
        base_matrix_(local, local) += h * terms_.damping[u] + h * h * terms_.stiffness[u];
        base_rhs_[local] -= h * h * terms_.stiffness[u] * local_u_[local];
      }
    }
    sliding_count_ = 0;
    for (int index : island.points) {
      const PointCoupling& p = terms_.points[index];
      point_jacobian_.setZero(3, n);
      addPointJacobian(island, p.body_b, p.point, 1.0);
      addPointJacobian(island, p.body_a, p.point, -1.0);
      weighted_.noalias() = (h * p.damping + h * h * p.stiffness) * point_jacobian_;
      base_matrix_.noalias() += point_jacobian_.transpose() * weighted_;
      const Eigen::Vector3d stretch_rate = p.stiffness * (point_jacobian_ * local_u_);
      base_rhs_.noalias() -= (h * h) * (point_jacobian_.transpose() * stretch_rate);
      if (p.sliding) {  // kept for the check at the step's end
        if (sliding_.size() <= sliding_count_) sliding_.emplace_back();
        sliding_[sliding_count_].index = index;
        sliding_[sliding_count_].jacobian = point_jacobian_;
        ++sliding_count_;
      }
    }
    solveWithSaturation(island, h);
    for (std::size_t i = 0; i < island.trees.size(); ++i) {
      const std::vector<int>& tree_u = trees_.getTreeU(island.trees[i]);
      for (std::size_t k = 0; k < tree_u.size(); ++k)
        du_[tree_u[k]] = local_du_[island.offsets[i] + static_cast<int>(k)];
    }
  }

  void addPointJacobian(const Island& island, SimTK::MobilizedBodyIndex body,
                        const Eigen::Vector3d& point, double sign) {
    const int tree = trees_.getTree(body);
    if (tree < 0) return;
    for (std::size_t i = 0; i < island.trees.size(); ++i)
      if (island.trees[i] == tree) {
        trees_.addPointJacobian(
            body, point, sign,
            point_jacobian_.middleCols(island.offsets[i],
                                       static_cast<Eigen::Index>(trees_.getTreeU(tree).size())));
        return;
      }
  }

  // Solves (base + saturating terms) du = rhs into local_du_. A saturating
  // force acts linearly in the solve if its law stays within the limit at
  // the step's end, else as its limit; the sides are guessed from the start
  // and corrected until consistent (an active-set iteration, at most
  // kMaxSaturationSolves factorizations). Sliding contact points likewise:
  // a point slides (its capped force) unless its stick law is within mu fn
  // at the step's end; it then sticks (the stick law, implicit).
  void solveWithSaturation(const Island& island, double h) {
    const std::size_t count = island.saturating.size();
    side_.assign(count, 0);
    saturating_index_.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      const SaturatingForce& f = terms_.saturating[island.saturating[i]];
      saturating_index_[i] = getLocalIndex(island, f.u);
      if (f.unclamped > f.limit) side_[i] = 1;
      if (f.unclamped < -f.limit) side_[i] = -1;
    }
    stuck_.assign(sliding_count_, 0);
    for (int solve = 1;; ++solve) {
      matrix_ = base_matrix_;
      rhs_ = base_rhs_;
      for (std::size_t j = 0; j < sliding_count_; ++j) {
        if (!stuck_[j]) continue;
        // The stick law in place of the capped force and its linearization.
        const PointCoupling& p = terms_.points[sliding_[j].index];
        const auto& jacobian = sliding_[j].jacobian;
        const Eigen::Matrix3d extra_stiffness = p.stick_stiffness - p.stiffness;
        weighted_.noalias() = (h * (p.stick_damping - p.damping) + h * h * extra_stiffness) * jacobian;
        matrix_.noalias() += jacobian.transpose() * weighted_;
        const Eigen::Vector3d change = h * (p.stick_force - p.slide_force) - h * h * (extra_stiffness * (jacobian * local_u_));
        rhs_.noalias() += jacobian.transpose() * change;
      }
      for (std::size_t i = 0; i < count; ++i) {
        const SaturatingForce& f = terms_.saturating[island.saturating[i]];
        const int k = saturating_index_[i];
        // M a holds what the force element applied; replace it with the
        // side's force.
        if (side_[i] == 0) {
          matrix_(k, k) += h * f.damping + h * h * f.stiffness;
          rhs_[k] += h * (f.unclamped - f.applied) - h * h * f.stiffness * local_u_[k];
        } else {
          rhs_[k] += h * (side_[i] * f.limit - f.applied);
        }
      }
      solve_.compute(matrix_);
      if (solve_.info() == Eigen::Success) {
        local_du_ = solve_.solve(rhs_);
      } else {
        // Not positive definite (a negative damping or stiffness from a
        // plugin's drive): LU still gives the step.
        local_du_ = matrix_.partialPivLu().solve(rhs_);
      }
      ++statistics_.iterations;
      if ((count == 0 && sliding_count_ == 0) || solve == kMaxSaturationSolves) return;
      bool consistent = true;
      for (std::size_t j = 0; j < sliding_count_; ++j) {
        // The stick law at the step's end. A sliding point whose law no
        // longer exceeds mu fn along its capped force (within the limit,
        // or turned against it: the capped force overshot, reversing the
        // slip) sticks; a sticking one whose law exceeds mu fn slides
        // again.
        const PointCoupling& p = terms_.points[sliding_[j].index];
        const auto& jacobian = sliding_[j].jacobian;
        const Eigen::Vector3d dv = jacobian * local_du_, v_end = jacobian * local_u_ + dv;
        const Eigen::Vector3d law = p.stick_force - p.tangent_damping * dv - h * (p.tangent_stiffness * v_end);
        const char stuck = stuck_[j] ? (law.norm() <= p.limit ? 1 : 0)
                                     : (law.dot(p.slide_force) < p.limit * p.slide_force.norm() ? 1 : 0);
        if (stuck != stuck_[j]) {
          stuck_[j] = stuck;
          consistent = false;
        }
      }
      for (std::size_t i = 0; i < count; ++i) {
        const SaturatingForce& f = terms_.saturating[island.saturating[i]];
        const int k = saturating_index_[i];
        const double at_end =
            f.unclamped - f.damping * local_du_[k] - f.stiffness * h * (local_u_[k] + local_du_[k]);
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
  TreeStructure trees_;
  bool quaternions_ = false, constrained_ = false;
  IntegratorStatistics statistics_;

  // Scratch, kept between steps.
  SimTK::Vector u_, force_, qdot_, no_udot_;
  ImplicitTerms terms_;
  std::vector<int> tree_root_, island_of_tree_;
  std::vector<Island> islands_;
  int island_count_ = 0;
  Eigen::VectorXd du_;
  Eigen::MatrixXd base_matrix_, matrix_;
  Eigen::VectorXd base_rhs_, rhs_, local_u_, local_du_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> point_jacobian_, weighted_;
  std::vector<int> side_, saturating_index_;
  struct SlidingPoint {
    int index = 0;  // into terms_.points
    Eigen::Matrix<double, 3, Eigen::Dynamic> jacobian;  // island-local
  };
  std::vector<SlidingPoint> sliding_;  // the island's first sliding_count_ are live
  std::size_t sliding_count_ = 0;
  std::vector<char> stuck_;
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
