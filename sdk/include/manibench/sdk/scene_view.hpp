// SceneView: the host's scene API (mb_scene_api) as a C++ object with Eigen
// types. Every failure the host reports becomes an sdk::Error carrying the
// host's message, so plugin code reads like ordinary C++.
#pragma once

#include <manibench/sdk/common.hpp>

#include <string>

namespace manibench::sdk {

struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();

  Eigen::Isometry3d toIsometry() const {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = orientation.toRotationMatrix();
    t.translation() = position;
    return t;
  }
  static Pose fromC(const mb_pose& p) {
    Pose out;
    out.position = Eigen::Vector3d(p.position[0], p.position[1], p.position[2]);
    out.orientation = Eigen::Quaterniond(p.quaternion[0], p.quaternion[1],
                                         p.quaternion[2], p.quaternion[3]);
    return out;
  }
  mb_pose toC() const {
    mb_pose p;
    for (int i = 0; i < 3; ++i) p.position[i] = position[i];
    p.quaternion[0] = orientation.w();
    p.quaternion[1] = orientation.x();
    p.quaternion[2] = orientation.y();
    p.quaternion[3] = orientation.z();
    return p;
  }
};

struct Twist {
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
};

class SceneView {
 public:
  SceneView(const mb_scene_api* api, mb_scene* scene) : api_(api), scene_(scene) {
    if (api_ == nullptr || scene_ == nullptr)
      throw Error("the host passed no scene", MB_INVALID_ARGUMENT);
    if (api_->abi_major != MB_ABI_MAJOR)
      throw Error("host scene API is ABI " + std::to_string(api_->abi_major) +
                  ", this plugin was built for " + std::to_string(MB_ABI_MAJOR));
  }

  const mb_scene_api* api() const { return api_; }
  mb_scene* handle() const { return scene_; }

  // --- building ----------------------------------------------------------
  void addGround(double height = 0) {
    call("add_ground", required(&mb_scene_api::add_ground), height);
  }
  mb_id addUrdfFile(const std::string& path, const std::string& name,
                    const Pose& root, bool fixed_base) {
    mb_id id = -1;
    const mb_pose p = root.toC();
    call("add_urdf_file", required(&mb_scene_api::add_urdf_file), path.c_str(),
         name.c_str(), &p, int32_t(fixed_base), &id);
    return id;
  }
  mb_id addUrdfString(const std::string& urdf_xml, const std::string& base_dir,
                      const std::string& name, const Pose& root,
                      bool fixed_base) {
    mb_id id = -1;
    const mb_pose p = root.toC();
    call("add_urdf_string", required(&mb_scene_api::add_urdf_string),
         urdf_xml.c_str(), base_dir.c_str(), name.c_str(), &p,
         int32_t(fixed_base), &id);
    return id;
  }

  // --- lookup --------------------------------------------------------------
  mb_id findArticulation(const std::string& name) const {
    mb_id id = -1;
    call("find_articulation", required(&mb_scene_api::find_articulation),
         name.c_str(), &id);
    return id;
  }
  mb_id findLink(mb_id articulation, const std::string& link_name) const {
    mb_id id = -1;
    call("find_link", required(&mb_scene_api::find_link), articulation,
         link_name.c_str(), &id);
    return id;
  }
  uint32_t getJointCount(mb_id articulation) const {
    uint32_t n = 0;
    call("get_joint_count", required(&mb_scene_api::get_joint_count),
         articulation, &n);
    return n;
  }
  mb_joint_info getJointInfo(mb_id articulation, uint32_t joint) const {
    mb_joint_info info{};
    call("get_joint_info", required(&mb_scene_api::get_joint_info),
         articulation, joint, &info);
    return info;
  }
  uint32_t findJoint(mb_id articulation, const std::string& joint_name) const {
    uint32_t index = 0;
    call("find_joint", required(&mb_scene_api::find_joint), articulation,
         joint_name.c_str(), &index);
    return index;
  }

  // --- state ---------------------------------------------------------------
  double getTime() const {
    double t = 0;
    call("get_time", required(&mb_scene_api::get_time), &t);
    return t;
  }
  Eigen::VectorXd getJointPositions(mb_id articulation) const {
    Eigen::VectorXd q(getJointCount(articulation));
    call("get_joint_positions", required(&mb_scene_api::get_joint_positions),
         articulation, q.data(), uint32_t(q.size()));
    return q;
  }
  Eigen::VectorXd getJointVelocities(mb_id articulation) const {
    Eigen::VectorXd v(getJointCount(articulation));
    call("get_joint_velocities", required(&mb_scene_api::get_joint_velocities),
         articulation, v.data(), uint32_t(v.size()));
    return v;
  }
  Pose getRootPose(mb_id articulation) const {
    mb_pose p{};
    call("get_root_pose", required(&mb_scene_api::get_root_pose), articulation,
         &p);
    return Pose::fromC(p);
  }
  Pose getLinkPose(mb_id link) const {
    mb_pose p{};
    call("get_link_pose", required(&mb_scene_api::get_link_pose), link, &p);
    return Pose::fromC(p);
  }
  // ABI 1.3: the root link's id (its URDF's root) and a floating root's
  // twist, without the URDF's link names.
  mb_id getRootLink(mb_id articulation) const {
    mb_id link = -1;
    call("get_root_link", required(&mb_scene_api::get_root_link), articulation, &link);
    return link;
  }
  Twist getRootTwist(mb_id articulation) const { return getLinkTwist(getRootLink(articulation)); }
  Twist getLinkTwist(mb_id link) const {
    double v[6] = {0, 0, 0, 0, 0, 0};
    call("get_link_twist", required(&mb_scene_api::get_link_twist), link, v);
    Twist t;
    t.angular = Eigen::Vector3d(v[0], v[1], v[2]);
    t.linear = Eigen::Vector3d(v[3], v[4], v[5]);
    return t;
  }
  // Contact force on link_a from link_b (from anything when link_b < 0),
  // world frame: the host computes the contacts for it (hence calc; the ABI
  // function keeps its 1.0 name).
  Eigen::Vector3d calcContactForce(mb_id link_a, mb_id link_b = -1) const {
    double f[3] = {0, 0, 0};
    call("get_contact_force", required(&mb_scene_api::get_contact_force),
         link_a, link_b, f);
    return Eigen::Vector3d(f[0], f[1], f[2]);
  }
  [[deprecated("use calcContactForce")]] Eigen::Vector3d getContactForce(
      mb_id link_a, mb_id link_b = -1) const {
    return calcContactForce(link_a, link_b);
  }

  void setJointPositions(mb_id articulation, const Eigen::VectorXd& q) {
    call("set_joint_positions", required(&mb_scene_api::set_joint_positions),
         articulation, q.data(), uint32_t(q.size()));
  }
  void setJointVelocities(mb_id articulation, const Eigen::VectorXd& qdot) {
    call("set_joint_velocities", required(&mb_scene_api::set_joint_velocities),
         articulation, qdot.data(), uint32_t(qdot.size()));
  }
  // ABI 1.3. Floating roots: angular velocity, then the root link origin's
  // velocity, world frame.
  void setRootTwist(mb_id articulation, const Twist& twist) {
    const double v[6] = {twist.angular.x(), twist.angular.y(), twist.angular.z(),
                         twist.linear.x(),  twist.linear.y(),  twist.linear.z()};
    call("set_root_twist", required(&mb_scene_api::set_root_twist), articulation, v);
  }
  void setRootPose(mb_id articulation, const Pose& pose) {
    const mb_pose p = pose.toC();
    call("set_root_pose", required(&mb_scene_api::set_root_pose), articulation,
         &p);
  }
  void setJointDynamics(mb_id articulation, uint32_t joint, double damping,
                        double friction) {
    call("set_joint_dynamics", required(&mb_scene_api::set_joint_dynamics),
         articulation, joint, damping, friction);
  }

  // --- ABI 1.1 --------------------------------------------------------------
  // 6 x n geometric Jacobian (angular rows, then linear rows of the point;
  // world frame) of a point on `link` with respect to the n joint velocities
  // of `articulation`.
  Eigen::MatrixXd calcLinkJacobian(
      mb_id articulation, mb_id link,
      const Eigen::Vector3d& point_in_link = Eigen::Vector3d::Zero()) const {
    const uint32_t n = getJointCount(articulation);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> j(6, n);
    call("calc_link_jacobian", required(&mb_scene_api::calc_link_jacobian),
         articulation, link, point_in_link.data(), j.data(), n);
    return j;
  }
  // While building: visuals of `link` whose name contains `visual_name_part`
  // (all of them when empty) join mask `mask_index` of the task's masks.
  void addLinkToMask(uint32_t mask_index, mb_id articulation, mb_id link,
                     const std::string& visual_name_part = "") {
    call("add_to_mask", required(&mb_scene_api::add_to_mask), mask_index,
         articulation, link, visual_name_part.c_str());
  }
  // While building: every visual of `articulation` joins mask `mask_index`.
  void addArticulationToMask(uint32_t mask_index, mb_id articulation) {
    call("add_to_mask", required(&mb_scene_api::add_to_mask), mask_index,
         articulation, mb_id(-1), static_cast<const char*>(nullptr));
  }

 private:
  // A function the plugin needs but the host's (older) API table lacks.
  template <class Fn>
  Fn mb_scene_api::*required(Fn mb_scene_api::*member) const {
    const std::size_t end =
        std::size_t(reinterpret_cast<const char*>(&(api_->*member)) -
                    reinterpret_cast<const char*>(api_)) +
        sizeof(Fn);
    if (end > api_->struct_size || api_->*member == nullptr)
      throw Error("the host's scene API (ABI " +
                      std::to_string(api_->abi_major) + "." +
                      std::to_string(api_->abi_minor) +
                      ") does not provide a function this plugin needs",
                  MB_UNSUPPORTED);
    return member;
  }

  template <class Fn, class... Args>
  void call(const char* what, Fn mb_scene_api::*member, Args... args) const {
    char buffer[1024] = {0};
    mb_error err{buffer, sizeof(buffer)};
    const mb_status status = (api_->*member)(scene_, args..., &err);
    if (status != MB_OK)
      throw Error(std::string(buffer[0] ? buffer : what), status);
  }

  const mb_scene_api* api_;
  mb_scene* scene_;
};

}  // namespace manibench::sdk
