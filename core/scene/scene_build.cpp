// Scene::Impl's building half: URDF models (scene_detail::ArticulationModel)
// into mobilized bodies, joint forces and contact shapes (see scene_impl.hpp).
#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

#include "scene_impl.hpp"

namespace manibench {

using scene_detail::isValidPose;
using scene_detail::kConstraintTolerance;
using scene_detail::toTransform;

namespace {

// A body a joint moves needs mass; links with neither <inertial> nor
// collision geometry (pure frames) get this much.
constexpr double kTinyMass = 1e-3;     // kg
constexpr double kTinyInertia = 1e-6;  // kg m^2, about the body origin
// See FrictionLaw::max_frequency: 2000 rad/s leaves bodies over 0.1 kg on
// their material stiffness and lets CPodes at accuracy 1e-2 rest a 1 g cube.
constexpr double kMaxContactFrequency = 2000;  // rad/s

}  // namespace

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
                                                   settings.default_density,
                                                   settings.default_joint_damping);
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
                                          body.massless ? static_cast<const SimTK::Body&>(massless) : rigid,
                                          SimTK::Transform(R));
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

}  // namespace manibench
