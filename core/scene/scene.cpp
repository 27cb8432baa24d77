// Scene: URDF articulations in one Simbody MultibodySystem; the public
// API over Scene::Impl (scene_impl.hpp: the life cycle; scene_build.cpp
// and scene_step.cpp: building and advancing).
#include "manibench/scene.hpp"

#include <manibench/sha256.hpp>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
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

}  // namespace

// --- SceneState ---------------------------------------------------------



SceneState::SceneState() = default;
SceneState::SceneState(const SceneState& other)
    : data(other.data ? std::make_unique<Data>(*other.data) : nullptr) {}
SceneState& SceneState::operator=(const SceneState& other) {
  if (this != &other)
    data = other.data ? std::make_unique<Data>(*other.data) : nullptr;
  return *this;
}
SceneState::~SceneState() = default;

// --- Scene -------------------------------------------------------------------

Scene::Scene(PhysicsSettings settings) {
  auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  auto non_negative = [](double v) { return v >= 0 && std::isfinite(v); };
  if (!positive(settings.accuracy) || !positive(settings.fixed_step) ||
      !positive(settings.implicit_step) ||
      !std::isfinite(settings.gravity_z) || !positive(settings.friction_stiffness) ||
      !non_negative(settings.friction_damping) || !positive(settings.default_density) ||
      !positive(settings.divergence_speed_limit) || !non_negative(settings.default_joint_damping))
    throw SceneError(
        "PhysicsSettings: accuracy, fixed_step, implicit_step, friction_stiffness, "
        "default_density and "
        "divergence_speed_limit must be positive, friction_damping and default_joint_damping "
        "non-negative, "
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
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw SceneError("URDF '" + path + "': is a directory, not a URDF file");
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw SceneError("URDF '" + path + "': cannot open the file: " + std::strerror(errno));
  std::ostringstream xml;
  xml << in.rdbuf();
  if (in.bad()) throw SceneError("URDF '" + path + "': cannot read the file");
  const std::size_t slash = path.find_last_of('/');
  const std::string base_dir = slash == std::string::npos ? "." : path.substr(0, slash);
  const int index = impl_->addArticulation(xml.str(), "'" + path + "'", base_dir, name, root, fixed_base);
  impl_->articulations[index].file = path;
  return index;
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

std::vector<int> Scene::listLinks(int articulation) const {
  const Impl::Articulation& art = impl_->getArticulation(articulation, "listLinks");
  std::vector<int> links(art.model.links.size());
  for (std::size_t l = 0; l < links.size(); ++l) links[l] = art.first_link + static_cast<int>(l);
  return links;
}

int Scene::getRootLink(int articulation) const {
  // The model lists links depth first from the root (urdf_model.cpp).
  return impl_->getArticulation(articulation, "getRootLink").first_link;
}

const std::string& Scene::getLinkName(int link) const {
  impl_->checkLink(link, "getLinkName");
  const auto& [a, l] = impl_->links[link];
  return impl_->articulations[a].model.links[l].name;
}

const std::vector<JointDescription>& Scene::getJoints(int articulation) const {
  return impl_->getArticulation(articulation, "getJoints").model.joints;
}

int Scene::getCollisionShapeCount(int articulation) const {
  std::size_t count = 0;
  for (const scene_detail::BodyModel& body : impl_->getArticulation(articulation, "getCollisionShapeCount").model.bodies)
    count += body.shapes.size();
  return static_cast<int>(count);
}

const std::vector<VisualShape>& Scene::getVisualShapes() const {
  return impl_->visual_shapes;
}

std::vector<std::string> Scene::getSourceDigests() const {
  std::vector<std::string> lines, seen;
  auto add = [&](const std::string& digest, const std::string& name) {
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) return;
    seen.push_back(name);
    lines.push_back(digest + "  " + name);
  };
  for (const Impl::Articulation& art : impl_->articulations) {
    add(calcSha256(art.source.urdf),
        art.file.empty() ? "urdf text of articulation '" + art.name + "'" : art.file);
    for (const std::string& mesh : art.model.mesh_files) add(calcFileSha256(mesh), mesh);
  }
  return lines;
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
  return impl_->getJointValues(articulation, false, "getJointPositions");
}

Eigen::VectorXd Scene::getJointVelocities(int articulation) const {
  return impl_->getJointValues(articulation, true, "getJointVelocities");
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

Eigen::Vector3d Scene::calcContactForce(int link_a, int link_b) const {
  impl_->requireFinalized("calcContactForce");
  impl_->checkLink(link_a, "calcContactForce");
  if (link_b >= 0) impl_->checkLink(link_b, "calcContactForce");
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
  impl_->setJointValues(articulation, q, false, "setJointPositions");
}

void Scene::setJointVelocities(int articulation, const Eigen::VectorXd& qdot) {
  impl_->setJointValues(articulation, qdot, true, "setJointVelocities");
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

SceneState Scene::saveState() {
  SceneState saved = impl_->captureState("saveState");
  // A restored state starts a fresh integrator; where the integrator has a
  // history, restart it here too, so that both continue alike.
  if (impl_->settings.integrator != Integrator::ImplicitEuler) impl_->updStateAndRestart();
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
