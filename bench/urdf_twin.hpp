// URDF to MJCF for the MuJoCo twin of a manibench scene (cabinet_twin.hpp).
//
// The URDF is read with urdfdom, the parser manibench's scene uses, so both
// engines start from the same numbers. The subset is what the cabinet tasks
// load: links with <inertial>, box, sphere and cylinder collisions (a
// cylinder with a sphere of its radius on each end becomes one MuJoCo
// capsule: the same solid), revolute, continuous, prismatic and fixed
// joints. Anything else is refused with the element's name. Joint limits,
// damping, Coulomb friction and effort limits are taken from the
// manibench scene itself (JointDescription), which may override the URDF
// (the cabinet tasks draw damping and friction per episode).
//
// In MJCF every URDF link is a body named "<articulation>/<link>" (a fixed
// joint welds it to its parent), every movable joint a joint named
// "<articulation>/<joint>", every driven joint a `general` actuator of the
// same name with an affine bias, so that one actuator carries manibench's
// whole drive law (setDrive below).
#pragma once

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "manibench/scene.hpp"

namespace manibench::bench {

// A collision primitive in its link's frame; cylinders and capsules run
// along z of `pose`.
struct TwinGeom {
  enum class Kind { Box, Sphere, Cylinder, Capsule };
  Kind kind = Kind::Box;
  // Box: half extents; Sphere: (radius, 0, 0); Cylinder and Capsule:
  // (radius, half length of the axis segment, 0).
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

// The lowest z of the geometry when its link's frame is at X_GL.
double calcLowestZ(const TwinGeom& geom, const Eigen::Isometry3d& X_GL);

struct TwinLink {
  enum class Joint { Root, Fixed, Revolute, Prismatic };  // continuous: Revolute
  std::string name;
  int parent = -1;  // index into TwinArticulation::links; -1 for the root
  Joint joint = Joint::Root;
  std::string joint_name;
  // The joint frame (= this link's frame) in the parent link's frame, and
  // the joint axis in it (unit length).
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  double mass = 0;  // 0: no <inertial>
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // about com, link axes
  std::vector<TwinGeom> geoms;
};

struct TwinArticulation {
  std::string name;
  std::vector<TwinLink> links;  // parents before children
  int findLink(const std::string& link) const;  // -1 if none
};

// Throws std::invalid_argument naming `what` and the element at fault.
TwinArticulation parseTwinArticulation(const std::string& urdf, const std::string& name,
                                       const std::string& what);

// One articulation as the twin places it, with the contact parameters its
// geoms get (see cabinet_twin.cpp for how they reproduce manibench's
// per-pair friction).
struct TwinPlacement {
  TwinArticulation articulation;
  Eigen::Isometry3d root = Eigen::Isometry3d::Identity();
  bool fixed_base = true;
  // Movable joints as manibench simulates them, looked up by name.
  std::vector<JointDescription> joints;
  std::vector<double> link_friction;  // per link: MuJoCo friction of its geoms
  std::vector<int> link_priority;     // per link: MuJoCo geom priority
  std::vector<double> floor_friction;  // per link: its contact with the floor
};

struct TwinMjcfOptions {
  double timestep = 0.002;
  std::string integrator = "implicit";
  bool floor = true;  // the plane z = 0
  // Driven joints, (placement index, joint name), in actuator order.
  std::vector<std::pair<int, std::string>> actuated;
};

std::string toTwinMjcf(const std::vector<TwinPlacement>& placements,
                       const TwinMjcfOptions& options);

// manibench's drive law on actuator `i` (made by toTwinMjcf):
// tau = kp (q* - q) + kd (v* - qdot) + f, clamped to the effort limit, as
// ctrl = kp q* + kd v* + f with bias (0, -kp, -kd). The gains live in the
// model, which MuJoCo lets a caller change between steps.
void setDrive(mjModel* m, mjData* d, int actuator, const DriveCommand& command);

}  // namespace manibench::bench
