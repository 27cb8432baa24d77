// The mobile Panda robots of the ManiSkill tasks (assets/robots/
// mobile_panda_{single,dual}.*, docs/robot.md) as a task family uses them:
// their YAML facts (joints, initial configuration with the task's lift
// height, head cameras at the task's height) and the robot's own part of
// a state observation (ManiSkill's agent vector with every joint, then each
// arm's TCP pose). Header-only; include <manibench/kit/mobile_panda.hpp>.
#pragma once

#include <manibench/kit/common.hpp>

#include <yaml-cpp/yaml.h>

#include <sstream>
#include <string>
#include <vector>

namespace manibench::kit::mobile_panda {

// Finger pad centre in its finger's frame (the URDF's pad collision box).
inline const Eigen::Vector3d& getPadOffset() {
  static const Eigen::Vector3d offset(0.0, 0.0076, 0.045);
  return offset;
}

struct Facts {
  std::string urdf;                  // path of the robot's URDF
  std::vector<std::string> joints;   // actuated joints, in action order
  Eigen::VectorXd initial;           // base x, y, yaw (0), the task's lift, every arm and finger
  std::vector<std::string> finger_links;  // per arm: left finger, right finger
  std::vector<std::string> tcp_links;     // per arm (right arm first)
  std::vector<std::string> arm_sides;     // "right", "left"
  std::string camera_yaml;           // a `cameras:` list: the head cameras at the task's height
};

// Reads <robot_dir>/<robot>.yaml (robot: mobile_panda_single or
// mobile_panda_dual) for `task` (the key of its lift_height and
// mount_height entries, e.g. "PushChair"). Errors name the file.
inline Facts loadFacts(const std::string& robot_dir, const std::string& robot, const std::string& task) {
  const std::string path = robot_dir + "/" + robot + ".yaml";
  Facts f;
  f.urdf = robot_dir + "/" + robot + ".urdf";
  YAML::Node facts;
  try {
    facts = YAML::LoadFile(path);
    f.joints = facts["joints"].as<std::vector<std::string>>();
    const YAML::Node init = facts["initial_configuration"];
    std::vector<double> q = init["base"].as<std::vector<double>>();
    const YAML::Node lift = facts["lift_height"][task];
    q.push_back(lift ? lift.as<double>() : init["lift"].as<double>());
    for (const YAML::Node& arm : facts["arms"]) {
      for (double x : init["arm"].as<std::vector<double>>()) q.push_back(x);
      for (double x : init["fingers"].as<std::vector<double>>()) q.push_back(x);
      const auto fingers = arm["finger_links"].as<std::vector<std::string>>();
      f.finger_links.insert(f.finger_links.end(), fingers.begin(), fingers.end());
      f.tcp_links.push_back(arm["tcp_link"].as<std::string>());
      f.arm_sides.push_back(arm["side"].as<std::string>());
    }
    if (q.size() != f.joints.size() || f.finger_links.size() != 2 * f.tcp_links.size())
      throw Error(path + ": the initial configuration (" + std::to_string(q.size()) + " values) or the arms' finger " +
                      "links do not match the " + std::to_string(f.joints.size()) + " joints",
                  MB_ERROR);
    f.initial = Eigen::Map<const Eigen::VectorXd>(q.data(), Eigen::Index(q.size()));
    // The head cameras, as camera entries of the configuration.
    const YAML::Node cams = facts["cameras"];
    const YAML::Node heights = cams["mount_height"];
    const double mount_z = heights[task] ? heights[task].as<double>() : heights["default"].as<double>();
    std::ostringstream yaml;
    yaml << "cameras:\n";
    for (const YAML::Node& m : cams["mounts"]) {
      const auto xyz = m["xyz"].as<std::vector<double>>();
      const auto rpy = m["rpy"].as<std::vector<double>>();
      if (xyz.size() != 3 || rpy.size() != 3)  // (indexing a short list would read past it)
        throw Error(path + ": camera mount " + m["name"].as<std::string>("?") + " needs xyz and rpy of 3 values",
                    MB_INVALID_ARGUMENT);
      yaml << "  - name: " << m["name"].as<std::string>() << "\n    articulation: robot\n    link: "
           << m["parent_link"].as<std::string>() << "\n    pose: {position: [" << xyz[0] << ", " << xyz[1] << ", "
           << mount_z << "], rpy: [" << rpy[0] << ", " << rpy[1] << ", " << rpy[2] << "]}\n    width: "
           << cams["width"].as<int>() << "\n    height: " << cams["height"].as<int>() << "\n    fovy: "
           << cams["fovy"].as<double>() << "\n    near: " << cams["near"].as<double>() << "\n    far: "
           << cams["far"].as<double>() << "\n";
    }
    f.camera_yaml = yaml.str();
  } catch (const YAML::Exception& e) {
    throw Error("cannot read the robot facts " + path + " (set task.robot_dir): " + e.what(), MB_NOT_FOUND);
  }
  return f;
}

// The robot's part of a state observation, in this order: finger pad
// positions and velocities (3 per pad, the arms in the YAML's order), base
// x, y, yaw, base velocity x, y, yaw rate, every joint's q and qdot, each
// arm's TCP pose (position, quaternion wxyz).
class AgentState {
 public:
  explicit AgentState(Facts facts) : facts_(std::move(facts)) {}

  const Facts& getFacts() const { return facts_; }

  uint32_t getDim() const {
    const auto pads = uint32_t(facts_.finger_links.size()), n = uint32_t(facts_.joints.size());
    return 6 * pads + 6 + 2 * n + 7 * uint32_t(facts_.tcp_links.size());
  }

  std::vector<Segment> describe() const {
    const bool one = facts_.tcp_links.size() == 1;
    const auto pads = uint32_t(facts_.finger_links.size()), n = uint32_t(facts_.joints.size());
    std::vector<Segment> s = {
        {"fingertip_positions", 3 * pads,
         one ? "left, right finger pad centres, world (m)"
             : "finger pad centres, world (m): right arm left, right pad; left arm left, right pad"},
        {"fingertip_velocities", 3 * pads, "of the pad centres, world (m/s)"},
        {"base_position", 2, "x, y of base_link, world (m)"},
        {"base_yaw", 1, "heading (rad)"},
        {"base_velocity", 2, "world x, y (m/s)"},
        {"base_angular_velocity", 1, "yaw rate (rad/s)"},
        {"joint_positions", n, "robot q, actuated joint order"},
        {"joint_velocities", n, "robot qdot, actuated joint order"},
    };
    for (const std::string& side : facts_.arm_sides)
      s.push_back({one ? "tcp_pose" : side + "_tcp_pose", 7,
                   (one ? std::string("gripper") : side + " gripper") +
                       " TCP (between the pads): position, quaternion wxyz, world"});
    return s;
  }

  // While building: finds the links and checks that the scene's joint
  // order is the action order.
  void bind(const SceneView& scene, mb_id robot) {
    robot_ = robot;
    for (std::size_t i = 0; i < facts_.joints.size(); ++i)
      if (scene.findJoint(robot, facts_.joints[i]) != i)
        throw Error("robot joint " + facts_.joints[i] + " is not at index " + std::to_string(i) + " of " + facts_.urdf);
    fingers_.clear();
    tcps_.clear();
    for (const std::string& l : facts_.finger_links) fingers_.push_back(scene.findLink(robot, l));
    for (const std::string& l : facts_.tcp_links) tcps_.push_back(scene.findLink(robot, l));
  }

  const std::vector<mb_id>& getFingers() const { return fingers_; }
  const std::vector<mb_id>& getTcps() const { return tcps_; }

  // World positions of the finger pads, in the observation's order.
  std::vector<Eigen::Vector3d> calcPadPositions(const SceneView& scene) const {
    std::vector<Eigen::Vector3d> out;
    for (const mb_id finger : fingers_) {
      const Pose pose = scene.getLinkPose(finger);
      out.push_back(pose.position + pose.orientation * getPadOffset());
    }
    return out;
  }

  // Writes getDim() values at the start of `out`.
  void observe(const SceneView& scene, Eigen::Ref<Eigen::VectorXd> out) const {
    Eigen::Index at = 0;
    const auto pads = Eigen::Index(fingers_.size());
    for (Eigen::Index k = 0; k < pads; ++k) {
      const Pose pose = scene.getLinkPose(fingers_[std::size_t(k)]);
      const Twist twist = scene.getLinkTwist(fingers_[std::size_t(k)]);
      const Eigen::Vector3d r = pose.orientation * getPadOffset();
      out.segment<3>(3 * k) = pose.position + r;
      out.segment<3>(3 * pads + 3 * k) = twist.linear + twist.angular.cross(r);
    }
    at = 6 * pads;
    const Eigen::VectorXd q = scene.getJointPositions(robot_);
    const Eigen::VectorXd qd = scene.getJointVelocities(robot_);
    out.segment<2>(at) = q.head<2>();
    out[at + 2] = q[2];
    out.segment<2>(at + 3) = qd.head<2>();
    out[at + 5] = qd[2];
    at += 6;
    out.segment(at, q.size()) = q;
    out.segment(at + q.size(), qd.size()) = qd;
    at += 2 * q.size();
    for (const mb_id tcp : tcps_) {
      const Pose p = scene.getLinkPose(tcp);
      out.segment<3>(at) = p.position;
      out.segment<4>(at + 3) << p.orientation.w(), p.orientation.x(), p.orientation.y(), p.orientation.z();
      at += 7;
    }
  }

 private:
  Facts facts_;
  mb_id robot_ = -1;
  std::vector<mb_id> fingers_, tcps_;
};

}  // namespace manibench::kit::mobile_panda
