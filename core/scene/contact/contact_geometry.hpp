// Contact geometry and narrow phase: which points of two convex shapes
// touch, with normal, depth and a feature id per point.
//
// Detection and the contact direction come from FCL: boxBox2 for box pairs;
// for a sphere or capsule against a box, cylinder or hull, the GJK distance
// from the sphere's centre (the capsule's axis) to the other shape; GJK/EPA
// for the rest (refined locally where a curved cylinder is involved). FCL
// reports a single point for most pairs, so the manifold is built here:
// the two shapes' supporting features along the FCL normal (vertex, edge
// or face) are clipped against each other and every penetrating point
// becomes a contact with its own exact depth; against a face, the normal is
// the face's. Pairs of a half space with anything, and of spheres and
// capsules among themselves, are closed-form and skip FCL.
//
// Conventions: poses are in Ground; the normal points from shape A into
// shape B (the force on B is along +normal); depth > 0 is penetration; the
// point lies midway between the two undeformed surfaces.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "Simbody.h"
#include "contact/convex_hull.hpp"

namespace manibench {
namespace scene_detail {

enum class ShapeKind { HalfSpace, Sphere, Box, Capsule, Cylinder, Convex };

// A shape in its own frame S. HalfSpace: the region z < 0 of S. Capsule and
// Cylinder: axis along z of S, centred at the origin. Convex: a hull whose
// vertices are given in S.
struct ShapeGeometry {
  ShapeKind kind = ShapeKind::Sphere;
  SimTK::Vec3 half{0};                     // Box half extents
  double radius = 0;                       // Sphere, Capsule, Cylinder
  double half_length = 0;                  // Capsule (core segment), Cylinder
  std::shared_ptr<const ConvexHull> hull;  // Convex
  std::shared_ptr<const fcl::CollisionGeometry<double>> fcl_geometry;  // not HalfSpace
  // Sphere and Capsule: the zero-radius core (a point or a segment), whose
  // distance to another shape gives the contact normal precisely.
  std::shared_ptr<const fcl::CollisionGeometry<double>> fcl_core;

  static ShapeGeometry makeHalfSpace();
  static ShapeGeometry makeSphere(double radius);
  static ShapeGeometry makeBox(const SimTK::Vec3& half);
  static ShapeGeometry makeCapsule(double radius, double half_length);
  static ShapeGeometry makeCylinder(double radius, double half_length);
  static ShapeGeometry makeConvex(std::shared_ptr<const ConvexHull> hull);

  // Axis-aligned bounding box in Ground (infinite for a half space).
  void calcBoundingBox(const SimTK::Transform& X_GS, SimTK::Vec3& lo, SimTK::Vec3& hi) const;
  // The point of the shape farthest along `d` (Ground); not for HalfSpace.
  SimTK::Vec3 findSupportPoint(const SimTK::Transform& X_GS, const SimTK::Vec3& d) const;
};

// Cylinder cap rims are polygons with this many corners where a cap lies
// flat on something (a 2% shortfall in radius at the worst angle); a rim
// that rests on its edge uses the exact deepest rim point instead.
constexpr int kCylinderRimPoints = 16;
// A manifold holds at most this many points; larger ones (a big flat hull
// face on the floor) are thinned to the deepest point plus the points that
// spread farthest from each other.
constexpr int kMaxManifoldPoints = 64;

struct ContactPoint {
  SimTK::Vec3 point;
  SimTK::UnitVec3 normal;
  double depth = 0;
  // Share of a full contact point, below 1 only while a cylinder rim turns
  // from lying flat to resting on its edge (keeps the force continuous).
  double weight = 1;
  // Identifies the pair of features that made the point (vertex, edge x
  // edge, ...), stable while the configuration changes smoothly; friction
  // anchors are matched by it.
  std::int32_t feature = 0;
};

// Computes manifolds. Holds scratch buffers, so one instance serves one
// thread; after warm-up the closed-form pairs and box pairs allocate
// nothing (FCL's GJK/EPA allocates internally).
class NarrowPhase {
 public:
  NarrowPhase();
  ~NarrowPhase();
  NarrowPhase(const NarrowPhase&) = delete;
  NarrowPhase& operator=(const NarrowPhase&) = delete;

  // Replaces `out` with the contact points between A and B.
  void calcContacts(const ShapeGeometry& a, const SimTK::Transform& X_GA, const ShapeGeometry& b,
                    const SimTK::Transform& X_GB, std::vector<ContactPoint>& out);

  struct Impl;  // narrow_phase_impl.hpp

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace scene_detail
}  // namespace manibench
