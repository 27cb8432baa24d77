// URDF -> an articulation description ready to become Simbody bodies.
//
// Parsing and validation happen here, before anything touches the
// MultibodySystem, so that a rejected URDF leaves the scene unchanged. Links
// joined by fixed joints are merged into one body: their mass properties are
// summed and their collision shapes re-expressed in that body's frame.
#pragma once

#include <string>
#include <vector>

#include "Simbody.h"
#include "manibench/scene.hpp"

namespace manibench {
namespace scene_detail {

struct CollisionShape {
  enum class Kind { Sphere, Box };
  Kind kind = Kind::Sphere;
  SimTK::Vec3 size{0};     // radius in [0] (sphere) or half extents (box)
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
  // Mass properties about the body origin, in the body frame. Zero mass
  // means "no inertial and no geometry to derive one from".
  double mass = 0;
  SimTK::Vec3 first_moment{0};  // mass * center of mass
  SimTK::Inertia inertia{0};
  std::vector<CollisionShape> shapes;
};

struct ArticulationModel {
  std::string source;  // file path, or "<string>" for addUrdfString
  std::vector<LinkModel> links;     // depth first from the root
  std::vector<BodyModel> bodies;    // parents before children
  std::vector<JointDescription> joints;
  // Collision geometry that exists in the URDF but is not simulated yet
  // ("link 'x': cylinder 'name'"), reported once when the URDF is added.
  std::vector<std::string> unsimulated;
};

// Parses `urdf_xml` and builds the description. `source` names the origin
// in error messages. Throws SceneError on malformed XML, URDF errors,
// unsupported joint types or invalid inertias.
ArticulationModel buildArticulationModel(const std::string& urdf_xml,
                                         const std::string& source,
                                         double default_density);

}  // namespace scene_detail
}  // namespace manibench
