// Convex hulls of collision meshes: contact treats every mesh as its convex
// hull (like MuJoCo), which keeps narrow phase cheap and manifolds stable.
//
// The hull is computed with Qhull (libqhull_r, Debian's reentrant C library)
// rather than FCL: FCL's Convex only stores a hull, it cannot compute one.
// Qhull merges coplanar facets, so a face is a real planar polygon (a box
// mesh gives 6 quads, not 12 triangles), which the manifold builder clips
// face against face.
#pragma once

#include <manibench/error.hpp>

#include <memory>
#include <string>
#include <vector>

#include "Simbody.h"
#include "manibench/scene.hpp"

namespace fcl {
template <typename S>
class CollisionGeometry;
}  // namespace fcl

namespace manibench {
namespace scene_detail {

struct ConvexHull {
  struct Face {
    SimTK::UnitVec3 normal;     // outward
    double offset = 0;          // normal . x = offset on the face plane
    std::vector<int> vertices;  // counterclockwise seen from outside
  };
  std::vector<SimTK::Vec3> vertices;
  std::vector<Face> faces;
  std::vector<std::vector<int>> vertex_faces;      // faces around a vertex
  std::vector<std::vector<int>> vertex_neighbors;  // vertices sharing an edge

  // Solid of unit density: volume (= mass), centroid and the inertia about
  // the centroid, in the hull frame.
  double volume = 0;
  SimTK::Vec3 centroid{0};
  SimTK::Mat33 unit_inertia{0, 0, 0, 0, 0, 0, 0, 0, 0};

  // Axis-aligned box around the vertices and the radius of the sphere about
  // the frame origin that holds them all (for the broad phase).
  SimTK::Vec3 box_center{0}, box_half{0};
  double bounding_radius = 0;

  // The same hull for FCL's GJK/EPA.
  std::shared_ptr<const fcl::CollisionGeometry<double>> fcl_geometry;

  // The vertex farthest along `d` (hull frame); ties go to the lowest index.
  int findSupportVertex(const SimTK::Vec3& d) const;
};

// Thrown for input that has no 3-d hull (fewer than 4 points, all on a
// plane or a line); the caller decides whether that is an error.
class FlatHullError : public Error {
 public:
  using Error::Error;
};

// Hull of `points`. Throws FlatHullError for degenerate input and
// std::runtime_error if Qhull fails otherwise.
std::shared_ptr<const ConvexHull> calcConvexHull(const std::vector<SimTK::Vec3>& points);

// Loads every vertex of a mesh file (anything assimp reads: OBJ, STL, DAE,
// ...) with node transforms applied, each coordinate multiplied by `scale`.
// Collada files keep their authored axes (the <up_axis> is ignored, as ROS
// tools do) and their <unit>. Throws std::runtime_error with assimp's reason.
std::vector<SimTK::Vec3> loadMeshVertices(const std::string& path, const SimTK::Vec3& scale);

// Both loaders below read a file once per process: results are cached by
// path, scale, file size and modification time (episodes rebuild scenes
// from the same files; assimp's reading was 80 % of a cabinet reset), and
// a file changed on disk is read again.

// Triangle lists of a mesh file for the renderer, one per sub-mesh, read
// with the same conventions as loadMeshVertices: positions scaled, normals
// (generated where the file has none) unit length, color and texture from
// the sub-mesh's material. Throws std::runtime_error with assimp's reason
// or if the file has no triangles.
std::shared_ptr<const std::vector<VisualMesh>> loadVisualMeshes(const std::string& path,
                                                                const SimTK::Vec3& scale);

// The thickness a collision mesh's hull gets at least, m. PartNet-Mobility
// models panels (a cabinet's back, shelves, drawer bottoms: 9 to 23 meshes
// in 6 of 8 cabinets, 70 of the oven's 92) as single planar surfaces, which
// have no convex solid; they carry contact (a drawer's bottom holds what is
// in it, a back panel stops the gripper), so they become solids this thick,
// centred on their plane. 1 cm: the thickness of real furniture panels, and
// 20 times the contact's depth under the gripper's squeeze (100 N over 4
// points at 1e5 N/m in series: 0.25 mm), so GJK/EPA never sees a contact
// through the whole solid.
constexpr double kMinHullThickness = 0.01;

// `points` with every principal direction (of their covariance) along which
// they span less than `thickness` padded to exactly `thickness`: the points
// shifted by +-(thickness - extent) / 2 along it. A plane becomes a slab, a
// line a bar, a point a cube; points that span `thickness` in every
// principal direction come back unchanged.
std::vector<SimTK::Vec3> padThinPoints(const std::vector<SimTK::Vec3>& points, double thickness);

// loadMeshVertices + padThinPoints(kMinHullThickness) + calcConvexHull: a
// flat or nearly flat mesh gives a thin solid, never a FlatHullError.
std::shared_ptr<const ConvexHull> loadConvexHull(const std::string& path, const SimTK::Vec3& scale);

}  // namespace scene_detail
}  // namespace manibench
