// URDF -> an articulation description ready to become Simbody bodies.
//
// Parsing and validation happen here, before anything touches the
// MultibodySystem, so that a rejected URDF leaves the scene unchanged. Links
// joined by fixed joints are merged into one body: their mass properties are
// summed and their collision shapes re-expressed in that body's frame.
// Links without <inertial> get mass from their collision volume (a mesh from
// its convex hull) at the default density. A planar joint becomes a chain of
// three one-dof joints through two massless bodies; mimic joints name their
// leader's index. Visuals are kept per link (not merged) for the renderer.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "Simbody.h"
#include "manibench/scene.hpp"
#include "contact/contact_geometry.hpp"

namespace manibench {
namespace scene_detail {

struct CollisionShape {
  ShapeGeometry geometry;  // capsules and cylinders along z of the shape frame
  SimTK::Transform X_BS;   // shape frame in the body frame
  int link = -1;           // articulation-local link index
};

struct LinkModel {
  std::string name;
  int body = -1;           // articulation-local body index
  SimTK::Transform X_BL;   // link frame in the body frame (merged offsets)
};

// One rigid body: the link a movable joint (or the root) creates, plus every
// link hanging below it on fixed joints. Its frame is that link's frame.
struct BodyModel {
  int parent = -1;         // body index; -1 for the root body
  int joint = -1;          // index into ArticulationModel::joints; -1: root
  int link = -1;           // the link that defines the body frame
  // Joint frame (URDF joint origin) in the parent body frame and the joint
  // axis in that frame, unit length.
  SimTK::Transform X_PJ;
  SimTK::UnitVec3 axis{1, 0, 0};
  // An intermediate body of a planar joint's chain: no mass of its own
  // (Simbody's Body::Massless; the child body carries the mass).
  bool massless = false;
  // Mass properties about the body origin, in the body frame. Zero mass
  // means "no inertial and no geometry to derive one from".
  double mass = 0;
  SimTK::Vec3 first_moment{0};  // mass * center of mass
  SimTK::Inertia inertia{0};    // set from inertia_sum by checkBodyMasses
  // The parts' inertias summed about the body origin, unchecked: a link
  // welded on over a fixed joint may have moments that are invalid alone
  // (a camera's 8.7e-6 + 6.7e-4 < 1.4e-3) and fine merged; only the
  // body's sum must be a valid inertia. `invalid_part` describes the first
  // part that was invalid alone ("" if none), for the error.
  SimTK::SymMat33 inertia_sum{0};
  std::string invalid_part;
  std::vector<CollisionShape> shapes;
};

struct ArticulationModel {
  std::string source;  // file path, or "<string>" for addUrdfString
  std::vector<LinkModel> links;     // depth first from the root
  std::vector<BodyModel> bodies;    // parents before children
  std::vector<JointDescription> joints;
  // Every <visual>, with `link` the articulation-local link index.
  std::vector<VisualShape> visuals;
  // Collision geometry that exists in the URDF but is not simulated (an
  // unknown geometry type: "link 'x': collision 'name' (why)"), reported
  // once when the URDF is added.
  std::vector<std::string> unsimulated;
  // Every mesh file read (collision and visual), in the order first read:
  // what an evaluation's certificate hashes (Scene::getSourceDigests).
  std::vector<std::string> mesh_files;
};

// Parses `urdf_xml` and builds the description. `source` names the origin
// in error messages; relative mesh paths start at `base_dir`. Collision
// meshes become their convex hulls. `<capsule radius length>` (which
// urdfdom does not know) is accepted as a z-axis capsule of that cylinder
// length plus two hemispheres. Throws SceneError on malformed XML, URDF
// errors, unreadable meshes, floating joints inside the tree, mimics of
// unknown joints or invalid inertias.
// Mesh files are read through the process-wide caches of
// contact/convex_hull.hpp.
ArticulationModel buildArticulationModel(const std::string& urdf_xml,
                                         const std::string& source,
                                         const std::string& base_dir,
                                         double default_density,
                                         double default_joint_damping = 0);

// Where a URDF mesh filename points: an absolute path, file://,
// package://NAME/rest (looked up in ROS_PACKAGE_PATH, then in an ancestor
// of `base_dir` named NAME, then as base_dir/NAME/rest, PyBullet's
// convention, then as base_dir/rest), or a path relative to `base_dir`
// (docs/urdf.md). Returns the first existing candidate, or "" if none
// exists; `tried` (may be null) gets every candidate in order.
std::string findMeshFile(const std::string& filename, const std::string& base_dir,
                         std::vector<std::string>* tried = nullptr);
// "not found; tried: a, b, c" for a mesh that findMeshFile did not find.
std::string describeMissingMesh(const std::string& filename, const std::string& base_dir);

}  // namespace scene_detail
}  // namespace manibench
