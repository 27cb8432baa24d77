#include "scene/contact/contact_geometry.hpp"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/detail/primitive_shape_algorithm/box_box.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace manibench {
namespace scene_detail {
namespace {

using SimTK::Rotation;
using SimTK::Transform;
using SimTK::UnitVec3;
using SimTK::Vec3;

// A face counts as facing a direction within ~8 degrees, an edge as lying
// across it within ~8 degrees. Outside these the feature is a single vertex.
// Points of a face or edge that do not penetrate are dropped anyway, so the
// exact values only matter for which features get clipped.
constexpr double kFaceCos = 0.990;
constexpr double kEdgeSin = 0.139;
// Two edges (or capsule axes) closer to parallel than this give two points.
constexpr double kParallelSin = 0.02;
constexpr double kParallelCos = 0.9998;
// The reference face is A's unless B's faces the normal better by this
// much: a hysteresis against flipping between nearly parallel faces (which
// would renumber the points and drop their friction anchors).
constexpr double kReferenceBias = 1e-3;
// How far the overlap along FCL's normal may exceed FCL's depth before the
// normal is taken for a failure. EPA on curved surfaces is off by up to a
// few tenths of a millimetre (then refined); a failed EPA is off by the
// size of the shapes.
constexpr double kDepthSlack = 1e-3;
// A tilted cylinder rim switches from the polygon to its exact deepest
// point between these sines of the tilt angle (about 1 and 6 degrees).
constexpr double kRimBlendStart = 0.02;
constexpr double kRimBlendEnd = 0.10;

// What made a contact point, for its feature id (see makeFeature). The
// closed-form half-space pairs number their points by vertex instead; ids
// are only ever compared within one pair of shapes.
enum FeatureKind : std::uint32_t {
  kVertex = 1,        // an incident vertex inside the reference face
  kEdgeCrossing = 2,  // an incident edge crossing a reference side plane
  kCorner = 3,        // a reference corner inside the incident face
  kSegmentEnd = 4,    // an end of a clipped segment
  kSingle = 5,        // the one point of a vertex or crossing-edge contact
  kOverlapEnd = 6,    // an end of the overlap of parallel segments
};
std::int32_t makeFeature(std::uint32_t kind, bool reference_b, std::uint32_t x, std::uint32_t y) {
  // 31 bits: kind (3) | reference_b (1) | x (12) | y (15). Collisions in
  // degenerate cases only cost a friction anchor, which the distance check
  // of the matcher catches.
  return static_cast<std::int32_t>(((kind & 7u) << 28) | ((reference_b ? 1u : 0u) << 27) |
                                   ((x & 0xFFFu) << 15) | (y & 0x7FFFu));
}

double sign(double x) { return x >= 0 ? 1.0 : -1.0; }

double smoothstep(double x) {
  x = std::min(1.0, std::max(0.0, x));
  return x * x * (3 - 2 * x);
}

fcl::Transform3d toFcl(const Transform& X) {
  fcl::Transform3d T = fcl::Transform3d::Identity();
  const SimTK::Mat33& R = X.R().asMat33();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) T.linear()(i, j) = R(i, j);
  T.translation() = fcl::Vector3d(X.p()[0], X.p()[1], X.p()[2]);
  return T;
}

// Unit vector along the part of `d` perpendicular to unit `a`; false if
// `d` is (nearly) parallel to `a`.
bool findPerpendicular(const Vec3& d, const Vec3& a, Vec3& out, double* length = nullptr) {
  const Vec3 s = d - SimTK::dot(d, a) * a;
  const double n = s.norm();
  if (length != nullptr) *length = n;
  if (n < 1e-12) return false;
  out = s / n;
  return true;
}

// Closest points of segments p0 + s u (s in [0,1]) and q0 + t w (t in [0,1]).
void findClosestPoints(const Vec3& p0, const Vec3& u, const Vec3& q0, const Vec3& w, Vec3& p,
                       Vec3& q) {
  const Vec3 r = p0 - q0;
  const double a = u.normSqr(), e = w.normSqr(), f = SimTK::dot(w, r);
  double s = 0, t = 0;
  if (a <= 1e-24 && e <= 1e-24) {
    s = t = 0;
  } else if (a <= 1e-24) {
    t = std::min(1.0, std::max(0.0, f / e));
  } else {
    const double c = SimTK::dot(u, r);
    if (e <= 1e-24) {
      s = std::min(1.0, std::max(0.0, -c / a));
    } else {
      const double b = SimTK::dot(u, w), den = a * e - b * b;
      s = den > 1e-14 * a * e ? std::min(1.0, std::max(0.0, (b * f - c * e) / den)) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::min(1.0, std::max(0.0, -c / a));
      } else if (t > 1) {
        t = 1;
        s = std::min(1.0, std::max(0.0, (b - c) / a));
      }
    }
  }
  p = p0 + s * u;
  q = q0 + t * w;
}

// Corner `code` of a box: bit i set means +half[i].
Vec3 boxCorner(const Vec3& half, int code) {
  return Vec3(code & 1 ? half[0] : -half[0], code & 2 ? half[1] : -half[1],
              code & 4 ? half[2] : -half[2]);
}

Vec3 rimPoint(double radius, double z, int k) {
  const double angle = 2 * SimTK::Pi * k / kCylinderRimPoints;
  return Vec3(radius * std::cos(angle), radius * std::sin(angle), z);
}

void addPoint(std::vector<ContactPoint>& out, const Vec3& point, const UnitVec3& normal,
              double depth, std::int32_t feature, double weight = 1) {
  ContactPoint c;
  c.point = point;
  c.normal = normal;
  c.depth = depth;
  c.weight = weight;
  c.feature = feature;
  out.push_back(c);
}

}  // namespace

// --- ShapeGeometry ----------------------------------------------------------

ShapeGeometry ShapeGeometry::makeHalfSpace() {
  ShapeGeometry g;
  g.kind = ShapeKind::HalfSpace;
  return g;
}

ShapeGeometry ShapeGeometry::makeSphere(double radius) {
  ShapeGeometry g;
  g.kind = ShapeKind::Sphere;
  g.radius = radius;
  g.fcl_geometry = std::make_shared<fcl::Sphered>(radius);
  g.fcl_core = std::make_shared<fcl::Sphered>(0.0);
  return g;
}

ShapeGeometry ShapeGeometry::makeBox(const Vec3& half) {
  ShapeGeometry g;
  g.kind = ShapeKind::Box;
  g.half = half;
  g.fcl_geometry = std::make_shared<fcl::Boxd>(2 * half[0], 2 * half[1], 2 * half[2]);
  return g;
}

ShapeGeometry ShapeGeometry::makeCapsule(double radius, double half_length) {
  ShapeGeometry g;
  g.kind = ShapeKind::Capsule;
  g.radius = radius;
  g.half_length = half_length;
  g.fcl_geometry = std::make_shared<fcl::Capsuled>(radius, 2 * half_length);
  g.fcl_core = std::make_shared<fcl::Capsuled>(0.0, 2 * half_length);
  return g;
}

ShapeGeometry ShapeGeometry::makeCylinder(double radius, double half_length) {
  ShapeGeometry g;
  g.kind = ShapeKind::Cylinder;
  g.radius = radius;
  g.half_length = half_length;
  g.fcl_geometry = std::make_shared<fcl::Cylinderd>(radius, 2 * half_length);
  return g;
}

ShapeGeometry ShapeGeometry::makeConvex(std::shared_ptr<const ConvexHull> hull) {
  assert(hull && hull->fcl_geometry);
  ShapeGeometry g;
  g.kind = ShapeKind::Convex;
  g.fcl_geometry = hull->fcl_geometry;
  g.hull = std::move(hull);
  return g;
}

void ShapeGeometry::calcBoundingBox(const Transform& X, Vec3& lo, Vec3& hi) const {
  const SimTK::Mat33& R = X.R().asMat33();
  Vec3 center = X.p(), extent(0);
  switch (kind) {
    case ShapeKind::HalfSpace:
      lo = Vec3(-SimTK::Infinity);
      hi = Vec3(SimTK::Infinity);
      return;
    case ShapeKind::Sphere:
      extent = Vec3(radius);
      break;
    case ShapeKind::Box:
      for (int i = 0; i < 3; ++i)
        extent[i] =
            std::abs(R(i, 0)) * half[0] + std::abs(R(i, 1)) * half[1] + std::abs(R(i, 2)) * half[2];
      break;
    case ShapeKind::Capsule:
      for (int i = 0; i < 3; ++i) extent[i] = std::abs(R(i, 2)) * half_length + radius;
      break;
    case ShapeKind::Cylinder:
      for (int i = 0; i < 3; ++i) {
        const double a = R(i, 2);
        extent[i] = std::abs(a) * half_length + radius * std::sqrt(std::max(0.0, 1 - a * a));
      }
      break;
    case ShapeKind::Convex:
      center = X * hull->box_center;
      for (int i = 0; i < 3; ++i)
        extent[i] = std::abs(R(i, 0)) * hull->box_half[0] + std::abs(R(i, 1)) * hull->box_half[1] +
                    std::abs(R(i, 2)) * hull->box_half[2];
      break;
  }
  lo = center - extent;
  hi = center + extent;
}

Vec3 ShapeGeometry::findSupportPoint(const Transform& X, const Vec3& d) const {
  const Vec3 dl = ~X.R() * d;
  switch (kind) {
    case ShapeKind::Sphere:
      return X.p() + radius * d / d.norm();
    case ShapeKind::Box:
      return X * Vec3(sign(dl[0]) * half[0], sign(dl[1]) * half[1], sign(dl[2]) * half[2]);
    case ShapeKind::Capsule:
      return X * Vec3(0, 0, sign(dl[2]) * half_length) + radius * d / d.norm();
    case ShapeKind::Cylinder: {
      Vec3 s(0);
      findPerpendicular(dl, Vec3(0, 0, 1), s);
      return X * Vec3(radius * s[0], radius * s[1], sign(dl[2]) * half_length);
    }
    case ShapeKind::Convex:
      return X * hull->vertices[hull->findSupportVertex(dl)];
    case ShapeKind::HalfSpace:
      break;
  }
  assert(!"findSupportPoint of a half space");
  return Vec3(0);
}

// --- NarrowPhase --------------------------------------------------------------

namespace {

// The part of a shape's surface that is extreme along a direction.
struct Feature {
  enum class Kind { Point, Segment, Polygon };
  Kind kind = Kind::Point;
  std::vector<Vec3> points;       // Ground
  std::vector<std::int32_t> ids;  // per point: vertex numbers of the shape
  UnitVec3 normal;                // Polygon: its outward normal

  void reset(Kind k) {
    kind = k;
    points.clear();
    ids.clear();
  }
  void add(const Vec3& p, std::int32_t id) {
    points.push_back(p);
    ids.push_back(id);
  }
};

// One vertex of a polygon being clipped. `edge` labels the edge from this
// vertex to the next: an incident-polygon edge (its start vertex id) or a
// reference side plane the polygon was cut along (kPlaneEdge | plane).
struct ClipVertex {
  Vec3 p;
  std::int32_t id;
  std::uint32_t edge;
};
constexpr std::uint32_t kPlaneEdge = 1u << 30;

// The feature of shape `g` extreme along unit direction `d`.
void calcFeature(const ShapeGeometry& g, const Transform& X, const Vec3& d, Feature& f) {
  const Rotation& R = X.R();
  const Vec3 dl = ~R * d;
  switch (g.kind) {
    case ShapeKind::Sphere:
      f.reset(Feature::Kind::Point);
      f.add(X.p() + g.radius * d, 0);
      return;
    case ShapeKind::Capsule: {
      const Vec3 a = R.z();
      if (std::abs(dl[2]) < kEdgeSin) {
        f.reset(Feature::Kind::Segment);
        f.add(X.p() - g.half_length * a + g.radius * d, 0);
        f.add(X.p() + g.half_length * a + g.radius * d, 1);
      } else {
        f.reset(Feature::Kind::Point);
        f.add(X.p() + sign(dl[2]) * g.half_length * a + g.radius * d, dl[2] >= 0 ? 1 : 0);
      }
      return;
    }
    case ShapeKind::Box: {
      int axis = 0;
      for (int i = 1; i < 3; ++i)
        if (std::abs(dl[i]) > std::abs(dl[axis])) axis = i;
      if (std::abs(dl[axis]) >= kFaceCos) {
        // The face's corners counterclockwise about its outward normal.
        const int j = (axis + 1) % 3, k = (axis + 2) % 3;
        const bool positive = dl[axis] >= 0;
        const int base = positive ? 1 << axis : 0;
        static const int kLoop[4][2] = {{1, 1}, {0, 1}, {0, 0}, {1, 0}};
        f.reset(Feature::Kind::Polygon);
        for (int n = 0; n < 4; ++n) {
          const int c = positive ? n : 3 - n;
          const int code = base | (kLoop[c][0] << j) | (kLoop[c][1] << k);
          f.add(X * boxCorner(g.half, code), code);
        }
        Vec3 normal(0);
        normal[axis] = positive ? 1 : -1;
        f.normal = UnitVec3(R * normal, true);
        return;
      }
      int code = (dl[0] >= 0 ? 1 : 0) | (dl[1] >= 0 ? 2 : 0) | (dl[2] >= 0 ? 4 : 0);
      int edge_axis = -1;
      for (int i = 0; i < 3; ++i)
        if (std::abs(dl[i]) < kEdgeSin &&
            (edge_axis < 0 || std::abs(dl[i]) < std::abs(dl[edge_axis])))
          edge_axis = i;
      if (edge_axis >= 0) {
        f.reset(Feature::Kind::Segment);
        const int low = code & ~(1 << edge_axis), high = code | (1 << edge_axis);
        f.add(X * boxCorner(g.half, low), low);
        f.add(X * boxCorner(g.half, high), high);
      } else {
        f.reset(Feature::Kind::Point);
        f.add(X * boxCorner(g.half, code), code);
      }
      return;
    }
    case ShapeKind::Cylinder: {
      const double z = sign(dl[2]) * g.half_length;
      if (std::abs(dl[2]) >= kFaceCos) {
        f.reset(Feature::Kind::Polygon);
        const bool top = dl[2] >= 0;
        for (int n = 0; n < kCylinderRimPoints; ++n) {
          const int k = top ? n : kCylinderRimPoints - 1 - n;
          f.add(X * rimPoint(g.radius, z, k), (top ? kCylinderRimPoints : 0) + k);
        }
        f.normal = UnitVec3(top ? Vec3(R.z()) : Vec3(-R.z()), true);
        return;
      }
      Vec3 s(0);
      findPerpendicular(dl, Vec3(0, 0, 1), s);
      const Vec3 side = g.radius * s;
      if (std::abs(dl[2]) < kEdgeSin) {
        f.reset(Feature::Kind::Segment);
        f.add(X * Vec3(side[0], side[1], -g.half_length), 2 * kCylinderRimPoints);
        f.add(X * Vec3(side[0], side[1], g.half_length), 2 * kCylinderRimPoints + 1);
      } else {
        f.reset(Feature::Kind::Point);
        f.add(X * Vec3(side[0], side[1], z), 2 * kCylinderRimPoints + (dl[2] >= 0 ? 1 : 0));
      }
      return;
    }
    case ShapeKind::Convex: {
      const ConvexHull& hull = *g.hull;
      const int v = hull.findSupportVertex(dl);
      int best_face = -1;
      double best = -2;
      for (int face : hull.vertex_faces[v]) {
        const double c = SimTK::dot(hull.faces[face].normal, dl);
        if (c > best) {
          best = c;
          best_face = face;
        }
      }
      if (best >= kFaceCos) {
        const ConvexHull::Face& face = hull.faces[best_face];
        f.reset(Feature::Kind::Polygon);
        for (int w : face.vertices) f.add(X * hull.vertices[w], w);
        f.normal = UnitVec3(R * face.normal, true);
        return;
      }
      int best_neighbor = -1;
      double least = kEdgeSin;
      for (int w : hull.vertex_neighbors[v]) {
        const Vec3 e = hull.vertices[w] - hull.vertices[v];
        const double c = std::abs(SimTK::dot(e, dl)) / e.norm();
        if (c < least) {
          least = c;
          best_neighbor = w;
        }
      }
      if (best_neighbor >= 0) {
        f.reset(Feature::Kind::Segment);
        const int lo = std::min(v, best_neighbor), hi = std::max(v, best_neighbor);
        f.add(X * hull.vertices[lo], lo);
        f.add(X * hull.vertices[hi], hi);
      } else {
        f.reset(Feature::Kind::Point);
        f.add(X * hull.vertices[v], v);
      }
      return;
    }
    case ShapeKind::HalfSpace:
      break;
  }
  assert(!"calcFeature of a half space");
}

}  // namespace

struct NarrowPhase::Scratch {
  Feature feature_a, feature_b;
  std::vector<ClipVertex> clip_in, clip_out;
  std::vector<ContactPoint> thinned;
  std::vector<char> taken;
  std::vector<double> spread;
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::DistanceRequestd distance_request;
  fcl::DistanceResultd distance_result;
  std::vector<fcl::ContactPointd> box_contacts;

  Scratch() {
    request.num_max_contacts = 1;
    request.enable_contact = true;
    // FCL's own GJK/EPA finds the true minimum-penetration direction; the
    // libccd path (MPR) follows the centre-to-centre ray and picks a wrong
    // face when a plate overhangs an edge.
    request.gjk_solver_type = fcl::GST_INDEP;
    distance_request.enable_nearest_points = true;
    distance_request.gjk_solver_type = fcl::GST_INDEP;
    distance_request.distance_tolerance = 1e-10;
  }

  // --- closed-form pairs ---
  void collideHalfSpace(const Transform& X_H, const ShapeGeometry& g, const Transform& X,
                        std::vector<ContactPoint>& out) const;
  void collideCapsules(double ra, double la, const Transform& X_A, double rb, double lb,
                       const Transform& X_B, std::vector<ContactPoint>& out) const;
  // --- general convex pairs ---
  bool findNormal(const ShapeGeometry& a, const Transform& X_A, const ShapeGeometry& b,
                  const Transform& X_B, UnitVec3& n);
  bool orientNormal(const ShapeGeometry& a, const Transform& X_A, const ShapeGeometry& b,
                    const Transform& X_B, Vec3 direction, double depth, UnitVec3& n) const;
  // 1: normal found, 0: no contact, -1: the core penetrates (use EPA).
  int findCoreNormal(const ShapeGeometry& a, const Transform& X_A, const ShapeGeometry& b,
                     const Transform& X_B, UnitVec3& n);
  void refineNormal(const ShapeGeometry& a, const Transform& X_A, const ShapeGeometry& b,
                    const Transform& X_B, UnitVec3& n) const;
  void buildManifold(const ShapeGeometry& a, const Transform& X_A, const ShapeGeometry& b,
                     const Transform& X_B, const UnitVec3& n, std::vector<ContactPoint>& out);
  void clipPolygons(const Feature& ref, const Feature& inc, bool reference_b,
                    std::vector<ContactPoint>& out);
  void clipSegment(const Feature& ref, const Vec3& p0, const Vec3& p1, std::int32_t id0,
                   std::int32_t id1, bool reference_b, std::vector<ContactPoint>& out) const;
  void addSingle(const ShapeGeometry& a, const Transform& X_A, const ShapeGeometry& b,
                 const Transform& X_B, const UnitVec3& n, std::vector<ContactPoint>& out) const;
  void collideSegments(const Feature& fa, const Feature& fb, const UnitVec3& n,
                       std::vector<ContactPoint>& out) const;
  void thin(std::vector<ContactPoint>& points);
};

NarrowPhase::NarrowPhase() : scratch_(std::make_unique<Scratch>()) {}
NarrowPhase::~NarrowPhase() = default;

void NarrowPhase::Scratch::collideHalfSpace(const Transform& X_H, const ShapeGeometry& g,
                                            const Transform& X,
                                            std::vector<ContactPoint>& out) const {
  const UnitVec3 n(X_H.z(), true);
  const double plane = SimTK::dot(X_H.p(), n);
  // Height above the plane; a penetrating point goes midway to the plane.
  auto addIfBelow = [&](const Vec3& p, std::int32_t id, double weight) {
    const double h = SimTK::dot(p, n) - plane;
    if (h < 0) addPoint(out, p - 0.5 * h * n, n, -h, id, weight);
  };
  switch (g.kind) {
    case ShapeKind::Sphere:
      addIfBelow(X.p() - g.radius * n, 0, 1);
      return;
    case ShapeKind::Capsule:
      addIfBelow(X * Vec3(0, 0, -g.half_length) - g.radius * n, 0, 1);
      addIfBelow(X * Vec3(0, 0, g.half_length) - g.radius * n, 1, 1);
      return;
    case ShapeKind::Box: {
      // Quick reject on the box's extent along the normal.
      const Vec3 nl = ~X.R() * n;
      const double reach =
          std::abs(nl[0]) * g.half[0] + std::abs(nl[1]) * g.half[1] + std::abs(nl[2]) * g.half[2];
      if (SimTK::dot(X.p(), n) - plane >= reach) return;
      for (int code = 0; code < 8; ++code) addIfBelow(X * boxCorner(g.half, code), code, 1);
      return;
    }
    case ShapeKind::Cylinder: {
      // Lying flat, the cap rests on its polygon (stable, fixed points for
      // friction); tilted, on the exact deepest rim point. Blending the two
      // over a few degrees keeps the force continuous.
      const Vec3 a = X.R().z();
      Vec3 s(0);
      double tilt = 0;
      const bool tilted = findPerpendicular(Vec3(n), a, s, &tilt);
      const double w =
          tilted ? smoothstep((tilt - kRimBlendStart) / (kRimBlendEnd - kRimBlendStart)) : 0;
      for (int cap = 0; cap < 2; ++cap) {
        const double z = cap == 0 ? -g.half_length : g.half_length;
        if (w < 1)
          for (int k = 0; k < kCylinderRimPoints; ++k)
            addIfBelow(X * rimPoint(g.radius, z, k), cap * kCylinderRimPoints + k, 1 - w);
        if (w > 0) addIfBelow(X * Vec3(0, 0, z) - g.radius * s, 2 * kCylinderRimPoints + cap, w);
      }
      return;
    }
    case ShapeKind::Convex: {
      const ConvexHull& hull = *g.hull;
      for (std::size_t v = 0; v < hull.vertices.size(); ++v)
        addIfBelow(X * hull.vertices[v], static_cast<std::int32_t>(v), 1);
      return;
    }
    case ShapeKind::HalfSpace:
      return;  // two half spaces are both on Ground
  }
}

// Spheres are capsules of zero length. Nearly parallel capsules touch
// along a line: two points at the ends of the overlap keep them level.
void NarrowPhase::Scratch::collideCapsules(double ra, double la, const Transform& X_A, double rb,
                                           double lb, const Transform& X_B,
                                           std::vector<ContactPoint>& out) const {
  const Vec3 ca = X_A.p(), cb = X_B.p();
  const Vec3 ua = X_A.R().z(), ub = X_B.R().z();
  auto addSpheres = [&](const Vec3& pa, const Vec3& pb, std::int32_t id) {
    const Vec3 d = pb - pa;
    const double distance = d.norm();
    const double depth = ra + rb - distance;
    if (depth <= 0) return;
    UnitVec3 n;
    if (distance > 1e-12)
      n = UnitVec3(d / distance, true);
    else if ((cb - ca).norm() > 1e-12)
      n = UnitVec3(cb - ca);
    else
      n = UnitVec3(SimTK::ZAxis);
    addPoint(out, pa + (ra - 0.5 * depth) * Vec3(n), n, depth, id);
  };
  if (la > 0 && lb > 0 && std::abs(SimTK::dot(ua, ub)) > kParallelCos) {
    // Overlap of B's axis projected on A's, in A's axial coordinate.
    const double o = SimTK::dot(cb - ca, ua);
    const double lo = std::max(-la, o - lb), hi = std::min(la, o + lb);
    if (lo <= hi) {
      const double direction = SimTK::dot(ua, ub) >= 0 ? 1 : -1;
      const int count = hi - lo > 1e-9 ? 2 : 1;
      for (int i = 0; i < count; ++i) {
        const double t = i == 0 ? lo : hi;
        const double tb = std::max(-lb, std::min(lb, direction * (t - o)));
        addSpheres(ca + t * ua, cb + tb * ub, makeFeature(kOverlapEnd, false, 0, i));
      }
      return;
    }
  }
  Vec3 pa, pb;
  findClosestPoints(ca - la * ua, 2 * la * ua, cb - lb * ub, 2 * lb * ub, pa, pb);
  addSpheres(pa, pb, makeFeature(kSingle, false, 0, 0));
}

// The contact direction from FCL, oriented from A into B. FCL's sign
// conventions differ between its routines (and EPA reports the normal in
// A's frame in 0.7), so A is placed at the origin and the orientation is
// taken from the geometry: along the true normal the overlap of the two
// shapes' extents is the penetration depth, along its opposite it is their
// whole size. That overlap also checks the answer: EPA returns a
// meaningless direction when the shapes barely touch (seen: a capsule
// grazing a hull gave its initial guess, +x, with depth 0), so a normal
// whose overlap exceeds FCL's own depth is rejected and the query repeated
// with the shapes swapped.
bool NarrowPhase::Scratch::findNormal(const ShapeGeometry& a, const Transform& X_A,
                                      const ShapeGeometry& b, const Transform& X_B, UnitVec3& n) {
  if (a.kind == ShapeKind::Box && b.kind == ShapeKind::Box) {
    fcl::Vector3d normal;
    double depth = 0;
    int code = 0;
    box_contacts.clear();
    const int count = fcl::detail::boxBox2<double>(
        fcl::Vector3d(2 * a.half[0], 2 * a.half[1], 2 * a.half[2]), toFcl(X_A),
        fcl::Vector3d(2 * b.half[0], 2 * b.half[1], 2 * b.half[2]), toFcl(X_B), normal, &depth,
        &code, 1, box_contacts);
    // boxBox2 is a separating-axis test: its normal needs no second opinion.
    return count > 0 &&
           orientNormal(a, X_A, b, X_B, Vec3(normal[0], normal[1], normal[2]), SimTK::Infinity, n);
  }
  if (a.fcl_core || b.fcl_core) {
    const int found = findCoreNormal(a, X_A, b, X_B, n);
    if (found >= 0) return found == 1;
  }
  for (int attempt = 0; attempt < 2; ++attempt) {
    const bool swapped = attempt == 1;
    const ShapeGeometry& first = swapped ? b : a;
    const ShapeGeometry& second = swapped ? a : b;
    const Transform& X_first = swapped ? X_B : X_A;
    const Transform& X_second = swapped ? X_A : X_B;
    result.clear();
    fcl::collide(first.fcl_geometry.get(), fcl::Transform3d::Identity(), second.fcl_geometry.get(),
                 toFcl(~X_first * X_second), request, result);
    if (!result.isCollision() || result.numContacts() == 0) return false;
    const fcl::Contactd& contact = result.getContact(0);
    const Vec3 direction =
        X_first.R() * Vec3(contact.normal[0], contact.normal[1], contact.normal[2]);
    if (orientNormal(a, X_A, b, X_B, direction, std::abs(contact.penetration_depth), n)) {
      if (a.kind == ShapeKind::Cylinder || b.kind == ShapeKind::Cylinder)
        refineNormal(a, X_A, b, X_B, n);
      return true;
    }
  }
  return false;
}

// The normal from the distance between a sphere's centre (capsule's axis)
// and the other shape: exact where EPA, working on curved surfaces, is off
// by degrees (and with it the depth along the normal).
int NarrowPhase::Scratch::findCoreNormal(const ShapeGeometry& a, const Transform& X_A,
                                         const ShapeGeometry& b, const Transform& X_B,
                                         UnitVec3& n) {
  const bool core_is_a = a.fcl_core != nullptr;
  const ShapeGeometry& core = core_is_a ? a : b;
  const ShapeGeometry& other = core_is_a ? b : a;
  const Transform& X_core = core_is_a ? X_A : X_B;
  const Transform& X_other = core_is_a ? X_B : X_A;
  distance_result.clear();
  const double distance =
      fcl::distance(other.fcl_geometry.get(), fcl::Transform3d::Identity(), core.fcl_core.get(),
                    toFcl(~X_other * X_core), distance_request, distance_result);
  if (distance >= core.radius) return 0;
  if (!(distance > 1e-9)) return -1;
  const fcl::Vector3d& p_other = distance_result.nearest_points[0];
  const fcl::Vector3d& p_core = distance_result.nearest_points[1];
  const Vec3 away = X_other.R() * Vec3(p_core[0] - p_other[0], p_core[1] - p_other[1],
                                       p_core[2] - p_other[2]);  // other -> core
  const double length = away.norm();
  if (!(length > 1e-12) || !away.isFinite()) return -1;
  n = UnitVec3(core_is_a ? Vec3(-away / length) : Vec3(away / length), true);
  return 1;
}

// Minimizes the overlap of the shapes' extents along n (the penetration
// depth is its minimum over all directions) by projected gradient descent:
// the gradient of a support function is the support point.
void NarrowPhase::Scratch::refineNormal(const ShapeGeometry& a, const Transform& X_A,
                                        const ShapeGeometry& b, const Transform& X_B,
                                        UnitVec3& n) const {
  auto overlap = [&](const Vec3& d, Vec3* gradient) {
    const Vec3 w = a.findSupportPoint(X_A, d) - b.findSupportPoint(X_B, -d);
    if (gradient != nullptr) *gradient = w;
    return SimTK::dot(w, d);
  };
  Vec3 current(n), w;
  double f = overlap(current, &w);
  for (int iteration = 0; iteration < 20; ++iteration) {
    const Vec3 g = w - SimTK::dot(w, current) * current;
    const double g_norm = g.norm();
    if (g_norm < 1e-12) break;
    double step = 0.1;  // radians
    bool improved = false;
    for (int halving = 0; halving < 30 && step > 1e-9; ++halving, step /= 2) {
      const Vec3 trial = (current - (step / g_norm) * g).normalize();
      Vec3 w_trial;
      const double f_trial = overlap(trial, &w_trial);
      if (f_trial < f - 1e-4 * step * g_norm) {
        current = trial;
        f = f_trial;
        w = w_trial;
        improved = true;
        break;
      }
    }
    if (!improved || step < 1e-8) break;
  }
  n = UnitVec3(current, true);
}

bool NarrowPhase::Scratch::orientNormal(const ShapeGeometry& a, const Transform& X_A,
                                        const ShapeGeometry& b, const Transform& X_B,
                                        Vec3 direction, double depth, UnitVec3& n) const {
  const double length = direction.norm();
  if (!(length > 0.5) || !direction.isFinite()) return false;
  direction /= length;
  const double along = SimTK::dot(
      a.findSupportPoint(X_A, direction) - b.findSupportPoint(X_B, -direction), direction);
  const double against = SimTK::dot(
      b.findSupportPoint(X_B, direction) - a.findSupportPoint(X_A, -direction), direction);
  if (std::min(along, against) > 2 * depth + kDepthSlack) return false;
  n = UnitVec3(along <= against ? direction : Vec3(-direction), true);
  return true;
}

// Clips the incident polygon against the side planes of the reference
// polygon; every surviving point below the reference face is a contact.
void NarrowPhase::Scratch::clipPolygons(const Feature& ref, const Feature& inc, bool reference_b,
                                        std::vector<ContactPoint>& out) {
  clip_in.clear();
  for (std::size_t i = 0; i < inc.points.size(); ++i)
    clip_in.push_back({inc.points[i], makeFeature(kVertex, reference_b, 0, inc.ids[i]),
                       static_cast<std::uint32_t>(inc.ids[i])});
  const std::size_t m = ref.points.size();
  for (std::size_t k = 0; k < m && !clip_in.empty(); ++k) {
    const Vec3& q = ref.points[k];
    // Inward normal of side plane k (ref is counterclockwise about its normal).
    const Vec3 inward = SimTK::cross(Vec3(ref.normal), ref.points[(k + 1) % m] - q);
    clip_out.clear();
    const std::size_t count = clip_in.size();
    for (std::size_t i = 0; i < count; ++i) {
      const ClipVertex& cur = clip_in[i];
      const ClipVertex& next = clip_in[(i + 1) % count];
      const double dc = SimTK::dot(cur.p - q, inward), dn = SimTK::dot(next.p - q, inward);
      if (dc >= 0) clip_out.push_back(cur);
      if ((dc > 0 && dn < 0) || (dc < 0 && dn > 0)) {
        const Vec3 x = cur.p + (dc / (dc - dn)) * (next.p - cur.p);
        const std::int32_t id =
            cur.edge & kPlaneEdge
                ? makeFeature(kCorner, reference_b, cur.edge & ~kPlaneEdge,
                              static_cast<std::uint32_t>(k))
                : makeFeature(kEdgeCrossing, reference_b, static_cast<std::uint32_t>(k), cur.edge);
        // Leaving: the new edge runs along plane k. Entering: it continues
        // the edge it came in on.
        const std::uint32_t edge = dc > 0 ? (kPlaneEdge | static_cast<std::uint32_t>(k)) : cur.edge;
        clip_out.push_back({x, id, edge});
      }
    }
    std::swap(clip_in, clip_out);
  }
  const double plane = SimTK::dot(ref.points[0], ref.normal);
  const UnitVec3 normal = reference_b ? -ref.normal : ref.normal;
  for (const ClipVertex& v : clip_in) {
    const double depth = plane - SimTK::dot(v.p, ref.normal);
    if (depth > 0) addPoint(out, v.p + 0.5 * depth * Vec3(ref.normal), normal, depth, v.id);
  }
}

// Clips segment p0-p1 (or the point p0 = p1) to the reference polygon's
// prism; the parts below the reference face are contacts.
void NarrowPhase::Scratch::clipSegment(const Feature& ref, const Vec3& p0, const Vec3& p1,
                                       std::int32_t id0, std::int32_t id1, bool reference_b,
                                       std::vector<ContactPoint>& out) const {
  const Vec3 u = p1 - p0;
  const bool single = u.normSqr() < 1e-30;
  double t0 = 0, t1 = single ? 0 : 1;
  int plane0 = -1, plane1 = -1;  // the side plane that cut each end, if any
  const std::size_t m = ref.points.size();
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3& q = ref.points[k];
    const Vec3 inward = SimTK::cross(Vec3(ref.normal), ref.points[(k + 1) % m] - q);
    const double d0 = SimTK::dot(p0 - q, inward), du = SimTK::dot(u, inward);
    if (std::abs(du) < 1e-300) {
      if (d0 < 0) return;
      continue;
    }
    const double t = -d0 / du;
    if (du > 0) {
      if (t > t0) {
        t0 = t;
        plane0 = static_cast<int>(k);
      }
    } else if (t < t1) {
      t1 = t;
      plane1 = static_cast<int>(k);
    }
    if (t0 > t1) return;
  }
  const double plane = SimTK::dot(ref.points[0], ref.normal);
  const UnitVec3 normal = reference_b ? -ref.normal : ref.normal;
  for (int end = 0; end < 2; ++end) {
    const double t = end == 0 ? t0 : t1;
    if (end == 1 && t1 - t0 < 1e-12) break;
    const Vec3 p = p0 + t * u;
    const double depth = plane - SimTK::dot(p, ref.normal);
    if (depth <= 0) continue;
    const int cut = end == 0 ? plane0 : plane1;
    const std::int32_t id = cut < 0 ? makeFeature(kSegmentEnd, reference_b, 0,
                                                  static_cast<std::uint32_t>(end == 0 ? id0 : id1))
                                    : makeFeature(kSegmentEnd, reference_b, 1 + cut, end);
    addPoint(out, p + 0.5 * depth * Vec3(ref.normal), normal, depth, id);
  }
}

// One point along n: the depth from the shapes' extents along n, the place
// from the features (at a vertex if either side touches with one).
void NarrowPhase::Scratch::addSingle(const ShapeGeometry& a, const Transform& X_A,
                                     const ShapeGeometry& b, const Transform& X_B,
                                     const UnitVec3& n, std::vector<ContactPoint>& out) const {
  const Vec3 nv(n);
  const double depth = SimTK::dot(a.findSupportPoint(X_A, nv) - b.findSupportPoint(X_B, -nv), nv);
  if (depth <= 0) return;
  const Feature& fa = feature_a;
  const Feature& fb = feature_b;
  auto centroid = [](const Feature& f) {
    Vec3 c(0);
    for (const Vec3& p : f.points) c += p;
    return c / static_cast<double>(f.points.size());
  };
  using Kind = Feature::Kind;
  Vec3 point;
  if (fb.kind == Kind::Point) {
    point = fb.points[0] + 0.5 * depth * nv;
  } else if (fa.kind == Kind::Point) {
    point = fa.points[0] - 0.5 * depth * nv;
  } else if (fa.kind == Kind::Segment && fb.kind == Kind::Segment) {
    Vec3 pa, pb;
    findClosestPoints(fa.points[0], fa.points[1] - fa.points[0], fb.points[0],
                      fb.points[1] - fb.points[0], pa, pb);
    point = 0.5 * (pa + pb);
  } else if (fb.kind == Kind::Segment) {
    point = centroid(fb) + 0.5 * depth * nv;
  } else if (fa.kind == Kind::Segment) {
    point = centroid(fa) - 0.5 * depth * nv;
  } else {
    point = 0.5 * (centroid(fa) + centroid(fb));
  }
  addPoint(out, point, n, depth, makeFeature(kSingle, false, 0, 0));
}

void NarrowPhase::Scratch::collideSegments(const Feature& fa, const Feature& fb, const UnitVec3& n,
                                           std::vector<ContactPoint>& out) const {
  const Vec3 a0 = fa.points[0], u = fa.points[1] - a0;
  const Vec3 b0 = fb.points[0], w = fb.points[1] - b0;
  // Directions within the contact plane.
  const Vec3 up = u - SimTK::dot(u, n) * Vec3(n), wp = w - SimTK::dot(w, n) * Vec3(n);
  const double lu = up.norm(), lw = wp.norm();
  if (lu > 1e-12 && lw > 1e-12 &&
      std::abs(SimTK::dot(SimTK::cross(up, wp), n)) < kParallelSin * lu * lw) {
    // Parallel: the ends of the overlap, measured along A's edge.
    const Vec3 e = up / lu;
    const double sb0 = SimTK::dot(b0 - a0, e), sb1 = SimTK::dot(b0 + w - a0, e);
    const double lo = std::max(0.0, std::min(sb0, sb1)), hi = std::min(lu, std::max(sb0, sb1));
    if (lo <= hi && std::abs(sb1 - sb0) > 1e-12) {
      for (int end = 0; end < 2; ++end) {
        const double s = end == 0 ? lo : hi;
        if (end == 1 && hi - lo < 1e-12) break;
        const Vec3 pa = a0 + (s / lu) * u;
        const Vec3 pb = b0 + ((s - sb0) / (sb1 - sb0)) * w;
        const double depth = SimTK::dot(pa - pb, n);
        if (depth > 0)
          addPoint(out, 0.5 * (pa + pb), n, depth, makeFeature(kOverlapEnd, false, 0, end));
      }
      return;
    }
  }
  Vec3 pa, pb;
  findClosestPoints(a0, u, b0, w, pa, pb);
  const double depth = SimTK::dot(pa - pb, n);
  if (depth > 0) addPoint(out, 0.5 * (pa + pb), n, depth, makeFeature(kSingle, false, 0, 0));
}

void NarrowPhase::Scratch::buildManifold(const ShapeGeometry& a, const Transform& X_A,
                                         const ShapeGeometry& b, const Transform& X_B,
                                         const UnitVec3& n, std::vector<ContactPoint>& out) {
  using Kind = Feature::Kind;
  const Feature& fa = feature_a;
  const Feature& fb = feature_b;
  if (fa.kind == Kind::Polygon && fb.kind == Kind::Polygon) {
    const double align_a = SimTK::dot(fa.normal, n), align_b = -SimTK::dot(fb.normal, n);
    if (align_b > align_a + kReferenceBias)
      clipPolygons(fb, fa, true, out);
    else
      clipPolygons(fa, fb, false, out);
  } else if (fa.kind == Kind::Polygon) {
    clipSegment(fa, fb.points.front(), fb.points.back(), fb.ids.front(), fb.ids.back(), false, out);
  } else if (fb.kind == Kind::Polygon) {
    clipSegment(fb, fa.points.front(), fa.points.back(), fa.ids.front(), fa.ids.back(), true, out);
  } else if (fa.kind == Kind::Segment && fb.kind == Kind::Segment) {
    collideSegments(fa, fb, n, out);
  }
  // A vertex, or a point that fell just outside a face: one point along n.
  if (out.empty()) addSingle(a, X_A, b, X_B, n, out);
}

// Keeps the deepest point and then, one at a time, the point farthest
// from those kept (deterministic; only for very large manifolds).
void NarrowPhase::Scratch::thin(std::vector<ContactPoint>& points) {
  const std::size_t n = points.size();
  taken.assign(n, 0);
  spread.assign(n, SimTK::Infinity);
  std::size_t pick = 0;
  for (std::size_t i = 1; i < n; ++i)
    if (points[i].depth > points[pick].depth) pick = i;
  thinned.clear();
  while (thinned.size() < static_cast<std::size_t>(kMaxManifoldPoints)) {
    taken[pick] = 1;
    thinned.push_back(points[pick]);
    std::size_t next = n;
    for (std::size_t i = 0; i < n; ++i) {
      if (taken[i]) continue;
      spread[i] = std::min(spread[i], (points[i].point - points[pick].point).normSqr());
      if (next == n || spread[i] > spread[next]) next = i;
    }
    if (next == n) break;
    pick = next;
  }
  points.swap(thinned);
}

void NarrowPhase::calcContacts(const ShapeGeometry& a, const Transform& X_A, const ShapeGeometry& b,
                               const Transform& X_B, std::vector<ContactPoint>& out) {
  out.clear();
  Scratch& s = *scratch_;
  if (a.kind == ShapeKind::HalfSpace || b.kind == ShapeKind::HalfSpace) {
    if (a.kind == ShapeKind::HalfSpace) {
      s.collideHalfSpace(X_A, b, X_B, out);
    } else {
      s.collideHalfSpace(X_B, a, X_A, out);
      for (ContactPoint& c : out) c.normal = -c.normal;
    }
  } else if ((a.kind == ShapeKind::Sphere || a.kind == ShapeKind::Capsule) &&
             (b.kind == ShapeKind::Sphere || b.kind == ShapeKind::Capsule)) {
    s.collideCapsules(a.radius, a.half_length, X_A, b.radius, b.half_length, X_B, out);
  } else {
    UnitVec3 n;
    if (!s.findNormal(a, X_A, b, X_B, n)) return;
    calcFeature(a, X_A, Vec3(n), s.feature_a);
    calcFeature(b, X_B, -Vec3(n), s.feature_b);
    // Against a face, the other side's feature is taken along the face
    // normal: a sphere then touches at its true lowest point even where
    // FCL's normal leans a little.
    using Kind = Feature::Kind;
    if (s.feature_a.kind == Kind::Polygon && s.feature_b.kind != Kind::Polygon)
      calcFeature(b, X_B, -Vec3(s.feature_a.normal), s.feature_b);
    else if (s.feature_b.kind == Kind::Polygon && s.feature_a.kind != Kind::Polygon)
      calcFeature(a, X_A, -Vec3(s.feature_b.normal), s.feature_a);
    s.buildManifold(a, X_A, b, X_B, n, out);
  }
  if (out.size() > static_cast<std::size_t>(kMaxManifoldPoints)) s.thin(out);
}

}  // namespace scene_detail
}  // namespace manibench
