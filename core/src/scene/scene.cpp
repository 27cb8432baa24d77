// Scene: URDF articulations in one Simbody MultibodySystem.
//
// Life cycle. Before finalize() the scene only collects validated
// articulation descriptions (scene_detail::ArticulationModel); finalize()
// turns them into mobilized bodies, force elements and contact surfaces and
// realizes the topology. Afterwards the current state lives either in
// Impl::state (right after finalize, a setter or a restore: the integrator
// must be (re)initialized from it) or in the integrator (while stepping).
// Re-initializing costs ~0.8 ms and restarts CPodes' history, so the control
// tick path (setDriveCommands + advance) never does it.
//
// Contact is one Force::Custom (scene/contact/contact_force.hpp) that owns
// every collision shape; Simbody's own contact subsystem is not used (it
// skips box-box, box-sphere and every cylinder pair).
#include "manibench/scene.hpp"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "Simbody.h"
#include "scene/contact/contact_force.hpp"
#include "scene/stepper.hpp"
#include "scene/joint_forces.hpp"
#include "scene/urdf_model.hpp"

namespace manibench {

using scene_detail::ArticulationModel;
using scene_detail::CollisionShape;
using scene_detail::ContactForce;
using scene_detail::ContactShape;
using scene_detail::JointControls;
using scene_detail::JointForces;
using scene_detail::JointSlot;

namespace {

// A body a joint moves needs mass; links with neither <inertial> nor
// collision geometry (pure frames) get this much.
constexpr double kConstraintTolerance = 1e-8;  // mimic joints, rad or m
constexpr double kTinyMass = 1e-3;     // kg
constexpr double kTinyInertia = 1e-6;  // kg m^2, about the body origin
// See FrictionLaw::max_frequency: 2000 rad/s leaves bodies over 0.1 kg on
// their material stiffness and lets CPodes at accuracy 1e-2 rest a 1 g cube.
constexpr double kMaxContactFrequency = 2000;  // rad/s
// Divergence by step size: an advance() whose integrator steps average
// below kMinMeanStepSize (after kMinStepBudget steps) is a blow-up, not a
// stiff but healthy system (those take ~10-30 us steps even explicitly).
// stepTo() returns every kStepsPerCall internal steps so that this is
// checked; without it a runaway CPodes creeps forward in 1e-14 s steps.
constexpr double kMinMeanStepSize = 1e-6;  // s
constexpr int kMinStepBudget = 10000;
constexpr int kStepsPerCall = 1000;

std::uint64_t newSceneId() {
  static std::atomic<std::uint64_t> next{1};
  return next++;
}

SimTK::Transform toTransform(const Pose& pose) {
  const Eigen::Quaterniond q = pose.orientation.normalized();
  return SimTK::Transform(
      SimTK::Rotation(SimTK::Quaternion(q.w(), q.x(), q.y(), q.z())),
      SimTK::Vec3(pose.position.x(), pose.position.y(), pose.position.z()));
}

Pose toPose(const SimTK::Transform& X) {
  const SimTK::Quaternion q = X.R().convertRotationToQuaternion();
  Pose pose;
  pose.position = Eigen::Vector3d(X.p()[0], X.p()[1], X.p()[2]);
  pose.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  return pose;
}

Eigen::Vector3d toEigen(const SimTK::Vec3& v) {
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

bool isValidPose(const Pose& pose) {
  return pose.position.allFinite() && pose.orientation.coeffs().allFinite() &&
         pose.orientation.norm() > 1e-12;
}

// Empty if `m` is a valid material, else what is wrong with it.
std::string checkMaterial(const ContactMaterial& m) {
  if (!(m.stiffness > 0) || !std::isfinite(m.stiffness)) return "stiffness must be positive";
  if (!(m.dissipation >= 0) || !std::isfinite(m.dissipation))
    return "dissipation must be non-negative";
  if (!(m.dynamic_friction >= 0) || !std::isfinite(m.dynamic_friction))
    return "dynamic_friction must be non-negative";
  if (!(m.static_friction >= m.dynamic_friction) || !std::isfinite(m.static_friction))
    return "static_friction must be at least dynamic_friction";
  if (!(m.viscous_friction >= 0) || !std::isfinite(m.viscous_friction))
    return "viscous_friction must be non-negative";
  return "";
}

std::unique_ptr<scene_detail::Stepper> makeStepper(const SimTK::MultibodySystem& system,
                                                   const SimTK::State& initial,
                                                   const PhysicsSettings& settings,
                                                   const scene_detail::JointForces* joint_forces,
                                                   const scene_detail::ContactForce* contact_force) {
  // Mimic couplings (the only constraints) are held to 1e-8 rather than
  // the accuracy: CPodes at 1e-4 let them drift by 5e-6 rad. Scenes
  // without constraints keep Simbody's default (a tenth of the accuracy).
  const bool constrained = system.getMatterSubsystem().getNumConstraints() > 0;
  switch (settings.integrator) {
    case Integrator::ImplicitEuler: {
      scene_detail::ImplicitEulerOptions options;
      options.step = settings.implicit_step;
      options.constraint_tolerance = constrained ? kConstraintTolerance : 0;
      return scene_detail::makeImplicitEulerStepper(system, initial, {joint_forces, contact_force},
                                                    options);
    }
    case Integrator::CPodes: {
      scene_detail::CPodesOptions options;
      options.accuracy = settings.accuracy;
      options.constraint_tolerance =
          constrained ? kConstraintTolerance : settings.accuracy / 10;
      return scene_detail::makeCPodesStepper(system, initial, options);
    }
    case Integrator::RkMerson:
    case Integrator::SemiExplicitEuler:
      break;
  }
  return scene_detail::makeSimbodyStepper(system, initial, settings,
                                          constrained ? kConstraintTolerance : 0);
}

std::string formatTime(double t) {
  std::ostringstream s;
  s << t;
  return s.str();
}

}  // namespace

// --- Integrator ---------------------------------------------------------

namespace {
constexpr std::pair<Integrator, const char*> kIntegratorNames[] = {
    {Integrator::ImplicitEuler, "implicit_euler"},
    {Integrator::CPodes, "cpodes"},
    {Integrator::RkMerson, "rk_merson"},
    {Integrator::SemiExplicitEuler, "semi_explicit_euler"},
};
}  // namespace

const char* getIntegratorName(Integrator integrator) {
  for (const auto& [value, name] : kIntegratorNames)
    if (value == integrator) return name;
  assert(false && "every Integrator has a name");
  return "?";
}

Integrator parseIntegrator(const std::string& name) {
  std::string choices;
  for (const auto& [value, known] : kIntegratorNames) {
    if (name == known) return value;
    choices += std::string(choices.empty() ? "'" : ", '") + known + "'";
  }
  throw SceneError("PhysicsSettings: unknown integrator '" + name + "' (expected " + choices + ")");
}

// --- SceneState ---------------------------------------------------------

struct SceneState::Data {
  std::uint64_t scene_id = 0;  // the scene this state belongs to
  SimTK::State state;
  JointControls controls;
};

SceneState::SceneState() = default;
SceneState::SceneState(const SceneState& other)
    : data(other.data ? std::make_unique<Data>(*other.data) : nullptr) {}
SceneState& SceneState::operator=(const SceneState& other) {
  if (this != &other)
    data = other.data ? std::make_unique<Data>(*other.data) : nullptr;
  return *this;
}
SceneState::~SceneState() = default;

// --- Scene::Impl -------------------------------------------------------------

struct Scene::Impl {
  struct Articulation {
    std::string name;
    ArticulationSource source;
    ArticulationModel model;
    std::string base_dir;  // for mesh files
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
        id(newSceneId()),
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

  // --- building ---
  int addArticulation(const std::string& xml, const std::string& source,
                      const std::string& base_dir, const std::string& name,
                      const Pose& root, bool fixed_base);
  void finalize();
  void buildArticulation(Articulation& art, std::vector<ContactShape>& shapes);

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

int Scene::Impl::addArticulation(const std::string& xml,
                                 const std::string& source,
                                 const std::string& base_dir,
                                 const std::string& name, const Pose& root,
                                 bool fixed_base) {
  if (name.empty()) throw SceneError("URDF " + source + ": the articulation name is empty");
  for (const Articulation& other : articulations)
    if (other.name == name)
      throw SceneError("URDF " + source + ": an articulation named '" + name +
                       "' already exists in the scene");
  if (!isValidPose(root))
    throw SceneError("URDF " + source + ": the root pose of articulation '" +
                     name + "' is not finite or has a zero quaternion");

  Articulation art;
  art.name = name;
  art.source = {xml, base_dir, root, fixed_base};
  art.model = scene_detail::buildArticulationModel(xml, source, base_dir,
                                                   settings.default_density);
  art.link_materials.assign(art.model.links.size(), settings.default_material);
  art.base_dir = base_dir;
  art.X_root = toTransform(root);
  art.fixed_base = fixed_base;
  art.first_link = static_cast<int>(links.size());
  art.first_joint = joint_count;

  if (!art.model.unsimulated.empty()) {
    std::string list;
    for (const std::string& item : art.model.unsimulated)
      list += (list.empty() ? "" : ", ") + item;
    std::fprintf(stderr, "manibench: URDF %s: collision geometry without contact: %s\n",
                 source.c_str(), list.c_str());
  }

  const int a = static_cast<int>(articulations.size());
  for (int l = 0; l < static_cast<int>(art.model.links.size()); ++l)
    links.emplace_back(a, l);
  joint_count += static_cast<int>(art.model.joints.size());
  for (VisualShape visual : art.model.visuals) {
    visual.link += art.first_link;
    visual_shapes.push_back(std::move(visual));
  }
  articulations.push_back(std::move(art));
  return a;
}

void Scene::Impl::buildArticulation(Articulation& art, std::vector<ContactShape>& shapes) {
  const ArticulationModel& model = art.model;
  const int articulation = static_cast<int>(&art - articulations.data());
  auto addShape = [&](const CollisionShape& shape, SimTK::MobilizedBodyIndex mobod,
                      const SimTK::Transform& X_BS, double inverse_mass) {
    ContactShape contact;
    contact.inverse_mass = inverse_mass;
    contact.geometry = shape.geometry;
    contact.body = mobod;
    contact.X_BS = X_BS;
    contact.link = art.first_link + shape.link;
    contact.articulation = articulation;
    contact.material = art.link_materials[shape.link];
    shapes.push_back(std::move(contact));
  };
  art.body_mobods.resize(model.bodies.size());
  art.joint_body.assign(model.joints.size(), -1);
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].joint >= 0) art.joint_body[model.bodies[b].joint] = static_cast<int>(b);
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const scene_detail::BodyModel& body = model.bodies[b];
    // A fixed root is merged into Ground at the root pose; its frame then
    // sits at X_root in Ground, which every offset below must include.
    const bool on_ground = b == 0 && art.fixed_base;
    if (on_ground) {
      for (const CollisionShape& shape : body.shapes)
        addShape(shape, SimTK::GroundIndex, art.X_root * shape.X_BS, 0);
      art.body_mobods[b] = SimTK::GroundIndex;
      continue;
    }
    const SimTK::MassProperties mass =
        body.mass > 0
            ? SimTK::MassProperties(body.mass, body.first_moment / body.mass, body.inertia)
            : SimTK::MassProperties(kTinyMass, SimTK::Vec3(0), SimTK::Inertia(kTinyInertia));
    SimTK::Body::Rigid rigid(mass);
    SimTK::Body::Massless massless;

    SimTK::MobilizedBody mobod;
    if (b == 0) {
      // Floating root: Free from the Ground origin; q is the root pose.
      mobod = SimTK::MobilizedBody::Free(matter.updGround(), SimTK::Transform(),
                                         rigid, SimTK::Transform());
    } else {
      const JointDescription& joint = model.joints[body.joint];
      SimTK::MobilizedBody& parent =
          matter.updMobilizedBody(art.body_mobods[body.parent]);
      const SimTK::Transform X_PJ =
          body.parent == 0 && art.fixed_base ? art.X_root * body.X_PJ : body.X_PJ;
      // Pin turns about Z of its F and M frames, Slider moves along X: turn
      // both frames so that axis is the URDF axis; at q = 0 the child frame
      // then coincides with the URDF joint frame.
      if (joint.type == JointType::Prismatic) {
        const SimTK::Rotation R(body.axis, SimTK::XAxis);
        mobod = SimTK::MobilizedBody::Slider(
            parent, X_PJ * SimTK::Transform(R),
            body.massless ? static_cast<const SimTK::Body&>(massless) : rigid,
            SimTK::Transform(R));
      } else {
        const SimTK::Rotation R(body.axis, SimTK::ZAxis);
        mobod = SimTK::MobilizedBody::Pin(parent, X_PJ * SimTK::Transform(R),
                                          rigid, SimTK::Transform(R));
      }
    }
    art.body_mobods[b] = mobod.getMobilizedBodyIndex();
    const double inverse_mass = b == 0 ? 1 / mass.getMass() : 0;  // free roots only
    for (const CollisionShape& shape : body.shapes)
      addShape(shape, mobod.getMobilizedBodyIndex(), shape.X_BS, inverse_mass);
  }
  // Mimic joints: a holonomic coupling m q_leader - q_follower + o = 0.
  // Simbody enforces it with a Lagrange multiplier at the acceleration
  // level; the integrators (CPodes, RK-Merson, semi-explicit Euler) project
  // q and u back onto it after each step, so it does not drift.
  for (const JointDescription& joint : model.joints) {
    if (joint.mimic < 0) continue;
    SimTK::Vector coefficients(3);
    coefficients[0] = joint.mimic_multiplier;
    coefficients[1] = -1;
    coefficients[2] = joint.mimic_offset;
    SimTK::Array_<SimTK::MobilizedBodyIndex> bodies{
        art.body_mobods[art.joint_body[joint.mimic]], art.body_mobods[art.joint_body[joint.index]]};
    SimTK::Array_<SimTK::MobilizerQIndex> coordinates{SimTK::MobilizerQIndex(0),
                                                     SimTK::MobilizerQIndex(0)};
    SimTK::Constraint::CoordinateCoupler(matter, new SimTK::Function::Linear(coefficients),
                                         bodies, coordinates);
  }
}

void Scene::Impl::applyMimics(const Articulation& art, SimTK::State& s) const {
  // Passes enough for chains of mimics in any order.
  for (std::size_t pass = 0; pass < art.model.joints.size(); ++pass) {
    bool any = false;
    for (const JointDescription& joint : art.model.joints) {
      if (joint.mimic < 0) continue;
      any = true;
      const SimTK::MobilizedBody& leader =
          matter.getMobilizedBody(joint_mobods[art.first_joint + joint.mimic]);
      const SimTK::MobilizedBody& follower =
          matter.getMobilizedBody(joint_mobods[art.first_joint + joint.index]);
      follower.setOneQ(s, 0, joint.mimic_multiplier * leader.getOneQ(s, 0) + joint.mimic_offset);
      follower.setOneU(s, 0, joint.mimic_multiplier * leader.getOneU(s, 0));
    }
    if (!any) return;
  }
}

void Scene::Impl::finalize() {
  std::vector<ContactShape> shapes;
  std::vector<char> self_collision;
  for (Articulation& art : articulations) {
    buildArticulation(art, shapes);
    self_collision.push_back(art.self_collision ? 1 : 0);
  }
  if (has_ground) {
    // The region below z = height.
    ContactShape floor;
    floor.geometry = scene_detail::ShapeGeometry::makeHalfSpace();
    floor.body = SimTK::GroundIndex;
    floor.X_BS = SimTK::Transform(SimTK::Vec3(0, 0, ground_height));
    floor.material = ground_material;
    shapes.push_back(std::move(floor));
  }
  scene_detail::FrictionLaw law;
  law.stiffness = settings.friction_stiffness;
  law.damping = settings.friction_damping;
  // Light free bodies: h w <= 1 for fixed explicit steps, else the rate at
  // which CPodes at its default accuracy still resolves contact.
  law.max_frequency = settings.integrator == Integrator::SemiExplicitEuler
                          ? 1 / settings.fixed_step
                          : kMaxContactFrequency;
  contact_force =
      new ContactForce(matter, forces, std::move(shapes), std::move(self_collision), law);
  contact_force->setLinearizationKept(settings.integrator == Integrator::ImplicitEuler);
  SimTK::Force::Custom(forces, contact_force);

  // Joint slots and their URDF dynamics.
  std::vector<JointSlot> slots;
  JointControls controls;
  for (const Articulation& art : articulations) {
    for (const JointDescription& joint : art.model.joints) {
      SimTK::MobilizedBodyIndex mobod;
      for (std::size_t b = 0; b < art.model.bodies.size(); ++b)
        if (art.model.bodies[b].joint == joint.index) mobod = art.body_mobods[b];
      assert(mobod.isValid());
      slots.push_back({mobod, joint.effort_limit, joint.lower, joint.upper});
      joint_mobods.push_back(mobod);
      controls.damping.push_back(joint.damping);
      controls.friction.push_back(joint.friction);
    }
  }
  controls.drives.assign(slots.size(), DriveCommand());
  controls.driven.assign(slots.size(), 0);
  controls.balanced.assign(slots.size(), 0);
  joint_forces = new JointForces(matter, gravity, std::move(slots), std::move(controls));
  SimTK::Force::Custom(forces, joint_forces);

  state = system.realizeTopology();
  system.realizeModel(state);

  // Coordinate and surface maps for divergence reports and contact queries.
  mobod_link.assign(matter.getNumBodies(), -1);
  for (const Articulation& art : articulations)
    for (std::size_t b = 0; b < art.model.bodies.size(); ++b)
      if (art.body_mobods[b] != SimTK::GroundIndex)
        mobod_link[art.body_mobods[b]] = art.first_link + art.model.bodies[b].link;
  q_mobod.assign(state.getNQ(), SimTK::MobilizedBodyIndex());
  u_mobod.assign(state.getNU(), SimTK::MobilizedBodyIndex());
  for (SimTK::MobilizedBodyIndex m(1); m < matter.getNumBodies(); ++m) {
    const SimTK::MobilizedBody& mobod = matter.getMobilizedBody(m);
    for (int i = 0; i < mobod.getNumQ(state); ++i) q_mobod[mobod.getFirstQIndex(state) + i] = m;
    for (int i = 0; i < mobod.getNumU(state); ++i) u_mobod[mobod.getFirstUIndex(state) + i] = m;
  }
  link_frames.resize(links.size());
  for (const Articulation& art : articulations) {
    for (std::size_t l = 0; l < art.model.links.size(); ++l) {
      const scene_detail::LinkModel& link = art.model.links[l];
      LinkFrame& frame = link_frames[art.first_link + l];
      frame.mobod = art.body_mobods[link.body];
      frame.X_BL = frame.mobod == SimTK::GroundIndex ? art.X_root * link.X_BL : link.X_BL;
    }
  }

  // Initial configuration: joints at 0 or the nearest limit, roots posed.
  for (const Articulation& art : articulations) {
    for (const JointDescription& joint : art.model.joints)
      matter.getMobilizedBody(joint_mobods[art.first_joint + joint.index])
          .setOneQ(state, 0, std::min(std::max(0.0, joint.lower), joint.upper));
    if (!art.fixed_base)
      matter.getMobilizedBody(art.body_mobods[0]).setQToFitTransform(state, art.X_root);
    applyMimics(art, state);
  }
  system.realize(state, SimTK::Stage::Position);

  needs_init = true;
}

const std::string& Scene::Impl::getMobodLinkName(SimTK::MobilizedBodyIndex mobod) const {
  static const std::string ground = "ground";
  const int link = mobod.isValid() ? mobod_link[mobod] : -1;
  if (link < 0) return ground;
  const auto& [a, l] = links[link];
  return articulations[a].model.links[l].name;
}

std::string Scene::Impl::describeMobod(SimTK::MobilizedBodyIndex mobod) const {
  const int link = mobod.isValid() ? mobod_link[mobod] : -1;
  if (link < 0) return "ground";
  return "link '" + getMobodLinkName(mobod) + "' of articulation '" +
         articulations[links[link].first].name + "'";
}

bool Scene::Impl::findDivergence(const SimTK::State& s,
                                 SimTK::MobilizedBodyIndex& mobod,
                                 std::string& what) const {
  const SimTK::Vector& q = s.getQ();
  for (int i = 0; i < q.size(); ++i)
    if (!std::isfinite(q[i])) {
      mobod = q_mobod[i];
      what = "non-finite position";
      return true;
    }
  const SimTK::Vector& u = s.getU();
  const double limit = settings.divergence_speed_limit;
  for (int i = 0; i < u.size(); ++i)
    if (!(std::abs(u[i]) <= limit)) {
      mobod = u_mobod[i];
      if (!std::isfinite(u[i])) {
        what = "non-finite velocity";
      } else {
        std::ostringstream m;
        m << "speed " << std::abs(u[i]) << " above divergence_speed_limit " << limit;
        what = m.str();
      }
      return true;
    }
  return false;
}

void Scene::Impl::throwDiverged(const std::string& cause) {
  // Whatever the integrator holds becomes the current state; the next
  // advance() restarts from it (and will fail again unless a restore or a
  // setter repaired it).
  // (If initialize() itself failed, `state` already is that state.)
  if (!needs_init) state = stepper->getState();
  needs_init = true;
  SimTK::MobilizedBodyIndex mobod;
  std::string what;
  if (!findDivergence(state, mobod, what)) {
    // The state itself is finite (the integrator gave up before accepting a
    // bad step): blame the first body with a non-finite acceleration.
    try {
      system.realize(state, SimTK::Stage::Acceleration);
      const SimTK::Vector& udot = state.getUDot();
      for (int i = 0; i < udot.size(); ++i)
        if (!std::isfinite(udot[i])) {
          mobod = u_mobod[i];
          what = "non-finite acceleration";
          break;
        }
    } catch (const std::exception&) {
    }
  }
  const double t = state.getTime();
  std::string message = "simulation diverged at t=" + formatTime(t) + " s";
  if (mobod.isValid()) message += ": " + describeMobod(mobod) + ": " + what;
  if (!cause.empty()) message += " (" + cause + ")";
  throw SimulationDiverged(message, mobod.isValid() ? getMobodLinkName(mobod) : "", t);
}

IntegratorStatistics Scene::Impl::calcIntegratorStatistics() const {
  IntegratorStatistics total = retired_statistics;
  if (stepper) total += stepper->getStatistics();
  return total;
}

void Scene::Impl::advance(double dt) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw SceneError("Scene::advance: dt must be positive and finite, got " + formatTime(dt));
  if (state.getNY() == 0) {
    // Nothing moves (only ground and fixed bodies): just the clock runs.
    state.updTime() += dt;
    return;
  }
  try {
    if (needs_init) {
      // A fresh integrator rather than initialize() again: CPodes leaks ~2
      // kB per re-initialization (Simbody 3.7), too much at one per episode.
      retired_statistics = calcIntegratorStatistics();
      ++retired_statistics.initializations;
      stepper = makeStepper(system, state, settings, joint_forces, contact_force);
      needs_init = false;
    }
    const double t_end = stepper->getState().getTime() + dt;
    const std::int64_t first_step = stepper->getStatistics().steps;
    const double budget = std::max<double>(kMinStepBudget, std::ceil(dt / kMinMeanStepSize));
    while (!stepper->stepTo(t_end, kStepsPerCall)) {
      SimTK::MobilizedBodyIndex mobod;
      std::string what;
      if (findDivergence(stepper->getState(), mobod, what)) throwDiverged("");
      const std::int64_t steps = stepper->getStatistics().steps - first_step;
      if (steps > budget) {
        std::ostringstream cause;
        cause << "the integrator took " << steps << " steps and reached only t="
              << stepper->getState().getTime() << " s";
        throw std::runtime_error(cause.str());
      }
    }
  } catch (const SimulationDiverged&) {
    throw;
  } catch (const std::exception& e) {
    std::string cause = e.what();
    // Simbody's messages span lines; keep the first few for the report.
    std::replace(cause.begin(), cause.end(), '\n', ' ');
    if (cause.size() > 400) cause = cause.substr(0, 400) + "...";
    throwDiverged("integrator failed: " + cause);
  }
  SimTK::MobilizedBodyIndex mobod;
  std::string what;
  if (findDivergence(stepper->getState(), mobod, what)) throwDiverged("");
}

// --- Scene -------------------------------------------------------------------

Scene::Scene(PhysicsSettings settings) {
  auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  auto non_negative = [](double v) { return v >= 0 && std::isfinite(v); };
  if (!positive(settings.accuracy) || !positive(settings.fixed_step) ||
      !positive(settings.implicit_step) ||
      !std::isfinite(settings.gravity_z) || !positive(settings.friction_stiffness) ||
      !non_negative(settings.friction_damping) || !positive(settings.default_density) ||
      !positive(settings.divergence_speed_limit))
    throw SceneError(
        "PhysicsSettings: accuracy, fixed_step, implicit_step, friction_stiffness, "
        "default_density and "
        "divergence_speed_limit must be positive, friction_damping non-negative, "
        "gravity_z finite");
  const ContactMaterial& material = settings.default_material;
  const std::string problem = checkMaterial(material);
  if (!problem.empty()) throw SceneError("PhysicsSettings: default_material: " + problem);
  impl_ = std::make_unique<Impl>(settings);
}

Scene::~Scene() = default;

const PhysicsSettings& Scene::getPhysicsSettings() const { return impl_->settings; }

void Scene::addGround(double height) {
  impl_->requireBuilding("addGround");
  if (impl_->has_ground) throw SceneError("Scene::addGround: the scene already has a ground");
  if (!std::isfinite(height)) throw SceneError("Scene::addGround: the height must be finite");
  impl_->has_ground = true;
  impl_->ground_height = height;
}

int Scene::addUrdfFile(const std::string& path, const std::string& name,
                       const Pose& root, bool fixed_base) {
  impl_->requireBuilding("addUrdfFile");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw SceneError("URDF '" + path + "': cannot open the file: " + std::strerror(errno));
  std::ostringstream xml;
  xml << in.rdbuf();
  if (in.bad()) throw SceneError("URDF '" + path + "': cannot read the file");
  const std::size_t slash = path.find_last_of('/');
  const std::string base_dir = slash == std::string::npos ? "." : path.substr(0, slash);
  return impl_->addArticulation(xml.str(), "'" + path + "'", base_dir, name, root, fixed_base);
}

int Scene::addUrdfString(const std::string& urdf_xml, const std::string& base_dir,
                         const std::string& name, const Pose& root, bool fixed_base) {
  impl_->requireBuilding("addUrdfString");
  return impl_->addArticulation(urdf_xml, "<string> of articulation '" + name + "'",
                                base_dir, name, root, fixed_base);
}

void Scene::setContactMaterial(int articulation, const std::string& link_name,
                               const ContactMaterial& material) {
  impl_->requireBuilding("setContactMaterial");
  impl_->getArticulation(articulation, "setContactMaterial");
  Impl::Articulation& art = impl_->articulations[articulation];
  const std::string problem = checkMaterial(material);
  if (!problem.empty())
    throw SceneError("Scene::setContactMaterial: articulation '" + art.name + "'" +
                     (link_name.empty() ? "" : ", link '" + link_name + "'") + ": " + problem);
  if (link_name.empty()) {
    art.link_materials.assign(art.link_materials.size(), material);
    return;
  }
  const int link = findLink(articulation, link_name);
  if (link < 0)
    throw SceneError("Scene::setContactMaterial: articulation '" + art.name +
                     "' has no link '" + link_name + "'");
  art.link_materials[link - art.first_link] = material;
}

void Scene::setGroundMaterial(const ContactMaterial& material) {
  impl_->requireBuilding("setGroundMaterial");
  const std::string problem = checkMaterial(material);
  if (!problem.empty()) throw SceneError("Scene::setGroundMaterial: " + problem);
  impl_->ground_material = material;
}

void Scene::setSelfCollision(int articulation, bool enabled) {
  impl_->requireBuilding("setSelfCollision");
  impl_->getArticulation(articulation, "setSelfCollision");
  impl_->articulations[articulation].self_collision = enabled;
}

void Scene::finalize() {
  impl_->requireBuilding("finalize");
  try {
    impl_->finalize();
  } catch (const SimTK::Exception::Base& e) {
    throw SceneError(std::string("Scene::finalize: Simbody rejected the model: ") + e.what());
  }
  impl_->finalized = true;
}

bool Scene::isFinalized() const { return impl_->finalized; }

int Scene::getArticulationCount() const {
  return static_cast<int>(impl_->articulations.size());
}

const std::string& Scene::getArticulationName(int articulation) const {
  return impl_->getArticulation(articulation, "getArticulationName").name;
}

const ArticulationSource& Scene::getArticulationSource(int articulation) const {
  return impl_->getArticulation(articulation, "getArticulationSource").source;
}

int Scene::findArticulation(const std::string& name) const {
  for (std::size_t a = 0; a < impl_->articulations.size(); ++a)
    if (impl_->articulations[a].name == name) return static_cast<int>(a);
  return -1;
}

int Scene::findLink(int articulation, const std::string& link_name) const {
  const Impl::Articulation& art = impl_->getArticulation(articulation, "findLink");
  for (std::size_t l = 0; l < art.model.links.size(); ++l)
    if (art.model.links[l].name == link_name) return art.first_link + static_cast<int>(l);
  return -1;
}

const std::string& Scene::getLinkName(int link) const {
  impl_->checkLink(link, "getLinkName");
  const auto& [a, l] = impl_->links[link];
  return impl_->articulations[a].model.links[l].name;
}

const std::vector<JointDescription>& Scene::getJoints(int articulation) const {
  return impl_->getArticulation(articulation, "getJoints").model.joints;
}

const std::vector<VisualShape>& Scene::getVisualShapes() const {
  return impl_->visual_shapes;
}

bool Scene::hasGround() const { return impl_->has_ground; }

double Scene::getGroundHeight() const { return impl_->has_ground ? impl_->ground_height : 0.0; }

std::size_t Scene::calcVisualTriangleCount() const {
  std::size_t triangles = 0;
  for (const VisualShape& visual : impl_->visual_shapes)
    if (visual.meshes)
      for (const VisualMesh& mesh : *visual.meshes) triangles += mesh.indices.size() / 3;
  return triangles;
}

int Scene::findJoint(int articulation, const std::string& joint_name) const {
  for (const JointDescription& joint : getJoints(articulation))
    if (joint.name == joint_name) return joint.index;
  return -1;
}

double Scene::getTime() const {
  impl_->requireFinalized("getTime");
  return impl_->getState().getTime();
}

Eigen::VectorXd Scene::getJointPositions(int articulation) const {
  impl_->requireFinalized("getJointPositions");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "getJointPositions");
  const SimTK::State& s = impl_->getState();
  Eigen::VectorXd q(art.model.joints.size());
  for (Eigen::Index j = 0; j < q.size(); ++j)
    q[j] = impl_->matter.getMobilizedBody(impl_->joint_mobods[art.first_joint + j]).getOneQ(s, 0);
  return q;
}

Eigen::VectorXd Scene::getJointVelocities(int articulation) const {
  impl_->requireFinalized("getJointVelocities");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "getJointVelocities");
  const SimTK::State& s = impl_->getState();
  Eigen::VectorXd u(art.model.joints.size());
  for (Eigen::Index j = 0; j < u.size(); ++j)
    u[j] = impl_->matter.getMobilizedBody(impl_->joint_mobods[art.first_joint + j]).getOneU(s, 0);
  return u;
}

Pose Scene::getRootPose(int articulation) const {
  impl_->requireFinalized("getRootPose");
  return getLinkPose(impl_->getArticulation(articulation, "getRootPose").first_link);
}

Pose Scene::getLinkPose(int link) const {
  impl_->requireFinalized("getLinkPose");
  impl_->checkLink(link, "getLinkPose");
  const Impl::LinkFrame& frame = impl_->link_frames[link];
  const SimTK::State& s = impl_->getRealizedState(SimTK::Stage::Position);
  return toPose(impl_->matter.getMobilizedBody(frame.mobod).getBodyTransform(s) * frame.X_BL);
}

Twist Scene::getLinkTwist(int link) const {
  impl_->requireFinalized("getLinkTwist");
  impl_->checkLink(link, "getLinkTwist");
  const Impl::LinkFrame& frame = impl_->link_frames[link];
  const SimTK::State& s = impl_->getRealizedState(SimTK::Stage::Velocity);
  const SimTK::MobilizedBody& mobod = impl_->matter.getMobilizedBody(frame.mobod);
  Twist twist;
  twist.angular = toEigen(mobod.getBodyAngularVelocity(s));
  twist.linear = toEigen(mobod.findStationVelocityInGround(s, frame.X_BL.p()));
  return twist;
}

Eigen::Vector3d Scene::getContactForce(int link_a, int link_b) const {
  impl_->requireFinalized("getContactForce");
  impl_->checkLink(link_a, "getContactForce");
  if (link_b >= 0) impl_->checkLink(link_b, "getContactForce");
  const SimTK::State& s = impl_->getRealizedState(SimTK::Stage::Velocity);
  const ContactForce& contact = *impl_->contact_force;
  std::vector<ContactForce::Report>& reports = impl_->contact_reports;
  contact.calcReports(s, reports);
  SimTK::Vec3 total(0);
  for (const ContactForce::Report& r : reports) {
    const int link1 = contact.getShape(r.shape_a).link;
    const int link2 = contact.getShape(r.shape_b).link;
    if (link1 == link_a && (link_b < 0 || link2 == link_b)) total -= r.force_on_b;
    if (link2 == link_a && (link_b < 0 || link1 == link_b)) total += r.force_on_b;
  }
  return toEigen(total);
}

double Scene::calcKineticEnergy() const {
  impl_->requireFinalized("calcKineticEnergy");
  return impl_->matter.calcKineticEnergy(impl_->getRealizedState(SimTK::Stage::Velocity));
}

Eigen::Matrix<double, 6, Eigen::Dynamic> Scene::calcLinkJacobian(
    int articulation, int link, const Eigen::Vector3d& point_in_link) const {
  impl_->requireFinalized("calcLinkJacobian");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "calcLinkJacobian");
  impl_->checkLink(link, "calcLinkJacobian");
  if (!point_in_link.allFinite())
    throw SceneError("Scene::calcLinkJacobian: the point on link '" + getLinkName(link) +
                     "' must be finite");
  const Eigen::Index n = static_cast<Eigen::Index>(art.model.joints.size());
  Eigen::Matrix<double, 6, Eigen::Dynamic> jacobian =
      Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, n);
  const Impl::LinkFrame& frame = impl_->link_frames[link];
  if (frame.mobod == SimTK::GroundIndex || n == 0) return jacobian;  // nothing moves it
  const SimTK::State& s = impl_->getRealizedState(SimTK::Stage::Position);
  const SimTK::Vec3 station =
      frame.X_BL * SimTK::Vec3(point_in_link.x(), point_in_link.y(), point_in_link.z());
  // 6 x nu over the whole system (all articulations); every joint is a
  // one-u Pin or Slider whose u is its joint velocity, so the articulation's
  // columns are those mobilizers' u columns.
  SimTK::Matrix full;
  impl_->matter.calcFrameJacobian(s, frame.mobod, station, full);
  for (Eigen::Index j = 0; j < n; ++j) {
    const SimTK::MobilizedBody& mobod =
        impl_->matter.getMobilizedBody(impl_->joint_mobods[art.first_joint + j]);
    const int u = mobod.getFirstUIndex(s);
    for (int r = 0; r < 6; ++r) jacobian(r, j) = full(r, u);
  }
  return jacobian;
}

void Scene::setJointPositions(int articulation, const Eigen::VectorXd& q) {
  impl_->requireFinalized("setJointPositions");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "setJointPositions");
  impl_->checkJointVector(art, q, "setJointPositions");
  SimTK::State& s = impl_->updStateAndRestart();
  for (Eigen::Index j = 0; j < q.size(); ++j)
    impl_->matter.getMobilizedBody(impl_->joint_mobods[art.first_joint + j]).setOneQ(s, 0, q[j]);
  impl_->applyMimics(art, s);
}

void Scene::setJointVelocities(int articulation, const Eigen::VectorXd& qdot) {
  impl_->requireFinalized("setJointVelocities");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "setJointVelocities");
  impl_->checkJointVector(art, qdot, "setJointVelocities");
  SimTK::State& s = impl_->updStateAndRestart();
  for (Eigen::Index j = 0; j < qdot.size(); ++j)
    impl_->matter.getMobilizedBody(impl_->joint_mobods[art.first_joint + j]).setOneU(s, 0, qdot[j]);
  impl_->applyMimics(art, s);
}

void Scene::setRootPose(int articulation, const Pose& pose) {
  impl_->requireFinalized("setRootPose");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "setRootPose");
  if (art.fixed_base)
    throw SceneError("Scene::setRootPose: articulation '" + art.name +
                     "' has a fixed base; its root pose is set when it is added");
  if (!isValidPose(pose))
    throw SceneError("Scene::setRootPose: articulation '" + art.name +
                     "': the pose is not finite or has a zero quaternion");
  SimTK::State& s = impl_->updStateAndRestart();
  impl_->matter.getMobilizedBody(art.body_mobods[0]).setQToFitTransform(s, toTransform(pose));
}

void Scene::setRootTwist(int articulation, const Twist& twist) {
  impl_->requireFinalized("setRootTwist");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "setRootTwist");
  if (art.fixed_base)
    throw SceneError("Scene::setRootTwist: articulation '" + art.name +
                     "' has a fixed base; its root does not move");
  if (!twist.angular.allFinite() || !twist.linear.allFinite())
    throw SceneError("Scene::setRootTwist: articulation '" + art.name +
                     "': the twist is not finite");
  SimTK::State& s = impl_->updStateAndRestart();
  // The root body's frame is the root link's frame.
  const SimTK::MobilizedBody& root = impl_->matter.getMobilizedBody(art.body_mobods[0]);
  const Eigen::Vector3d& w = twist.angular;
  const Eigen::Vector3d& v = twist.linear;
  root.setUToFitAngularVelocity(s, SimTK::Vec3(w.x(), w.y(), w.z()));
  root.setUToFitLinearVelocity(s, SimTK::Vec3(v.x(), v.y(), v.z()));
}

void Scene::setJointDynamics(int articulation, int joint, double damping, double friction) {
  impl_->requireFinalized("setJointDynamics");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "setJointDynamics");
  const int slot = impl_->getJointSlot(art, joint, "setJointDynamics");
  if (!(damping >= 0) || !(friction >= 0) || !std::isfinite(damping) || !std::isfinite(friction))
    throw SceneError("Scene::setJointDynamics: joint '" + art.model.joints[joint].name +
                     "' of articulation '" + art.name +
                     "': damping and friction must be finite and non-negative");
  JointControls& controls = impl_->updControls();
  controls.damping[slot] = damping;
  controls.friction[slot] = friction;
  impl_->invalidateForces();
}

void Scene::setDriveCommands(int articulation, const std::vector<int>& joints,
                             const std::vector<DriveCommand>& commands) {
  impl_->requireFinalized("setDriveCommands");
  const Impl::Articulation& art = impl_->getArticulation(articulation, "setDriveCommands");
  if (joints.size() != commands.size())
    throw SceneError("Scene::setDriveCommands: articulation '" + art.name + "': " +
                     std::to_string(joints.size()) + " joints but " +
                     std::to_string(commands.size()) + " commands");
  std::vector<int> slots;
  slots.reserve(joints.size());
  for (int joint : joints) slots.push_back(impl_->getJointSlot(art, joint, "setDriveCommands"));
  // Non-finite commands are accepted on purpose: they make the simulation
  // diverge, which advance() reports with the body at fault.
  JointControls& controls = impl_->updControls();
  for (std::size_t i = 0; i < slots.size(); ++i) {
    controls.drives[slots[i]] = commands[i];
    controls.driven[slots[i]] = 1;
  }
  impl_->invalidateForces();
}

void Scene::setPassiveForceBalancing(int articulation, const std::vector<int>& joints,
                                     bool enabled) {
  impl_->requireFinalized("setPassiveForceBalancing");
  const Impl::Articulation& art =
      impl_->getArticulation(articulation, "setPassiveForceBalancing");
  std::vector<int> slots;
  for (int joint : joints)
    slots.push_back(impl_->getJointSlot(art, joint, "setPassiveForceBalancing"));
  JointControls& controls = impl_->updControls();
  for (int slot : slots) controls.balanced[slot] = enabled ? 1 : 0;
  impl_->invalidateForces();
}

void Scene::advance(double dt) {
  impl_->requireFinalized("advance");
  impl_->advance(dt);
}

IntegratorStatistics Scene::getIntegratorStatistics() const {
  return impl_->calcIntegratorStatistics();
}

SceneState Scene::saveState() const {
  impl_->requireFinalized("saveState");
  SceneState saved;
  saved.data = std::make_unique<SceneState::Data>();
  saved.data->scene_id = impl_->id;
  saved.data->state = impl_->getState();
  saved.data->controls = impl_->joint_forces->getControls();
  // Restart the integrator here too: the trajectory after a save is then
  // bit-identical to the trajectory after restoring that save (a restored
  // state always starts the integrator afresh; CPodes' history can't be
  // saved).
  impl_->updStateAndRestart();
  return saved;
}

void Scene::restoreState(const SceneState& saved) {
  impl_->requireFinalized("restoreState");
  if (!saved.data)
    throw SceneError("Scene::restoreState: the SceneState is empty (not from saveState())");
  if (saved.data->scene_id != impl_->id)
    throw SceneError("Scene::restoreState: the SceneState was saved from another scene");
  impl_->state = saved.data->state;
  impl_->needs_init = true;
  impl_->updControls() = saved.data->controls;
  impl_->invalidateForces();
}

}  // namespace manibench
