// What the contact geometry's translation units share (shape_geometry.cpp,
// contact_features.cpp, narrow_phase.cpp, contact_manifold.cpp): the
// thresholds of feature selection, contact point ids, and small vector
// helpers. Internal to core/scene/contact.
#pragma once

#include <fcl/common/types.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "contact/contact_geometry.hpp"

namespace manibench {
namespace scene_detail {
namespace contact_math {

using SimTK::Rotation;
using SimTK::Transform;
using SimTK::UnitVec3;
using SimTK::Vec3;

// A face counts as facing a direction within ~8 degrees, an edge as lying
// across it within ~8 degrees. Outside these the feature is a single vertex.
// Points of a face or edge that do not penetrate are dropped anyway, so the
// exact values only matter for which features get clipped.
inline constexpr double kFaceCos = 0.990;
inline constexpr double kEdgeSin = 0.139;
// Two edges (or capsule axes) closer to parallel than this give two points.
inline constexpr double kParallelSin = 0.02;
inline constexpr double kParallelCos = 0.9998;
// The reference face is A's unless B's faces the normal better by this
// much: a hysteresis against flipping between nearly parallel faces (which
// would renumber the points and drop their friction anchors).
inline constexpr double kReferenceBias = 1e-3;
// How far the overlap along FCL's normal may exceed FCL's depth before the
// normal is taken for a failure. EPA on curved surfaces is off by up to a
// few tenths of a millimetre (then refined); a failed EPA is off by the
// size of the shapes.
inline constexpr double kDepthSlack = 1e-3;
// A tilted cylinder rim switches from the polygon to its exact deepest
// point between these sines of the tilt angle (about 1 and 6 degrees).
inline constexpr double kRimBlendStart = 0.02;
inline constexpr double kRimBlendEnd = 0.10;

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
inline std::int32_t makeFeature(std::uint32_t kind, bool reference_b, std::uint32_t x, std::uint32_t y) {
  // 31 bits: kind (3) | reference_b (1) | x (12) | y (15). Collisions in
  // degenerate cases only cost a friction anchor, which the distance check
  // of the matcher catches.
  return static_cast<std::int32_t>(((kind & 7u) << 28) | ((reference_b ? 1u : 0u) << 27) |
                                   ((x & 0xFFFu) << 15) | (y & 0x7FFFu));
}

inline double sign(double x) { return x >= 0 ? 1.0 : -1.0; }

inline double smoothstep(double x) {
  x = std::min(1.0, std::max(0.0, x));
  return x * x * (3 - 2 * x);
}

inline fcl::Transform3d toFcl(const Transform& X) {
  fcl::Transform3d T = fcl::Transform3d::Identity();
  const SimTK::Mat33& R = X.R().asMat33();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) T.linear()(i, j) = R(i, j);
  T.translation() = fcl::Vector3d(X.p()[0], X.p()[1], X.p()[2]);
  return T;
}

// Unit vector along the part of `d` perpendicular to unit `a`; false if
// `d` is (nearly) parallel to `a`.
inline bool findPerpendicular(const Vec3& d, const Vec3& a, Vec3& out, double* length = nullptr) {
  const Vec3 s = d - SimTK::dot(d, a) * a;
  const double n = s.norm();
  if (length != nullptr) *length = n;
  if (n < 1e-12) return false;
  out = s / n;
  return true;
}

// Closest points of segments p0 + s u (s in [0,1]) and q0 + t w (t in [0,1]).
inline void findClosestPoints(const Vec3& p0, const Vec3& u, const Vec3& q0, const Vec3& w, Vec3& p,
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
inline Vec3 boxCorner(const Vec3& half, int code) {
  return Vec3(code & 1 ? half[0] : -half[0], code & 2 ? half[1] : -half[1],
              code & 4 ? half[2] : -half[2]);
}

inline Vec3 rimPoint(double radius, double z, int k) {
  const double angle = 2 * SimTK::Pi * k / kCylinderRimPoints;
  return Vec3(radius * std::cos(angle), radius * std::sin(angle), z);
}

inline void addPoint(std::vector<ContactPoint>& out, const Vec3& point, const UnitVec3& normal,
              double depth, std::int32_t feature, double weight = 1) {
  ContactPoint c;
  c.point = point;
  c.normal = normal;
  c.depth = depth;
  c.weight = weight;
  c.feature = feature;
  out.push_back(c);
}

}  // namespace contact_math
}  // namespace scene_detail
}  // namespace manibench
