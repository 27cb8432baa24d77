// The multibody system's structure as the implicit step sees it.
//
// Every mobilized body hanging from Ground starts a tree (a free box, a
// robot, each drawer of a fixed cabinet). The mass matrix is block diagonal
// over the trees, so the implicit step solves one small dense system per
// contact island (trees joined by contact points) instead of one of size
// nu: 100 resting boxes are 100 6 x 6 systems, not one 600 x 600.
//
// Per state it computes each tree's mass matrix block by the composite-
// rigid-body algorithm (Simbody's calcM multiplies by M once per column,
// O(n^2) with a large constant, a third of a cabinet step), and the velocity
// Jacobian of a material point, both from the hinge matrix columns H of
// each mobilizer (Simbody's getHCol).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "Simbody.h"

namespace manibench {
namespace scene_detail {

class TreeStructure {
 public:
  // `state` realized through Model (the u layout is fixed from there on).
  TreeStructure(const SimTK::SimbodyMatterSubsystem& matter, const SimTK::State& state);

  int getNumTrees() const { return static_cast<int>(tree_u_.size()); }
  // The tree a body belongs to; -1 for Ground.
  int getTree(SimTK::MobilizedBodyIndex body) const { return bodies_[body].tree; }
  // A tree's generalized speeds (global indices, ascending); a tree-local
  // index is a position in this list.
  const std::vector<int>& getTreeU(int tree) const { return tree_u_[tree]; }
  int getTreeOfU(int u) const { return u_tree_[u]; }
  int getLocalIndexOfU(int u) const { return u_local_[u]; }

  // Per state, realized through Position: hinge columns and inertias.
  void update(const SimTK::State& state);
  // Writes the tree's mass matrix block into `block` (square, in tree-local
  // order), every entry: those of speeds on sibling branches are zero.
  void calcMassBlock(int tree, Eigen::Ref<Eigen::MatrixXd> block) const;
  // Adds sign times the Jacobian of the velocity of `body`'s material point
  // at `point` (Ground frame) with respect to its tree's speeds into
  // `jacobian`, 3 x (the tree's u count), tree-local columns. Nothing for
  // Ground.
  void addPointJacobian(SimTK::MobilizedBodyIndex body, const Eigen::Vector3d& point, double sign,
                        Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>> jacobian) const;

 private:
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  struct Body {
    SimTK::MobilizedBodyIndex parent;  // invalid for Ground
    int tree = -1;
    int first_u = 0, num_u = 0;  // global
    // Per state: the body origin, and per u its hinge column (angular, then
    // the linear velocity of the origin) and that motion about the Ground
    // origin (for the composite inertias, which then just add up).
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    std::vector<Vector6d> hinge, hinge_at_ground_origin;
    Matrix6d inertia_at_ground_origin = Matrix6d::Zero();
  };

  const SimTK::SimbodyMatterSubsystem& matter_;
  std::vector<Body> bodies_;  // by MobilizedBodyIndex; [0] is Ground
  std::vector<std::vector<int>> tree_u_;
  std::vector<std::vector<SimTK::MobilizedBodyIndex>> tree_bodies_;  // parents first
  std::vector<int> u_tree_, u_local_;
  mutable std::vector<Matrix6d> composite_;  // scratch, by MobilizedBodyIndex
};

}  // namespace scene_detail
}  // namespace manibench
