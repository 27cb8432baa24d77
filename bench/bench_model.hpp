// An engine-neutral description of a benchmark scene, written once and
// turned into URDF (for manibench::Scene) and MJCF (for MuJoCo), so that both
// engines simulate the same masses, inertias, joint frames, limits, damping,
// shapes, friction and drive gains by construction.
//
// Conventions (the subset of URDF and MJCF both read the same way):
// - Link frames are never rotated: a joint's frame sits at `origin` in the
//   parent link's frame with the parent's orientation, and the child link's
//   frame is the joint frame.
// - Inertia is principal about the centre of mass, axes along the link frame.
// - Links of one articulation never touch each other (manibench's contact
//   cliques; explicit <exclude> pairs in MJCF).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace manibench::bench {

struct Shape {
  enum class Kind { Box, Sphere };
  Kind kind = Kind::Box;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // in the link frame
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();  // boxes
  double radius = 0;                                       // spheres

  static Shape box(const Eigen::Vector3d& half, const Eigen::Vector3d& at = Eigen::Vector3d::Zero());
  static Shape sphere(double radius, const Eigen::Vector3d& at = Eigen::Vector3d::Zero());
};

struct Link {
  enum class Joint { Root, Revolute, Prismatic };
  std::string name;
  int parent = -1;  // index into Articulation::links; -1 for the root
  Joint joint = Joint::Root;
  std::string joint_name;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // joint frame in parent
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  bool limited = false;
  double lower = 0, upper = 0;
  double damping = 0;  // N s/m or N m s/rad
  double effort = 0;   // drive force limit; 0: unlimited
  double mass = 1;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Vector3d inertia = Eigen::Vector3d::Constant(1e-3);  // about com
  std::vector<Shape> shapes;
};

struct Articulation {
  std::string name;
  bool fixed_base = true;
  Eigen::Vector3d root_position = Eigen::Vector3d::Zero();
  std::vector<Link> links;  // links[0] is the root; parents come first
};

// tau = stiffness (q_target - q) + damping (v_target - qdot), clamped to the
// joint's effort limit; `balanced` adds inverse-dynamics cancelling of
// gravity and Coriolis forces on the joint (manibench's passive force
// balancing, supplement B.7).
struct Drive {
  int articulation = 0;
  std::string joint;
  double stiffness = 0;
  double damping = 0;
  bool balanced = false;
};

struct DriveTarget {
  double position = 0;
  double velocity = 0;
};

struct Model {
  std::string name;
  bool ground = false;  // a floor at z = 0
  double friction = 0.8;  // one Coulomb coefficient for every contact
  std::vector<Articulation> articulations;
  std::vector<Drive> drives;
  // Initial joint positions by (articulation, joint name); others start at 0.
  struct InitialJoint {
    int articulation;
    std::string joint;
    double position;
  };
  std::vector<InitialJoint> initial_joints;

  // All shapes of all links (sizes MuJoCo's contact buffers).
  int countShapes() const;
};

// One URDF document for an articulation (its root pose is not part of it).
std::string toUrdf(const Articulation& articulation);

struct MjcfOptions {
  double timestep = 0.002;
  std::string integrator = "Euler";  // MuJoCo's "Euler" or "implicit"
};
// One MJCF document for the whole model; bodies and joints are named
// "<articulation>/<link or joint>".
std::string toMjcf(const Model& model, const MjcfOptions& options);
std::string mjcfName(const Articulation& articulation, const std::string& name);

}  // namespace manibench::bench
