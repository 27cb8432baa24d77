// Contact manifolds: the two shapes' features along the contact normal
// clipped against each other (polygons, segments, single points), and
// thinning of large manifolds.
#include <cassert>

#include "contact/narrow_phase_impl.hpp"

namespace manibench {
namespace scene_detail {

void NarrowPhase::Impl::clipPolygons(const Feature& ref, const Feature& inc, bool reference_b,
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
void NarrowPhase::Impl::clipSegment(const Feature& ref, const Vec3& p0, const Vec3& p1,
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
void NarrowPhase::Impl::addSingle(const ShapeGeometry& a, const Transform& X_A,
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

void NarrowPhase::Impl::collideSegments(const Feature& fa, const Feature& fb, const UnitVec3& n,
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

void NarrowPhase::Impl::buildManifold(const ShapeGeometry& a, const Transform& X_A,
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
void NarrowPhase::Impl::thin(std::vector<ContactPoint>& points) {
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

}  // namespace scene_detail
}  // namespace manibench
