// Scene::Impl and what scene.cpp (the public API), scene_build.cpp
// (URDF models into the multibody system) and scene_step.cpp (advancing,
// divergence) share. Internal to the scene; nothing outside core/scene
// includes it.
//
// Life cycle. Before finalize() the scene only collects validated
// articulation descriptions (scene_detail::ArticulationModel); finalize()
// turns them into mobilized bodies, force elements and contact surfaces and
// realizes the topology. Afterwards the current state lives either in
// Impl::state (right after finalize, a setter or a restore: the integrator
// must be (re)initialized from it) or in the integrator (while stepping).
// Re-initializing restarts CPodes' history (and costs ~0.8 ms), so the
// control tick path (setDriveCommands + advance) never does it.
//
// Contact is one Force::Custom (scene/contact/contact_force.hpp) that owns
// every collision shape; Simbody's own contact subsystem is not used (it
// skips box-box, box-sphere and every cylinder pair).
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "Simbody.h"
#include "manibench/scene.hpp"
#include "contact/contact_force.hpp"
#include "joint_forces.hpp"
#include "stepper.hpp"
#include "urdf_model.hpp"

namespace manibench {

using scene_detail::ArticulationModel;
using scene_detail::CollisionShape;
using scene_detail::ContactForce;
using scene_detail::ContactShape;
using scene_detail::JointControls;
using scene_detail::JointForces;
using scene_detail::JointSlot;

namespace scene_detail {

// Mimic couplings (the only constraints) are held to this rather than the
// integrator's accuracy: CPodes at 1e-4 let them drift by 5e-6 rad.
constexpr double kConstraintTolerance = 1e-8;  // rad or m

inline std::uint64_t newSceneId() {
  static std::atomic<std::uint64_t> next{1};
  return next++;
}

inline SimTK::Transform toTransform(const Pose& pose) {
  const Eigen::Quaterniond q = pose.orientation.normalized();
  return SimTK::Transform(
      SimTK::Rotation(SimTK::Quaternion(q.w(), q.x(), q.y(), q.z())),
      SimTK::Vec3(pose.position.x(), pose.position.y(), pose.position.z()));
}

inline bool isValidPose(const Pose& pose) {
  return pose.position.allFinite() && pose.orientation.coeffs().allFinite() &&
         pose.orientation.norm() > 1e-12;
}

}  // namespace scene_detail

struct SceneState::Data {
  std::uint64_t scene_id = 0;  // the scene this state belongs to
  SimTK::State state;
  JointControls controls;
};

// --- Scene::Impl -------------------------------------------------------------

struct Scene::Impl {
  struct Articulation {
    std::string name;
    ArticulationSource source;
    ArticulationModel model;
    std::string base_dir;  // for mesh files
    std::string file;      // the URDF file (addUrdfFile), else ""
    SimTK::Transform X_root;
    bool fixed_base = false;
    bool self_collision = false;
    std::vector<ContactMaterial> link_materials;  // per model link
    int first_link = 0;   // global id of model.links[0]
    int first_joint = 0;  // global slot of model.joints[0]
    std::vector<SimTK::MobilizedBodyIndex> body_mobods;  // after finalize
    std::vector<int> joint_body;  // joint index -> model body, after finalize
  };
  // Where a link's frame sits, after finalize.
  struct LinkFrame {
    SimTK::MobilizedBodyIndex mobod;
    SimTK::Transform X_BL;
  };
  explicit Impl(const PhysicsSettings& s)
      : settings(s),
        id(scene_detail::newSceneId()),
        matter(system),
        forces(system),
        gravity(forces, matter, SimTK::Vec3(0, 0, s.gravity_z)),
        ground_material(s.default_material) {}

  PhysicsSettings settings;
  std::uint64_t id;

  // Building.
  bool has_ground = false;
  double ground_height = 0;
  std::vector<Articulation> articulations;
  std::vector<std::pair<int, int>> links;  // global id -> (articulation, local)
  int joint_count = 0;
  std::vector<VisualShape> visual_shapes;  // link ids global

  // Simbody. Declaration order is construction order.
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter;
  SimTK::GeneralForceSubsystem forces;
  SimTK::Force::Gravity gravity;
  ContactMaterial ground_material;
  JointForces* joint_forces = nullptr;     // owned by `forces`
  ContactForce* contact_force = nullptr;   // owned by `forces`
  std::unique_ptr<scene_detail::Stepper> stepper;
  IntegratorStatistics retired_statistics;  // of steppers replaced so far
  SimTK::State state;       // current state while needs_init
  bool needs_init = true;
  bool finalized = false;

  // Maps made by finalize().
  std::vector<LinkFrame> link_frames;                     // per global link
  std::vector<SimTK::MobilizedBodyIndex> joint_mobods;    // per joint slot
  std::vector<int> mobod_link;        // MobilizedBodyIndex -> global link
  std::vector<SimTK::MobilizedBodyIndex> q_mobod, u_mobod;  // per coordinate
  mutable std::vector<ContactForce::Report> contact_reports;  // scratch

  // --- phases and lookups ---
  void requireBuilding(const char* method) const {
    if (finalized)
      throw SceneError(std::string("Scene::") + method +
                       ": the scene is already finalized; add everything "
                       "before finalize()");
  }
  void requireFinalized(const char* method) const {
    if (!finalized)
      throw SceneError(std::string("Scene::") + method +
                       ": the scene is not finalized yet; call finalize() "
                       "first");
  }
  const Articulation& getArticulation(int a, const char* method) const {
    if (a < 0 || a >= static_cast<int>(articulations.size()))
      throw SceneError(std::string("Scene::") + method + ": no articulation " +
                       std::to_string(a) + " (the scene has " +
                       std::to_string(articulations.size()) + ")");
    return articulations[a];
  }
  void checkLink(int link, const char* method) const {
    if (link < 0 || link >= static_cast<int>(links.size()))
      throw SceneError(std::string("Scene::") + method + ": no link " +
                       std::to_string(link) + " (the scene has " +
                       std::to_string(links.size()) + ")");
  }
  int getJointSlot(const Articulation& art, int joint, const char* method) const {
    const int n = static_cast<int>(art.model.joints.size());
    if (joint < 0 || joint >= n)
      throw SceneError(std::string("Scene::") + method + ": articulation '" +
                       art.name + "' has no joint " + std::to_string(joint) +
                       " (it has " + std::to_string(n) + ")");
    return art.first_joint + joint;
  }
  void checkJointVector(const Articulation& art, const Eigen::VectorXd& v,
                        const char* method) const {
    if (v.size() != static_cast<Eigen::Index>(art.model.joints.size()))
      throw SceneError(std::string("Scene::") + method + ": articulation '" +
                       art.name + "' has " +
                       std::to_string(art.model.joints.size()) +
                       " joints, got " + std::to_string(v.size()) + " values");
    if (!v.allFinite())
      throw SceneError(std::string("Scene::") + method + ": articulation '" +
                       art.name + "': the values must be finite");
  }

  // --- state access ---
  const SimTK::State& getState() const {
    return needs_init ? state : stepper->getState();
  }
  // The state to modify; the integrator restarts from it on the next
  // advance().
  SimTK::State& updStateAndRestart() {
    if (!needs_init) {
      state = stepper->getState();
      needs_init = true;
    }
    return state;
  }
  const SimTK::State& getRealizedState(SimTK::Stage stage) const {
    const SimTK::State& s = getState();
    system.realize(s, stage);
    return s;
  }
  // Joint controls changed: forces cached in the current state are stale.
  // No restart needed; the integrator picks the new forces up.
  void invalidateForces() {
    SimTK::State& s = needs_init ? state : stepper->updState();
    s.invalidateAllCacheAtOrAbove(SimTK::Stage::Dynamics);
  }
  JointControls& updControls() { return joint_forces->updControls(); }
  // A copy of the current state and joint controls: what saveState keeps,
  // and what decodeState starts from before the bytes overwrite it.
  SceneState captureState(const char* method) const {
    requireFinalized(method);
    SceneState saved;
    saved.data = std::make_unique<SceneState::Data>();
    saved.data->scene_id = id;
    saved.data->state = getState();
    saved.data->controls = joint_forces->getControls();
    return saved;
  }
  // One articulation's joint positions (q) or velocities (u), in joint order.
  Eigen::VectorXd getJointValues(int articulation, bool velocities, const char* method) const {
    requireFinalized(method);
    const Articulation& art = getArticulation(articulation, method);
    const SimTK::State& s = getState();
    Eigen::VectorXd values(art.model.joints.size());
    for (Eigen::Index j = 0; j < values.size(); ++j) {
      const SimTK::MobilizedBody& body = matter.getMobilizedBody(joint_mobods[art.first_joint + j]);
      values[j] = velocities ? body.getOneU(s, 0) : body.getOneQ(s, 0);
    }
    return values;
  }
  // Sets them; the integrator restarts from the new state, and mimic joints
  // follow their leaders.
  void setJointValues(int articulation, const Eigen::VectorXd& values, bool velocities, const char* method) {
    requireFinalized(method);
    const Articulation& art = getArticulation(articulation, method);
    checkJointVector(art, values, method);
    SimTK::State& s = updStateAndRestart();
    for (Eigen::Index j = 0; j < values.size(); ++j) {
      const SimTK::MobilizedBody& body = matter.getMobilizedBody(joint_mobods[art.first_joint + j]);
      if (velocities)
        body.setOneU(s, 0, values[j]);
      else
        body.setOneQ(s, 0, values[j]);
    }
    applyMimics(art, s);
  }

  // --- building ---
  int addArticulation(const std::string& xml, const std::string& source,
                      const std::string& base_dir, const std::string& name,
                      const Pose& root, bool fixed_base);
  void finalize();
  void buildArticulation(Articulation& art, std::vector<ContactShape>& shapes);

  // What a state's bytes must agree with (scene_state_bytes.cpp): names
  // and counts, not values.
  uint64_t calcStructureFingerprint() const;

  // --- stepping ---
  void advance(double dt);
  IntegratorStatistics calcIntegratorStatistics() const;
  std::string describeMobod(SimTK::MobilizedBodyIndex mobod) const;
  const std::string& getMobodLinkName(SimTK::MobilizedBodyIndex mobod) const;
  // Finds a non-finite or too fast coordinate; returns false if none.
  bool findDivergence(const SimTK::State& s, SimTK::MobilizedBodyIndex& mobod,
                      std::string& what) const;
  [[noreturn]] void throwDiverged(const std::string& cause);
  // Puts mimic joints where their leaders say (before the integrator
  // projects, so that it does not split the difference).
  void applyMimics(const Articulation& art, SimTK::State& s) const;
};

}  // namespace manibench
