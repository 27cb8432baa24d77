// The mobile Panda robots of the ManiSkill tasks (assets/robots/
// mobile_panda_{single,dual}.*, docs/robot.md) as a task family uses them:
// their YAML facts (joints, initial configuration with the task's lift
// height, head cameras at the task's height) and the robot's own part of
// a state observation (ManiSkill's agent vector with every joint, then each
// arm's TCP pose); what every task on them does the same way (describing
// the robot, adding it to the scene, placing it facing a target) and what
// their scripted experts read (the robot's observation segments and the
// mobile_panda_ee controller's action segments, both by name).
#pragma once

#include <manibench/kit/common.hpp>
#include <manibench/kit/policy_math.hpp>
#include <manibench/kit/urdf.hpp>
#include <manibench/sdk/data.hpp>
#include <manibench/sdk/policy.hpp>
#include <manibench/sdk/random.hpp>
#include <manibench/sdk/task.hpp>

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
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

// The robots' folder: the task's `robot_dir` key when set, else the one
// of the manibench installation the plugin runs under
// (sdk::findDataDirectory("robots"), sdk/data.hpp).
inline std::string readRobotDir(const sdk::Config& config) {
  return config.has("robot_dir") ? config.get<std::string>("robot_dir", "") : sdk::findDataDirectory("robots");
}

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
  // The facts of <robot_dir>/<robot>.yaml for `task` (loadFacts), which
  // must describe `arms` arms and `joints` joints (what the task's
  // observation layout and expert assume); errors name the file.
  AgentState(const std::string& robot_dir, const std::string& robot, const std::string& task, std::size_t arms,
             std::size_t joints)
      : AgentState(loadFacts(robot_dir, robot, task)) {
    if (facts_.tcp_links.size() != arms || facts_.joints.size() != joints)
      throw Error(task + ": " + robot_dir + "/" + robot + ".yaml: expected " + std::to_string(joints) +
                      " joints and " + std::to_string(arms) + (arms == 1 ? " arm" : " arms") + ", got " +
                      std::to_string(facts_.joints.size()) + " and " + std::to_string(facts_.tcp_links.size()),
                  MB_ERROR);
  }

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

  // What every task on the robot describes alike: the robot's part of the
  // state observation (the task appends its own segments), the robot
  // (articulation "robot", every joint actuated), the mobile_panda
  // controller at 100 Hz with frame skip 5, and 200 steps an episode.
  sdk::TaskSpec describeTask() const {
    sdk::TaskSpec spec;
    spec.observation = describe();
    spec.agent_state_dim = getDim();
    spec.robot_articulation = "robot";
    spec.actuated_joints = facts_.joints;
    spec.default_controller = "mobile_panda";
    spec.control_frequency = 100;
    spec.frame_skip = 5;
    spec.max_episode_steps = 200;
    return spec;
  }

  // The finger pads' contact entries of a task's configuration layer
  // (ManiSkill v1: friction 2), one line per pad, under `bodies:`.
  std::string getFingerFrictionYaml() const {
    std::string yaml;
    for (const std::string& finger : facts_.finger_links)
      yaml += "      - {articulation: robot, link: " + finger + ", static_friction: 2.0, dynamic_friction: 2.0}\n";
    return yaml;
  }

  // While building: adds the robot (articulation "robot", fixed base: the
  // base moves on its planar joints) and binds it.
  mb_id addTo(SceneView& scene) {
    const mb_id robot = scene.addUrdfFile(facts_.urdf, "robot", Pose(), /*fixed_base=*/true);
    bind(scene, robot);
    return robot;
  }

  // At reset (supplement B.2): the robot in its initial configuration,
  // `distance` from `target` (x, y) at `bearing` (rad), its heading
  // bearing + `turn` (+-pi: facing the target) plus U(-0.05 pi, 0.05 pi)
  // drawn from `rng`, at rest.
  void placeFacing(SceneView& scene, sdk::Random& rng, const Eigen::Vector2d& target, double distance,
                   double bearing, double turn) const {
    const double heading = bearing + turn + rng.uniform(-0.05 * kPi, 0.05 * kPi);
    Eigen::VectorXd q = facts_.initial;
    q[0] = target.x() + distance * std::cos(bearing);
    q[1] = target.y() + distance * std::sin(bearing);
    q[2] = std::remainder(heading, 2 * kPi);
    scene.setJointPositions(robot_, q);
    scene.setJointVelocities(robot_, Eigen::VectorXd::Zero(q.size()));
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
    bindBodyLinks(scene);
  }

  const std::vector<mb_id>& getFingers() const { return fingers_; }
  const std::vector<mb_id>& getTcps() const { return tcps_; }
  // The robot's links with collision geometry, fingers left out: the arm,
  // the hand, the body.
  const std::vector<mb_id>& getBodyLinks() const { return body_links_; }

  // Whether arm `arm`'s two fingers both press on `link` (more than
  // `min_force` N each): the gripper holds it. One contact query per finger.
  bool isHolding(const SceneView& scene, mb_id link, std::size_t arm = 0, double min_force = 1.0) const {
    for (std::size_t k = 2 * arm; k < 2 * arm + 2; ++k)
      if (!(scene.calcContactForce(fingers_.at(k), link).norm() > min_force)) return false;
    return true;
  }
  // The largest contact force (N) on one of the robot's body links (not
  // its fingers): from the object, the ground or anything else the body
  // runs into. One contact query per body link: for diagnostics (progress
  // signals), not for every step of a fast loop.
  double calcBodyContactForce(const SceneView& scene) const {
    double most = 0;
    for (const mb_id link : body_links_) most = std::max(most, scene.calcContactForce(link).norm());
    return most;
  }

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
      putPose(out, uint32_t(at), scene.getLinkPose(tcp));
      at += 7;
    }
  }

 private:
  Facts facts_;
  // The links of the robot's URDF that have a <collision>, but the fingers.
  void bindBodyLinks(const SceneView& scene) {
    body_links_.clear();
    std::ifstream in(facts_.urdf);
    const urdf::Tree tree = urdf::readTree(in, "URDF " + facts_.urdf);
    for (const urdf::Tree::Link& link : tree.links) {
      if (std::find(facts_.finger_links.begin(), facts_.finger_links.end(), link.name) != facts_.finger_links.end())
        continue;
      if (link.element != nullptr && link.element->count("collision") > 0)
        body_links_.push_back(scene.findLink(robot_, link.name));
    }
  }

  mb_id robot_ = -1;
  std::vector<mb_id> fingers_, tcps_, body_links_;
};

// ---- what the experts read -------------------------------------------------

// The robot's segments of a state observation, looked up by name in the
// policy's layout (AgentState::describe() names them): the base, the
// joints and each arm's TCP pose (right arm first).
struct AgentOffsets {
  uint32_t base_position = 0, base_yaw = 0, joint_positions = 0;
  std::vector<uint32_t> tcp_poses;

  AgentOffsets() = default;
  // `policy` names the policy in errors.
  AgentOffsets(const sdk::Layout& observation, std::size_t arms, const std::string& policy) {
    auto find = [&](const std::string& name, uint32_t size) {
      const sdk::Segment* s = observation.find(name);
      if (s == nullptr || s->size != size)
        throw Error(policy + " needs the mobile Panda's state observation (segment '" + name + "' of size " +
                        std::to_string(size) + " is missing)",
                    MB_INVALID_ARGUMENT);
      return s->offset;
    };
    base_position = find("base_position", 2);
    base_yaw = find("base_yaw", 1);
    const sdk::Segment* joints = observation.find("joint_positions");
    if (joints == nullptr) find("joint_positions", 0);  // throws
    joint_positions = joints->offset;
    if (arms == 1)
      tcp_poses = {find("tcp_pose", 7)};
    else
      tcp_poses = {find("right_tcp_pose", 7), find("left_tcp_pose", 7)};
  }

  // The robot as a step's state observation shows it.
  struct Reading {
    Eigen::Vector2d base;  // x, y, world
    double yaw = 0, lift = 0;
    Eigen::Matrix3d base_rotation;  // base frame -> world: about z by yaw
    std::vector<Eigen::Vector3d> tcp;  // per arm (right first), world
    std::vector<Eigen::Matrix3d> tcp_rotation;
  };
  Reading read(const Eigen::VectorXd& state) const {
    Reading r;
    r.base = Eigen::Vector2d(state[base_position], state[base_position + 1]);
    r.yaw = state[base_yaw];
    r.lift = state[joint_positions + 3];
    r.base_rotation = Eigen::AngleAxisd(r.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (const uint32_t at : tcp_poses) {
      r.tcp.push_back(getVector3(state, at));
      r.tcp_rotation.push_back(getQuaternion(state, at + 3).toRotationMatrix());
    }
    return r;
  }
};

// The mobile_panda_ee controller's action, its segments bound by name:
// base_forward, base_left, base_yaw and lift (consecutive, from `base`),
// and per arm (right first) the end effector's linear and angular
// velocities and the gripper.
struct EeAction {
  struct Arm {
    uint32_t linear = 0, angular = 0, gripper = 0;
  };
  Eigen::Index dim = 0;
  uint32_t base = 0;
  std::vector<Arm> arms;

  EeAction() = default;
  // `arms`: 1 (the single-arm robot, whose arm is the right one) or 2.
  // Errors name `policy` and say how to run it.
  EeAction(const sdk::Layout& action, std::size_t arms, const std::string& policy) : dim(action.dim) {
    const std::vector<const char*> sides = arms == 1 ? std::vector<const char*>{"right"}
                                                     : std::vector<const char*>{"right", "left"};
    std::vector<std::pair<std::string, uint32_t>> wanted = {
        {"base_forward", 1}, {"base_left", 1}, {"base_yaw", 1}, {"lift", 1}};
    for (const char* side : sides)
      for (const auto& [part, size] : {std::pair<const char*, uint32_t>{"_ee_linear", 3}, {"_ee_angular", 3}, {"_gripper", 1}})
        wanted.emplace_back(side + std::string(part), size);
    for (const auto& [name, size] : wanted) {
      const sdk::Segment* s = action.find(name);
      if (s == nullptr || s->size != size)
        throw Error(policy + " needs the mobile_panda_ee controller" + (arms == 1 ? "" : " on the dual-arm robot") +
                        " (action segment '" + name + "' of size " + std::to_string(size) +
                        " is missing); leave --controller out (it chooses mobile_panda_ee)",
                    MB_INVALID_ARGUMENT);
    }
    base = action.get("base_forward").offset;
    if (action.get("base_left").offset != base + 1 || action.get("base_yaw").offset != base + 2 ||
        action.get("lift").offset != base + 3)
      throw Error(policy + ": base_forward, base_left, base_yaw, lift must be consecutive", MB_INVALID_ARGUMENT);
    for (const char* side : sides)
      this->arms.push_back({action.get(side + std::string("_ee_linear")).offset,
                            action.get(side + std::string("_ee_angular")).offset,
                            action.get(side + std::string("_gripper")).offset});
  }
};

// An expert's checks of what it is given: one of `tasks`, and the state
// observation (its privileged part is what it reads).
inline void requireStateObservation(const sdk::PolicyContext& context, const std::string& policy,
                                    const std::vector<std::string>& tasks, uint32_t dim) {
  bool known = false;
  std::string names;
  for (const std::string& t : tasks) {
    known = known || t == context.task_name;
    names += (names.empty() ? "" : " and ") + t;
  }
  if (!known)
    throw Error(policy + " drives " + names + ", not '" + context.task_name + "'", MB_INVALID_ARGUMENT);
  if (context.observation_mode != "state" || context.observation.dim != dim)
    throw Error(policy + " needs the state observation (" + std::to_string(dim) + " values), got mode '" +
                    context.observation_mode + "' with " + std::to_string(context.observation.dim),
                MB_INVALID_ARGUMENT);
}

// A scripted expert over mobile_panda_ee on the state observation: what
// every one checks and binds alike, and its phase (an enum whose first
// value is where an episode starts) with the steps spent in it.
template <class Phase>
class Expert : public sdk::Policy {
 public:
  // Checks the task (one of `tasks`) and the state observation (`dim`
  // values), binds the robot's observation segments and the action of
  // `arms` arms; errors name the policy `name`.
  Expert(const sdk::PolicyContext& context, const std::string& name, const std::vector<std::string>& tasks,
         uint32_t dim, std::size_t arms) {
    requireStateObservation(context, name, tasks, dim);
    agent_ = AgentOffsets(context.observation, arms, name);
    action_ = EeAction(context.action, arms, name);
  }
  void reset(uint64_t) override { enter(Phase{}); }

 protected:
  void enter(Phase phase) {
    phase_ = phase;
    phase_steps_ = 0;
  }
  Phase phase_{};
  uint32_t phase_steps_ = 0;
  AgentOffsets agent_;  // the robot's observation segments
  EeAction action_;     // mobile_panda_ee's action segments
};

}  // namespace manibench::kit::mobile_panda
