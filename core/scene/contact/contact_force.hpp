// Every contact of a scene in one Force::Custom: broad phase (half spaces
// against bounding boxes, sweep and prune among the rest, over boxes with a
// margin that stay valid for many evaluations), narrow phase
// (contact_geometry.hpp) and the force law, applied straight to the bodies.
// Scratch buffers persist between evaluations, so the loop does not
// allocate once warm (except inside FCL's GJK/EPA).
//
// Force law per contact point, with the pair's combined material:
//  - normal: Hunt-Crossley, fn = k d (1 + 1.5 c ddot), never pulling;
//  - friction: "anchored stiction". Each point holds a tangential
//    spring-damper (kt, ct) to an anchor, a pair of material points on the
//    two bodies saved when the point was last evaluated. While
//    |f_t| <= mu_s fn the spring holds the bodies (no creep, unlike
//    regularized Coulomb friction); beyond it the force is capped at
//    mu(v) fn and the anchor is dragged along. Anchors live in an
//    auto-update discrete variable, so they are part of the SimTK::State
//    (saved and restored with it, identical across runs).
// Materials combine per pair: stiffness in series (k1 k2 / (k1 + k2)),
// dissipation weighted by compliance ((c1 k2 + c2 k1) / (k1 + k2)), static,
// dynamic and viscous friction by geometric mean (sqrt(mu1 mu2): either
// surface being frictionless makes the pair frictionless, and equal
// materials keep their value).
#pragma once

#include <cstdint>
#include <ostream>
#include <vector>

#include "Simbody.h"
#include "manibench/scene.hpp"
#include "contact/contact_geometry.hpp"
#include "implicit_terms.hpp"

namespace manibench {
namespace scene_detail {

// How far (m) a body may move before the broad phase looks again. Larger:
// fewer rebuilds, more candidate pairs to filter.
constexpr double kBroadPhaseMargin = 0.02;

struct ContactShape {
  ShapeGeometry geometry;
  SimTK::MobilizedBodyIndex body;  // GroundIndex for fixed shapes
  SimTK::Transform X_BS;           // shape frame in the body frame
  int link = -1;                   // scene link id; -1 for the ground plane
  int articulation = -1;           // -1 for the ground plane
  ContactMaterial material;
  // 1 / mass of a free-floating body, for FrictionLaw::max_frequency; 0 for
  // fixed and jointed bodies (drives and joints, not contact, set their pace).
  double inverse_mass = 0;
};

struct FrictionLaw {
  double stiffness = 1e5;  // kt per contact point, N/m
  double damping = 20;     // ct per contact point, N s/m
  // Slip speed over which static friction falls to dynamic friction.
  double transition_speed = 1e-3;  // m/s
  // An anchor is kept only if its point on B is within this of the new
  // contact point (guards against a feature id meaning something else).
  double match_distance = 5e-3;  // m
  // Highest contact frequency of a free body (0: no limit). A light body on
  // stiff contact springs oscillates faster than a step can follow: at
  // h = 5e-4 semi-explicit Euler blows a 35 g cube away, and CPodes (whose
  // absolute tolerance is 0.1 * accuracy, 1 mm by default) bounces an 8 g
  // one. So each pair's stiffnesses are capped at m_eff w^2 and its friction
  // damping at m_eff w, shared by the manifold's points (at least 4), with
  // m_eff from the free bodies' masses. Bodies above m = 4 k / w^2 (0.1 kg
  // at the defaults) keep their material; lighter ones rest g / w^2 deep
  // (2.5 um at 2000 rad/s) and are softer when squeezed.
  double max_frequency = 0;  // rad/s
};

// One friction anchor (see above), in the two bodies' frames.
struct FrictionAnchor {
  std::uint64_t pair = 0;  // shape_a << 32 | shape_b
  std::int32_t feature = 0;
  SimTK::Vec3 on_a{0}, on_b{0};
};
// Sorted by (pair, feature).
struct FrictionAnchorSet {
  std::vector<FrictionAnchor> anchors;
};
std::ostream& operator<<(std::ostream& out, const FrictionAnchorSet& set);

class ContactForce : public SimTK::Force::Custom::Implementation, public ImplicitForce {
 public:
  // `self_collision[a]`: links of articulation a may touch each other
  // (never those joined by a joint).
  ContactForce(const SimTK::SimbodyMatterSubsystem& matter,
               const SimTK::GeneralForceSubsystem& forces, std::vector<ContactShape> shapes,
               std::vector<char> self_collision, const FrictionLaw& law);
  ~ContactForce() override;

  int getNumShapes() const { return static_cast<int>(shapes_.size()); }
  const ContactShape& getShape(int i) const { return shapes_[i]; }

  // The friction anchors a state holds (part of what a saved state is).
  const FrictionAnchorSet& getAnchors(const SimTK::State& state) const;
  void setAnchors(SimTK::State& state, FrictionAnchorSet anchors) const;

  // One contact point's force, for queries (Ground frame).
  struct Report {
    int shape_a = -1, shape_b = -1;
    SimTK::Vec3 point{0};
    SimTK::Vec3 force_on_b{0};  // the force on shape_a is its negative
  };
  // The contacts of a state realized to Velocity, as calcForce sees them.
  void calcReports(const SimTK::State& state, std::vector<Report>& reports) const;

  void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>& body_forces,
                 SimTK::Vector_<SimTK::Vec3>& particle_forces,
                 SimTK::Vector& mobility_forces) const override;
  SimTK::Real calcPotentialEnergy(const SimTK::State& state) const override;
  void realizeTopology(SimTK::State& state) const override;

  // Whether force evaluations keep what addImplicitTerms needs (the
  // implicit_euler stepper asks for it; others need not pay for it).
  void setLinearizationKept(bool kept) { keep_linearization_ = kept; }
  // The contact points of the last force evaluation, linearized. Sliding
  // points are stiff only across the slip (their force is at the friction
  // limit along it).
  void addImplicitTerms(const SimTK::State& state, ImplicitTerms& terms) const override;

 private:
  struct PairMaterial {
    double k, c, mu_static, mu_dynamic, mu_viscous;
    double friction_stiffness = 0, friction_damping = 0;  // the anchor spring's, per point
  };
  enum class Mode { Apply, Report, Energy };
  // Broad phase, narrow phase and force law; what happens to the result
  // depends on the mode (forces and anchors, reports, or energy).
  double evaluate(const SimTK::State& state, Mode mode,
                  SimTK::Vector_<SimTK::SpatialVec>* body_forces,
                  std::vector<Report>* reports) const;
  // Moves the reference pose of every body that left its margin, and
  // rebuilds the candidate pairs if any did.
  void updateCandidates(const SimTK::State& state) const;
  void findCandidates() const;
  // Shape i's box at pose X_GS, grown by kBroadPhaseMargin.
  void calcGrownBox(int i, const SimTK::Transform& X_GS) const;
  // The shape's pose and exact bounding box at the current evaluation.
  void ensureShapeBox(int shape) const;
  bool areBoxesTouching(int a, int b) const;
  PairMaterial calcPairMaterial(const ContactShape& a, const ContactShape& b,
                                std::size_t points) const;
  bool isPairAllowed(int i, int j) const;
  static PairMaterial combine(const ContactMaterial& a, const ContactMaterial& b);

  // Every body that carries shapes (Ground excluded).
  struct BodyShapes {
    const SimTK::MobilizedBody* mobod = nullptr;
    std::vector<int> shapes;
    // Farthest point, from the body origin, of the points whose bounding
    // box calcBoundingBox builds (corners, centres): no point moves more
    // than |dp| + |dR|_F * radius when the body's pose changes by dp, dR.
    double radius = 0;
    bool has_half_space = false;  // a moving plane: candidate of every shape
  };

  const SimTK::SimbodyMatterSubsystem& matter_;
  const SimTK::GeneralForceSubsystem& forces_;
  std::vector<ContactShape> shapes_;
  std::vector<char> self_collision_;
  FrictionLaw law_;
  std::vector<SimTK::MobilizedBodyIndex> parent_;  // per shape: its body's parent
  std::vector<int> half_spaces_, finite_;          // shape indices by kind
  std::vector<BodyShapes> bodies_;
  std::vector<int> shape_body_;  // per shape: index into bodies_, -1 on Ground
  mutable SimTK::DiscreteVariableIndex anchors_index_;

  // Broad phase, persistent between evaluations. Each body has a reference
  // pose; its shapes' boxes at that pose, grown by kBroadPhaseMargin, give
  // the candidate pairs, valid while no body has moved farther than the
  // margin from its reference. The exact boxes of the current pose then
  // filter the candidates, so the pairs tested are exactly the pairs whose
  // current boxes overlap, whatever the history.
  mutable std::vector<SimTK::Transform> X_ref_;  // per body
  mutable std::vector<char> ref_valid_;          // per body
  mutable std::vector<SimTK::Vec3> fat_lo_, fat_hi_;  // per shape
  mutable std::vector<int> order_;  // finite shapes by fat lower bound, kept between calls
  mutable std::vector<std::pair<int, int>> candidates_;  // sorted
  mutable bool candidates_valid_ = false;

  // Per evaluation: body poses, and (lazily) shape poses and exact boxes.
  mutable std::uint64_t evaluation_ = 0;
  mutable std::vector<SimTK::Transform> X_GB_;  // per body
  mutable std::vector<std::uint64_t> shape_stamp_;
  mutable NarrowPhase narrow_;
  mutable std::vector<SimTK::Transform> X_GS_;
  mutable std::vector<SimTK::Vec3> lo_, hi_;
  mutable std::vector<ContactPoint> manifold_;

  // Linearization of the last Apply evaluation, if kept.
  bool keep_linearization_ = false;
  mutable std::vector<PointCoupling> linearization_;
};

}  // namespace scene_detail
}  // namespace manibench
