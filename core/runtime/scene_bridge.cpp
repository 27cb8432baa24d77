// The host's mb_scene_api: C trampolines over Scene. Nothing thrown here may
// reach the plugin; every exception becomes a status and a message.
#include <manibench/scene_bridge.hpp>
#include <manibench/sdk/guard.hpp>
#include <manibench/visual_observer.hpp>

#include <cstdint>
#include <cstring>
#include <set>
#include <string>
#include <vector>

struct mb_scene {
  manibench::Scene* scene = nullptr;
  bool building = false;
  bool state_changes_allowed = false;
  // Names handed to plugins must outlive any later add_*; a std::set's nodes
  // never move.
  std::set<std::string> interned;
  // Where add_to_mask (ABI 1.1) records the task's segmentation masks.
  manibench::SegmentationMasks* masks = nullptr;
};

namespace manibench {
namespace {

// The SDK's guard (the one at every C boundary), with the scene's errors
// as their statuses.
template <class Body>
mb_status guarded(mb_scene* s, mb_error* err, Body&& body) noexcept {
  return sdk::detail::guardBoundary(err, [&] {
    if (s == nullptr || s->scene == nullptr) throw sdk::Error("no scene", MB_INVALID_ARGUMENT);
    try {
      body(*s);
    } catch (const SimulationDiverged& e) {
      throw sdk::Error(e.what(), MB_DIVERGED);
    } catch (const SceneError& e) {
      throw sdk::Error(e.what(), MB_INVALID_ARGUMENT);
    }
  });
}

void requireBuilding(const mb_scene& s, const char* call) {
  if (!s.building)
    throw SceneError(std::string(call) + " is only allowed while a task builds its scene");
}
void requireStateChanges(const mb_scene& s, const char* call) {
  if (!s.state_changes_allowed)
    throw SceneError(std::string(call) +
                     " is only allowed in a reset (observe, reward and success must not change the state)");
}
void requireCount(const Scene& scene, mb_id articulation, uint32_t count) {
  const std::size_t n = scene.getJoints(articulation).size();
  if (n != count)
    throw SceneError("articulation '" + scene.getArticulationName(articulation) + "' has " +
                     std::to_string(n) + " joints, the call passed " + std::to_string(count));
}
void requirePointer(const void* p, const char* what) {
  if (p == nullptr) throw SceneError(std::string(what) + " is null");
}
// An array of `count` values: null is fine when there are none (an empty
// Eigen vector's data() is null: a rigid object has no joints).
void requireArray(const void* p, uint32_t count, const char* what) {
  if (count > 0) requirePointer(p, what);
}

// A pose from a plugin, which must be there and have a unit quaternion.
Pose toCheckedPose(const mb_pose* p) {
  requirePointer(p, "pose");
  const Pose out = makePose(*p);
  const double norm = out.orientation.norm();
  if (!(std::abs(norm - 1.0) < 1e-6))
    throw SceneError("pose quaternion has norm " + std::to_string(norm) + ", expected 1");
  return out;
}

mb_status addGround(mb_scene* s, double height, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requireBuilding(m, "add_ground");
    m.scene->addGround(height);
  });
}
mb_status addUrdfFile(mb_scene* s, const char* path, const char* name, const mb_pose* root,
                      int32_t fixed_base, mb_id* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requireBuilding(m, "add_urdf_file");
    requirePointer(path, "path");
    requirePointer(name, "name");
    requirePointer(out, "output id");
    *out = m.scene->addUrdfFile(path, name, toCheckedPose(root), fixed_base != 0);
  });
}
mb_status addUrdfString(mb_scene* s, const char* xml, const char* base_dir, const char* name,
                        const mb_pose* root, int32_t fixed_base, mb_id* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requireBuilding(m, "add_urdf_string");
    requirePointer(xml, "URDF text");
    requirePointer(name, "name");
    requirePointer(out, "output id");
    *out = m.scene->addUrdfString(xml, base_dir ? base_dir : "", name, toCheckedPose(root),
                                  fixed_base != 0);
  });
}
mb_status findArticulation(mb_scene* s, const char* name, mb_id* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(name, "name");
    requirePointer(out, "output id");
    *out = m.scene->findArticulation(name);
    if (*out < 0) throw SceneError(std::string("no articulation named '") + name + "'");
  });
}
mb_status findLink(mb_scene* s, mb_id articulation, const char* link, mb_id* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(link, "link name");
    requirePointer(out, "output id");
    *out = m.scene->findLink(articulation, link);
    if (*out < 0)
      throw SceneError(std::string("articulation '") + m.scene->getArticulationName(articulation) +
                       "' has no link named '" + link + "'");
  });
}
mb_status getJointCount(mb_scene* s, mb_id articulation, uint32_t* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(out, "output count");
    *out = static_cast<uint32_t>(m.scene->getJoints(articulation).size());
  });
}
mb_status getJointInfo(mb_scene* s, mb_id articulation, uint32_t index, mb_joint_info* out,
                       mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(out, "output joint info");
    const auto& joints = m.scene->getJoints(articulation);
    if (index >= joints.size())
      throw SceneError("joint index " + std::to_string(index) + " out of range: articulation '" +
                       m.scene->getArticulationName(articulation) + "' has " +
                       std::to_string(joints.size()) + " joints");
    const JointDescription& j = joints[index];
    *out = makeJointInfo(j, m.interned.insert(j.name).first->c_str());
  });
}
mb_status findJoint(mb_scene* s, mb_id articulation, const char* name, uint32_t* out,
                    mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(name, "joint name");
    requirePointer(out, "output index");
    const int index = m.scene->findJoint(articulation, name);
    if (index < 0)
      throw SceneError(std::string("articulation '") + m.scene->getArticulationName(articulation) +
                       "' has no movable joint named '" + name + "'");
    *out = static_cast<uint32_t>(index);
  });
}
mb_status getTime(mb_scene* s, double* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(out, "output time");
    *out = m.scene->getTime();
  });
}
// get_joint_positions and get_joint_velocities: one value per joint.
mb_status getJointValues(mb_scene* s, mb_id articulation, double* out, uint32_t count, mb_error* err,
                         Eigen::VectorXd (Scene::*get)(int) const) {
  return guarded(s, err, [&](mb_scene& m) {
    requireCount(*m.scene, articulation, count);
    requireArray(out, count, "output array");
    Eigen::Map<Eigen::VectorXd>(out, count) = (m.scene->*get)(articulation);
  });
}
mb_status getJointPositions(mb_scene* s, mb_id articulation, double* out, uint32_t count,
                            mb_error* err) {
  return getJointValues(s, articulation, out, count, err, &Scene::getJointPositions);
}
mb_status getJointVelocities(mb_scene* s, mb_id articulation, double* out, uint32_t count,
                             mb_error* err) {
  return getJointValues(s, articulation, out, count, err, &Scene::getJointVelocities);
}
mb_status getRootPose(mb_scene* s, mb_id articulation, mb_pose* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(out, "output pose");
    *out = makeCPose(m.scene->getRootPose(articulation));
  });
}
mb_status getLinkPose(mb_scene* s, mb_id link, mb_pose* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(out, "output pose");
    *out = makeCPose(m.scene->getLinkPose(link));
  });
}
mb_status getLinkTwist(mb_scene* s, mb_id link, double out[6], mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(out, "output twist");
    const Twist t = m.scene->getLinkTwist(link);
    for (int i = 0; i < 3; ++i) {
      out[i] = t.angular[i];
      out[3 + i] = t.linear[i];
    }
  });
}
mb_status calcContactForce(mb_scene* s, mb_id a, mb_id b, double out[3], mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(out, "output force");
    const Eigen::Vector3d f = m.scene->calcContactForce(a, b);
    for (int i = 0; i < 3; ++i) out[i] = f[i];
  });
}
// set_joint_positions and set_joint_velocities: one value per joint.
mb_status setJointValues(mb_scene* s, mb_id articulation, const double* values, uint32_t count, mb_error* err,
                         void (Scene::*set)(int, const Eigen::VectorXd&), const char* call, const char* what) {
  return guarded(s, err, [&](mb_scene& m) {
    requireStateChanges(m, call);
    requireCount(*m.scene, articulation, count);
    requireArray(values, count, what);
    (m.scene->*set)(articulation, Eigen::Map<const Eigen::VectorXd>(values, count));
  });
}
mb_status setJointPositions(mb_scene* s, mb_id articulation, const double* q, uint32_t count,
                            mb_error* err) {
  return setJointValues(s, articulation, q, count, err, &Scene::setJointPositions, "set_joint_positions",
                        "positions");
}
mb_status setJointVelocities(mb_scene* s, mb_id articulation, const double* v, uint32_t count,
                             mb_error* err) {
  return setJointValues(s, articulation, v, count, err, &Scene::setJointVelocities, "set_joint_velocities",
                        "velocities");
}
mb_status setRootPose(mb_scene* s, mb_id articulation, const mb_pose* pose, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requireStateChanges(m, "set_root_pose");
    m.scene->setRootPose(articulation, toCheckedPose(pose));
  });
}
mb_status setJointDynamics(mb_scene* s, mb_id articulation, uint32_t joint, double damping,
                           double friction, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requireStateChanges(m, "set_joint_dynamics");
    if (!(damping >= 0) || !(friction >= 0))
      throw SceneError("joint damping and friction must be finite and >= 0, got " +
                       std::to_string(damping) + " and " + std::to_string(friction));
    m.scene->setJointDynamics(articulation, static_cast<int>(joint), damping, friction);
  });
}
mb_status calcLinkJacobian(mb_scene* s, mb_id articulation, mb_id link,
                           const double point_in_link[3], double* out, uint32_t count,
                           mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requireCount(*m.scene, articulation, count);
    requirePointer(point_in_link, "point in link");
    requirePointer(out, "output Jacobian");
    const Eigen::Matrix<double, 6, Eigen::Dynamic> j = m.scene->calcLinkJacobian(
        articulation, link, Eigen::Map<const Eigen::Vector3d>(point_in_link));
    // The ABI's layout is row-major.
    Eigen::Map<Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor>>(out, 6, count) = j;
  });
}

mb_status getRootLink(mb_scene* s, mb_id articulation, mb_id* out, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requirePointer(out, "output link id");
    *out = m.scene->getRootLink(articulation);
  });
}
mb_status setRootTwist(mb_scene* s, mb_id articulation, const double twist[6], mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requireStateChanges(m, "set_root_twist");
    requireArray(twist, 6, "twist");
    Twist t;
    t.angular = Eigen::Vector3d(twist[0], twist[1], twist[2]);
    t.linear = Eigen::Vector3d(twist[3], twist[4], twist[5]);
    if (!t.angular.allFinite() || !t.linear.allFinite())
      throw SceneError("set_root_twist: the twist of articulation '" + m.scene->getArticulationName(articulation) +
                       "' is not finite");
    m.scene->setRootTwist(articulation, t);
  });
}

mb_status addToMask(mb_scene* s, uint32_t mask_index, mb_id articulation, mb_id link,
                    const char* visual_name_part, mb_error* err) {
  return guarded(s, err, [&](mb_scene& m) {
    requireBuilding(m, "add_to_mask");
    // Without masks to collect into, every index is out of range.
    SegmentationMasks none;
    (m.masks ? *m.masks : none)
        .addVisuals(*m.scene, mask_index, articulation, link,
                    visual_name_part ? visual_name_part : "");
  });
}

const mb_scene_api kSceneApi = [] {
  mb_scene_api api{};
  api.struct_size = sizeof(mb_scene_api);
  api.abi_major = MB_ABI_MAJOR;
  api.abi_minor = MB_ABI_MINOR;
  api.add_ground = &addGround;
  api.add_urdf_file = &addUrdfFile;
  api.add_urdf_string = &addUrdfString;
  api.find_articulation = &findArticulation;
  api.find_link = &findLink;
  api.get_joint_count = &getJointCount;
  api.get_joint_info = &getJointInfo;
  api.find_joint = &findJoint;
  api.get_time = &getTime;
  api.get_joint_positions = &getJointPositions;
  api.get_joint_velocities = &getJointVelocities;
  api.get_root_pose = &getRootPose;
  api.get_link_pose = &getLinkPose;
  api.get_link_twist = &getLinkTwist;
  api.get_contact_force = &calcContactForce;
  api.set_joint_positions = &setJointPositions;
  api.set_joint_velocities = &setJointVelocities;
  api.set_root_pose = &setRootPose;
  api.set_joint_dynamics = &setJointDynamics;
  api.add_to_mask = &addToMask;
  api.calc_link_jacobian = &calcLinkJacobian;
  api.get_root_link = &getRootLink;
  api.set_root_twist = &setRootTwist;
  return api;
}();

}  // namespace

SceneBridge::SceneBridge(Scene& scene, SegmentationMasks* masks) : handle_(new mb_scene) {
  handle_->scene = &scene;
  handle_->masks = masks;
}
SceneBridge::~SceneBridge() { delete handle_; }
const mb_scene_api* SceneBridge::getApi() { return &kSceneApi; }
mb_scene* SceneBridge::getHandle() { return handle_; }
void SceneBridge::setBuilding(bool building) { handle_->building = building; }
void SceneBridge::setStateChangesAllowed(bool allowed) { handle_->state_changes_allowed = allowed; }

mb_joint_info makeJointInfo(const JointDescription& joint, const char* name) {
  mb_joint_info info{};
  info.name = name;
  info.type = static_cast<uint32_t>(joint.type);
  info.index = static_cast<uint32_t>(joint.index);
  info.lower = joint.lower;
  info.upper = joint.upper;
  info.velocity_limit = joint.velocity_limit;
  info.effort_limit = joint.effort_limit;
  return info;
}

}  // namespace manibench
