// The part of a shape's surface that is extreme along a direction (a point,
// a segment or a polygon), from which the narrow phase clips its manifolds.
// Internal to core/scene/contact.
#pragma once

#include "contact/contact_math.hpp"

namespace manibench {
namespace scene_detail {
namespace contact_math {

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
void calcFeature(const ShapeGeometry& g, const Transform& X, const Vec3& d, Feature& f);

}  // namespace contact_math
}  // namespace scene_detail
}  // namespace manibench
