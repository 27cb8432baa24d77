// The physics scene: articulations loaded from URDF into one Simbody
// multibody system, stepped in control ticks, queried by tasks, controllers
// and (later) the renderer. Simbody stays behind a pimpl so that code which
// includes this header needs neither Simbody's headers nor its no-NDEBUG rule.
#pragma once

#include <manibench/error.hpp>
#include <manibench/geometry.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace manibench {

enum class JointType { Revolute = 1, Continuous = 2, Prismatic = 3 };

// A movable one-dof joint. Fixed joints are merged into the parent body; a
// floating root is reached through the root pose, not the joint vector. A
// URDF planar joint NAME becomes three joints in a row: NAME_x and NAME_y
// (prismatic along two orthonormal in-plane directions; x and y for a z
// axis) and NAME_yaw (continuous about the axis).
struct JointDescription {
  std::string name;
  JointType type = JointType::Revolute;
  int index = 0;  // position in the articulation's joint vector
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  double velocity_limit = 0;  // 0: unknown
  double effort_limit = 0;    // 0: unlimited
  double damping = 0;         // from URDF <dynamics>, overridable per episode
  double friction = 0;        // Coulomb, from URDF <dynamics>
  // URDF <mimic>: a constraint holds q = multiplier * q[mimic] + offset,
  // `mimic` being the leader's index in the same joint vector (-1: none).
  // The follower stays in the joint vector; drive the leader, not it.
  int mimic = -1;
  double mimic_multiplier = 1;
  double mimic_offset = 0;
};

// One sub-mesh of a visual mesh file, ready for the renderer: triangles in
// the mesh frame with the URDF scale applied, unit normals per vertex.
struct VisualMesh {
  std::vector<Eigen::Vector3f> positions, normals;
  // Per vertex (u, v) of the file's first texture coordinate set, as the
  // file has them: v up (0 is the image's bottom row, OBJ's convention),
  // often outside [0, 1] (the texture repeats). Empty when it has none.
  std::vector<Eigen::Vector2f> texture_coords;
  std::vector<std::uint32_t> indices;  // three per triangle, counterclockwise
  Eigen::Vector4f color = Eigen::Vector4f::Ones();  // the sub-mesh material's diffuse rgba
  std::string texture;  // diffuse texture path (relative ones resolved), or ""
};

// A URDF <visual>. Primitives are centred on the shape frame; cylinders and
// capsules run along its z axis.
struct VisualShape {
  enum class Kind { Box, Sphere, Cylinder, Capsule, Mesh };
  int link = -1;     // global link id (as findLink); merged links keep theirs
  std::string name;  // the <visual name>, or ""
  Kind kind = Kind::Box;
  // Box: full extents; Sphere: (radius, 0, 0); Cylinder and Capsule:
  // (radius, length, 0), the capsule's length without its end caps.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Pose pose_in_link;  // the <visual><origin>
  // The URDF <material> color (inline, or a robot-level material named by
  // the visual); has_material is false where the visual names none, and
  // then a mesh's own sub-mesh colors apply and color is white.
  Eigen::Vector4f color = Eigen::Vector4f::Ones();
  bool has_material = false;
  std::string material_name;
  std::string texture;  // the URDF material's <texture filename>, as written
  // Mesh kind: the resolved file, its scale, and its sub-meshes (shared by
  // every visual of the scene that uses the same file and scale).
  std::string mesh_file;
  Eigen::Vector3d mesh_scale = Eigen::Vector3d::Ones();
  std::shared_ptr<const std::vector<VisualMesh>> meshes;
};

// The contact properties of a body's surface. Two surfaces in contact
// combine: stiffness in series (k1 k2 / (k1 + k2), so two default surfaces
// give 1e5 N/m per contact point), dissipation weighted by compliance
// ((c1 k2 + c2 k1) / (k1 + k2)), and each friction coefficient by geometric
// mean (sqrt(mu1 mu2)).
struct ContactMaterial {
  // Per contact point: fn = k d (1 + 1.5 c ddot) at penetration d (Hunt-
  // Crossley). A box face resting on a face touches at 4 points.
  double stiffness = 2e5;      // N/m, this surface alone
  double dissipation = 5.0;    // s/m
  double static_friction = 0.8;
  double dynamic_friction = 0.6;  // <= static_friction
  double viscous_friction = 0.0;  // s/m: mu = dynamic + viscous * slip speed
};

// How a scene's equations of motion are integrated (docs/performance.md
// compares them).
enum class Integrator {
  // Fixed step `implicit_step`, linearly implicit Euler: the stiff forces
  // (drives, joint damping, friction and limit stops, contact springs and
  // dampers) enter the step through their analytic derivatives, so the
  // cost of a step does not depend on how stiff or jerky they are.
  ImplicitEuler,
  // CPODES (BDF, Newton): implicit, error-controlled; cost grows with
  // discontinuities (jerky commands) and with the square of the body count.
  CPodes,
  // Runge-Kutta-Merson: explicit, error-controlled (smooth motion; with
  // contact it needs accuracy 1e-4 or it rings).
  RkMerson,
  // Fixed step `fixed_step`, semi-explicit Euler: stiff joint drives need
  // h < 2 I / damping.
  SemiExplicitEuler,
};
// "implicit_euler", "cpodes", "rk_merson", "semi_explicit_euler".
const char* getIntegratorName(Integrator integrator);
// The inverse of getIntegratorName; throws SceneError naming the choices.
Integrator parseIntegrator(const std::string& name);

struct PhysicsSettings {
  double gravity_z = -9.81;
  Integrator integrator = Integrator::ImplicitEuler;
  double implicit_step = 2e-3;  // s, implicit_euler
  double accuracy = 1e-2;    // cpodes, rk_merson
  double fixed_step = 5e-4;  // s, semi_explicit_euler
  // Material of every link until Scene::setContactMaterial says otherwise,
  // and of the ground unless Scene::setGroundMaterial does.
  ContactMaterial default_material;
  // Stiction: each contact point is held by a tangential spring-damper up
  // to mu_static * fn (so a box on a slope does not creep).
  double friction_stiffness = 1e5;  // N/m per contact point
  double friction_damping = 20;     // N s/m per contact point
  // Density that gives mass to links with collision geometry but no
  // <inertial> (as in PartNet-Mobility), kg/m^3.
  double default_density = 1000;
  // Any generalized speed above this (rad/s or m/s) counts as divergence.
  double divergence_speed_limit = 1e3;
  // Damping of joints whose URDF has no <dynamics> (N m s/rad or N s/m):
  // published hands and arms often have none, and their light links are
  // then undamped.
  double default_joint_damping = 0;
};

// Counters of integrator work (Simbody's Integrator statistics, summed).
struct IntegratorStatistics {
  std::int64_t steps = 0;             // accepted internal steps
  std::int64_t attempts = 0;          // tried steps, failed ones included
  std::int64_t realizations = 0;      // evaluations of the equations of motion
  std::int64_t iterations = 0;        // Newton iterations (implicit integrators)
  std::int64_t jacobians = 0;         // difference-quotient Jacobians (cpodes)
  std::int64_t projections = 0;       // constraint projections
  std::int64_t error_test_failures = 0;
  std::int64_t convergence_test_failures = 0;
  std::int64_t initializations = 0;   // restarts (resets, setters)

  IntegratorStatistics& operator+=(const IntegratorStatistics& o) {
    steps += o.steps;
    attempts += o.attempts;
    realizations += o.realizations;
    iterations += o.iterations;
    jacobians += o.jacobians;
    projections += o.projections;
    error_test_failures += o.error_test_failures;
    convergence_test_failures += o.convergence_test_failures;
    initializations += o.initializations;
    return *this;
  }
  IntegratorStatistics& operator-=(const IntegratorStatistics& o) {
    steps -= o.steps;
    attempts -= o.attempts;
    realizations -= o.realizations;
    iterations -= o.iterations;
    jacobians -= o.jacobians;
    projections -= o.projections;
    error_test_failures -= o.error_test_failures;
    convergence_test_failures -= o.convergence_test_failures;
    initializations -= o.initializations;
    return *this;
  }
};

// How an articulation was added: its URDF text, the folder its relative
// mesh paths start at, its root pose and whether that root is fixed. Read
// by tools that rebuild the same scene in another engine (bench/).
struct ArticulationSource {
  std::string urdf;
  std::string base_dir;
  Pose root;
  bool fixed_base = false;
};

// Bad input (malformed URDF, unknown name, wrong vector size, misuse of the
// build/run phases). The message names the file, link or joint at fault.
class SceneError : public Error {
 public:
  using Error::Error;
};

// The state became NaN or exploded; the message names the body and the time.
class SimulationDiverged : public Error {
 public:
  SimulationDiverged(const std::string& message, std::string body, double time)
      : Error(message), body_(std::move(body)), time_(time) {}
  const std::string& body() const { return body_; }
  double time() const { return time_; }

 private:
  std::string body_;
  double time_;
};

// Opaque full snapshot of a finalized scene's state (time, q, u, drives).
class SceneState {
 public:
  SceneState();
  SceneState(const SceneState&);
  SceneState& operator=(const SceneState&);
  ~SceneState();
  struct Data;
  std::unique_ptr<Data> data;
};

class Scene {
 public:
  explicit Scene(PhysicsSettings settings = {});
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // The settings the scene was made with.
  const PhysicsSettings& getPhysicsSettings() const;

  // --- building: before finalize() ---------------------------------------
  void addGround(double height);
  // Returns the articulation id. `name` must be unique in the scene.
  int addUrdfFile(const std::string& path, const std::string& name,
                  const Pose& root, bool fixed_base);
  int addUrdfString(const std::string& urdf_xml, const std::string& base_dir,
                    const std::string& name, const Pose& root,
                    bool fixed_base);
  // Contact material of one link of `articulation`, or of all its links if
  // `link_name` is empty.
  void setContactMaterial(int articulation, const std::string& link_name,
                          const ContactMaterial& material);
  void setGroundMaterial(const ContactMaterial& material);
  // Whether links of `articulation` touch each other (default: no). Links
  // joined by a joint never touch, nor do links merged by fixed joints.
  void setSelfCollision(int articulation, bool enabled);
  // Builds the multibody system; afterwards no more adds. All joints start
  // at 0 (or the nearest limit), velocities 0, roots where they were added.
  void finalize();
  bool isFinalized() const;

  // --- lookup: any time after the add ------------------------------------
  int getArticulationCount() const;
  const std::string& getArticulationName(int articulation) const;
  const ArticulationSource& getArticulationSource(int articulation) const;
  int findArticulation(const std::string& name) const;  // -1 if none
  // Link ids are global in the scene; links merged by fixed joints keep ids.
  int findLink(int articulation, const std::string& link_name) const;  // -1
  // Every link id of the articulation, the root's first (depth first).
  std::vector<int> listLinks(int articulation) const;
  // The link id of the articulation's root link (its URDF's root).
  int getRootLink(int articulation) const;
  const std::string& getLinkName(int link) const;
  const std::vector<JointDescription>& getJoints(int articulation) const;
  int findJoint(int articulation, const std::string& joint_name) const;  // -1
  // The convex pieces that collide: one per primitive or mesh (its hull).
  int getCollisionShapeCount(int articulation) const;
  // Every <visual> of every articulation, in the order added (each URDF's
  // links depth first from its root, visuals in file order). Grows with
  // each add; unchanged by finalize and stepping. Link poses come from
  // getLinkPose.
  const std::vector<VisualShape>& getVisualShapes() const;
  // What the scene was built from, as `sha256sum` lines ("<64 hex digits>
  // <two spaces><name>"), in the order added: each URDF (its file path, or
  // "urdf text of articulation 'NAME'" for addUrdfString) and every mesh
  // file its links read, each once. An evaluation's certificate holds them
  // per object (docs/evaluation.md, "Certificate"). Throws Error naming a
  // mesh file that can no longer be read.
  std::vector<std::string> getSourceDigests() const;
  // The addGround plane (z = height, infinite), if any; the renderer draws
  // it as background (no visual, no link).
  bool hasGround() const;
  double getGroundHeight() const;  // 0 without a ground
  // Triangles of all visual meshes (mesh visuals only; the renderer
  // tessellates primitives itself).
  std::size_t calcVisualTriangleCount() const;

  // --- state: after finalize() -------------------------------------------
  double getTime() const;
  Eigen::VectorXd getJointPositions(int articulation) const;
  Eigen::VectorXd getJointVelocities(int articulation) const;
  Pose getRootPose(int articulation) const;
  Pose getLinkPose(int link) const;
  Twist getLinkTwist(int link) const;
  // Contact force on link_a from link_b (from anything if link_b < 0), world.
  Eigen::Vector3d calcContactForce(int link_a, int link_b) const;
  double calcKineticEnergy() const;
  // Geometric Jacobian of the point `point_in_link` (link frame) on `link`
  // with respect to the joint velocities of `articulation`: rows angular
  // velocity x, y, z of the link, then linear velocity x, y, z of the point
  // (world frame); one column per joint of the joint vector (planar x, y,
  // yaw included). Columns of joints that do not move the link are zero, as
  // are the floating root's motions (not in the joint vector). Each column
  // moves its joint alone: a mimic leader's column leaves out its followers.
  Eigen::Matrix<double, 6, Eigen::Dynamic> calcLinkJacobian(
      int articulation, int link,
      const Eigen::Vector3d& point_in_link = Eigen::Vector3d::Zero()) const;

  void setJointPositions(int articulation, const Eigen::VectorXd& q);
  void setJointVelocities(int articulation, const Eigen::VectorXd& qdot);
  void setRootPose(int articulation, const Pose& pose);  // floating roots
  // Floating roots: angular velocity and the root link origin's velocity,
  // world frame.
  void setRootTwist(int articulation, const Twist& twist);
  void setJointDynamics(int articulation, int joint, double damping,
                        double friction);

  // --- actuation ----------------------------------------------------------
  // Drive commands hold until replaced; joints without one are passive.
  void setDriveCommands(int articulation, const std::vector<int>& joints,
                        const std::vector<DriveCommand>& commands);
  // Inverse-dynamics cancelling of gravity and Coriolis forces on `joints`
  // at every physics evaluation (supplement B.7).
  void setPassiveForceBalancing(int articulation,
                                const std::vector<int>& joints, bool enabled);

  // Integrates `dt` seconds without re-initializing the integrator (unless a
  // setter changed the state). Throws SimulationDiverged on NaN/explosion.
  void advance(double dt);
  // What the integrators of this scene did so far (every advance() since
  // finalize(), across re-initializations): the cost behind a step.
  IntegratorStatistics getIntegratorStatistics() const;

  // A snapshot of the state, the drive commands, the joint dynamics and
  // the friction anchors. CPODES and Simbody's integrators carry a step
  // history (order, step size) that no snapshot can hold, so under them
  // saving also restarts the integrator: a run continued after the save and
  // one restored from it are then bit-identical. implicit_euler (the
  // default) carries none: saving leaves it alone, and a restored run
  // continues bit-identically to the uninterrupted one.
  SceneState saveState();
  void restoreState(const SceneState& state);
  // A saved state as bytes and back (for Environment's state blobs and
  // demonstrations): time, positions, speeds, friction anchors, drive
  // commands and joint dynamics, in host byte order. decodeState throws
  // SceneError for bytes of another version or of a scene of another
  // structure (other articulations, joints or contact shapes).
  std::vector<std::uint8_t> encodeState(const SceneState& state) const;
  SceneState decodeState(const std::uint8_t* data, std::size_t size) const;
  // The first difference between two encoded states, for people ("time",
  // "position q[3] of link 'l2' of articulation 'arm': a vs b", ...); ""
  // when they are bit-identical.
  std::string findStateDifference(const std::vector<std::uint8_t>& a,
                                  const std::vector<std::uint8_t>& b) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace manibench
