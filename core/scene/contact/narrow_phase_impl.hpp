// NarrowPhase::Impl: the narrow phase's buffers and its stages, shared by
// narrow_phase.cpp (closed-form pairs, the contact normal, calcContacts)
// and contact_manifold.cpp (features clipped into a manifold, thinning).
// Internal to core/scene/contact.
#pragma once

#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include "contact/contact_features.hpp"

namespace manibench {
namespace scene_detail {

using namespace contact_math;

struct NarrowPhase::Impl {
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

  Impl() {
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

}  // namespace scene_detail
}  // namespace manibench
