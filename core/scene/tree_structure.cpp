#include "tree_structure.hpp"

#include <cassert>

namespace manibench {
namespace scene_detail {
namespace {

Eigen::Matrix3d calcCrossMatrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Vector3d toEigen(const SimTK::Vec3& v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

}  // namespace

TreeStructure::TreeStructure(const SimTK::SimbodyMatterSubsystem& matter,
                             const SimTK::State& state)
    : matter_(matter) {
  const int bodies = matter.getNumBodies();
  bodies_.resize(bodies);
  composite_.resize(bodies);
  u_tree_.assign(state.getNU(), -1);
  u_local_.assign(state.getNU(), -1);
  // Mobilized body indices number parents before children.
  for (SimTK::MobilizedBodyIndex m(1); m < bodies; ++m) {
    const SimTK::MobilizedBody& mobod = matter.getMobilizedBody(m);
    Body& body = bodies_[m];
    body.parent = mobod.getParentMobilizedBody().getMobilizedBodyIndex();
    assert(body.parent < m);
    if (body.parent == SimTK::GroundIndex) {
      body.tree = static_cast<int>(tree_u_.size());
      tree_u_.emplace_back();
      tree_bodies_.emplace_back();
    } else {
      body.tree = bodies_[body.parent].tree;
    }
    body.first_u = mobod.getFirstUIndex(state);
    body.num_u = mobod.getNumU(state);
    body.hinge.resize(body.num_u);
    body.hinge_at_ground_origin.resize(body.num_u);
    tree_bodies_[body.tree].push_back(m);
    for (int k = 0; k < body.num_u; ++k) {
      const int u = body.first_u + k;
      u_tree_[u] = body.tree;
      u_local_[u] = static_cast<int>(tree_u_[body.tree].size());
      tree_u_[body.tree].push_back(u);
    }
  }
}

void TreeStructure::update(const SimTK::State& state) {
  for (SimTK::MobilizedBodyIndex m(1); m < static_cast<int>(bodies_.size()); ++m) {
    const SimTK::MobilizedBody& mobod = matter_.getMobilizedBody(m);
    Body& body = bodies_[m];
    body.origin = toEigen(mobod.getBodyOriginLocation(state));
    for (int k = 0; k < body.num_u; ++k) {
      const SimTK::SpatialVec H = mobod.getHCol(state, SimTK::MobilizerUIndex(k));
      const Eigen::Vector3d w = toEigen(H[0]), v = toEigen(H[1]);
      body.hinge[k] << w, v;
      // The velocity of the material point at the Ground origin: v - w x o.
      body.hinge_at_ground_origin[k] << w, v - w.cross(body.origin);
    }
    // Spatial inertia about the Ground origin, Ground frame, acting on
    // (w, v_O): [[Ic - m [c]x[c]x, m [c]x], [-m [c]x, m 1]], c the mass
    // centre and Ic the central inertia.
    const SimTK::MassProperties& mass_properties = mobod.getBodyMassProperties(state);
    const double mass = mass_properties.getMass();
    const SimTK::Rotation& R_GB = mobod.getBodyRotation(state);
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) R(r, c) = R_GB[r][c];
    const Eigen::Vector3d c_B = toEigen(mass_properties.getMassCenter());
    const SimTK::Mat33 I_Bo = mass_properties.calcInertia().toMat33();
    Eigen::Matrix3d I_origin_B;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) I_origin_B(r, c) = I_Bo(r, c);
    // Central inertia, by the parallel axis theorem, then turned to Ground.
    const Eigen::Matrix3d I_central =
        R * (I_origin_B - mass * (c_B.squaredNorm() * Eigen::Matrix3d::Identity() -
                                  c_B * c_B.transpose())) *
        R.transpose();
    const Eigen::Vector3d c = body.origin + R * c_B;
    const Eigen::Matrix3d cx = calcCrossMatrix(c);
    Matrix6d& I = body.inertia_at_ground_origin;
    I.topLeftCorner<3, 3>() = I_central - mass * cx * cx;
    I.topRightCorner<3, 3>() = mass * cx;
    I.bottomLeftCorner<3, 3>() = -mass * cx;
    I.bottomRightCorner<3, 3>() = mass * Eigen::Matrix3d::Identity();
  }
}

void TreeStructure::calcMassBlock(int tree, Eigen::Ref<Eigen::MatrixXd> block) const {
  const std::vector<SimTK::MobilizedBodyIndex>& members = tree_bodies_[tree];
  // Composite inertias: about one point (the Ground origin) they just add,
  // leaves first.
  for (SimTK::MobilizedBodyIndex m : members) composite_[m] = bodies_[m].inertia_at_ground_origin;
  for (auto it = members.rbegin(); it != members.rend(); ++it) {
    const SimTK::MobilizedBodyIndex parent = bodies_[*it].parent;
    if (parent != SimTK::GroundIndex) composite_[parent] += composite_[*it];
  }
  // M(l, k) = S_l^T Ic(b) S_k for u_k of body b and u_l of b or an ancestor;
  // speeds of sibling branches do not couple: those entries are zero.
  block.setZero();
  for (SimTK::MobilizedBodyIndex m : members) {
    const Body& body = bodies_[m];
    for (int k = 0; k < body.num_u; ++k) {
      const Vector6d F = composite_[m] * body.hinge_at_ground_origin[k];
      const int col = u_local_[body.first_u + k];
      for (SimTK::MobilizedBodyIndex j = m; j != SimTK::GroundIndex; j = bodies_[j].parent) {
        const Body& ancestor = bodies_[j];
        for (int l = 0; l < ancestor.num_u; ++l) {
          const int row = u_local_[ancestor.first_u + l];
          const double value = ancestor.hinge_at_ground_origin[l].dot(F);
          block(row, col) = value;
          block(col, row) = value;
        }
      }
    }
  }
}

void TreeStructure::addPointJacobian(SimTK::MobilizedBodyIndex body, const Eigen::Vector3d& point,
                                     double sign,
                                     Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>> jacobian) const {
  for (SimTK::MobilizedBodyIndex j = body; j != SimTK::GroundIndex; j = bodies_[j].parent) {
    const Body& ancestor = bodies_[j];
    const Eigen::Vector3d r = point - ancestor.origin;
    for (int l = 0; l < ancestor.num_u; ++l) {
      const Vector6d& H = ancestor.hinge[l];
      jacobian.col(u_local_[ancestor.first_u + l]) +=
          sign * (H.tail<3>() + H.head<3>().cross(r));
    }
  }
}

}  // namespace scene_detail
}  // namespace manibench
