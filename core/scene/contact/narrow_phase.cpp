// The narrow phase: closed-form pairs (half spaces, capsules), the contact
// normal of general convex pairs (FCL's GJK/EPA, refined), and the
// dispatch in calcContacts. Manifolds: contact_manifold.cpp.
#include <fcl/narrowphase/detail/primitive_shape_algorithm/box_box.h>

#include <cassert>

#include "contact/narrow_phase_impl.hpp"

namespace manibench {
namespace scene_detail {

NarrowPhase::NarrowPhase() : impl_(std::make_unique<Impl>()) {}
NarrowPhase::~NarrowPhase() = default;

void NarrowPhase::Impl::collideHalfSpace(const Transform& X_H, const ShapeGeometry& g,
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
void NarrowPhase::Impl::collideCapsules(double ra, double la, const Transform& X_A, double rb,
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
bool NarrowPhase::Impl::findNormal(const ShapeGeometry& a, const Transform& X_A,
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
int NarrowPhase::Impl::findCoreNormal(const ShapeGeometry& a, const Transform& X_A,
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
void NarrowPhase::Impl::refineNormal(const ShapeGeometry& a, const Transform& X_A,
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

bool NarrowPhase::Impl::orientNormal(const ShapeGeometry& a, const Transform& X_A,
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

void NarrowPhase::calcContacts(const ShapeGeometry& a, const Transform& X_A, const ShapeGeometry& b,
                               const Transform& X_B, std::vector<ContactPoint>& out) {
  out.clear();
  Impl& s = *impl_;
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
