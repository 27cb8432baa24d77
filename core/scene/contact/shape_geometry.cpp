// ShapeGeometry: the collision shapes' factories (with their FCL
// geometry), bounding boxes and support points.
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>

#include "contact/contact_math.hpp"

namespace manibench {
namespace scene_detail {

using namespace contact_math;

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

namespace {

// A capsule or a cylinder: a radius about the local z axis, a half length
// along it.
ShapeGeometry makeAxial(ShapeKind kind, double radius, double half_length) {
  ShapeGeometry g;
  g.kind = kind;
  g.radius = radius;
  g.half_length = half_length;
  return g;
}

}  // namespace

ShapeGeometry ShapeGeometry::makeCapsule(double radius, double half_length) {
  ShapeGeometry g = makeAxial(ShapeKind::Capsule, radius, half_length);
  g.fcl_geometry = std::make_shared<fcl::Capsuled>(radius, 2 * half_length);
  g.fcl_core = std::make_shared<fcl::Capsuled>(0.0, 2 * half_length);
  return g;
}

ShapeGeometry ShapeGeometry::makeCylinder(double radius, double half_length) {
  ShapeGeometry g = makeAxial(ShapeKind::Cylinder, radius, half_length);
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

}  // namespace scene_detail
}  // namespace manibench
