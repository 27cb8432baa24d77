#include "contact/contact_features.hpp"

#include <cassert>

namespace manibench {
namespace scene_detail {
namespace contact_math {

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

}  // namespace contact_math
}  // namespace scene_detail
}  // namespace manibench
