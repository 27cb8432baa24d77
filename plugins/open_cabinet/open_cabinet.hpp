// OpenCabinetDoor / OpenCabinetDrawer: the mobile Panda opens one door or
// drawer of a cabinet by its handle (ManiSkill v1, supplement B.2-B.4,
// C.1.1). Cabinets come from a procedural generator (cabinet_generator.cpp)
// or, when the task config names a folder, from PartNet-Mobility objects
// (partnet_loader.cpp). An object id names a cabinet AND its target link
// ("1003_link_1"), as ManiSkill's per-link levels do: the masks (handle,
// target link, robot) are assigned while the scene is built.
#pragma once

#include <manibench/sdk.hpp>
#include <manibench/kit/mobile_panda.hpp>
#include <manibench/sdk/random.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace open_cabinet {

enum class TargetKind { kDoor, kDrawer };

// The SDK's fully specified generator (splitmix64) and id hash (FNV-1a).
using manibench::sdk::Random;
using manibench::sdk::hashString;

// A door or drawer the robot can be asked to open: a link with a handle
// and a revolute (door) or prismatic (drawer) joint.
struct TargetLink {
  std::string link;    // URDF link name
  std::string joint;   // URDF joint name (the link's parent joint)
  TargetKind kind = TargetKind::kDoor;
  // Joint axis in the link frame (URDF: the joint frame is the link frame),
  // signed so that increasing q opens.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  // The handle's grasp frame in the link frame: origin at the middle of
  // the grip, x out of the panel (towards whoever opens it), z along the
  // grip (the fingers close across it).
  Eigen::Vector3d handle_position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d handle_rotation = Eigen::Matrix3d::Identity();
  double handle_half_length = 0.0;  // m, along the grip
  std::string handle_type;          // bar, knob, boxed (generator); mesh (PartNet)
};

// One cabinet: its URDF and what the tasks need to know about it.
struct CabinetModel {
  std::string id;
  std::string urdf;      // URDF text
  std::string base_dir;  // for relative mesh paths ("" for generated ones)
  std::vector<TargetLink> targets;  // doors and drawers with handles
  // Where the cabinet frame goes in the world (puts its bottom on the
  // ground), and its axis-aligned extent there (front faces -x), m.
  Eigen::Vector3d placement = Eigen::Vector3d::Zero();
  Eigen::Vector3d lower = Eigen::Vector3d::Zero(), upper = Eigen::Vector3d::Zero();
  std::string summary;  // one line: size, grid, handle types

  std::vector<const TargetLink*> getTargets(TargetKind kind) const;
};

// ---- procedural generator (cabinet_generator.cpp) ----------------------------

enum class CellKind { kDoorLeftHinge, kDoorRightHinge, kDrawer, kShelf };
enum class HandleType { kBar, kKnob, kBoxed };

struct HandleParams {
  HandleType type = HandleType::kBar;
  double length = 0.15;    // grip length, m (knob: head size)
  double thickness = 0.015;  // grip cross-section, m
  double standoff = 0.045;   // panel front to grip axis, m
  double offset = 0.06;      // doors: grip axis from the free edge, m
};

// Every parameter of a generated cabinet (see kGeneratorRanges in the .cpp).
struct CabinetParams {
  double width = 0.8, height = 0.8, depth = 0.45, wall = 0.02;
  int rows = 1, cols = 1;
  std::vector<CellKind> cells;  // row-major, row 0 at the bottom, col 0 at -y
  std::vector<double> door_limits;    // rad, per cell (doors only)
  HandleParams handle;
  std::array<double, 3> body_color{}, front_color{}, handle_color{};
};

// The parameters of a generated cabinet id (throws MB_NOT_FOUND for ids the
// generator does not know); the same id always gives the same cabinet.
CabinetParams getCabinetParams(const std::string& cabinet_id);
CabinetModel generateCabinet(const std::string& cabinet_id);
// Generated cabinet ids of a task kind and split.
std::vector<std::string> listGeneratedCabinets(TargetKind kind, const std::string& split);
std::string toString(HandleType type);

// ---- PartNet-Mobility (partnet_loader.cpp) ------------------------------------

// Loads <folder>/<id>/mobility.urdf and semantics.txt through the SDK's
// PartNet reader (manibench/kit/partnet.hpp). Handles are the
// visuals whose name contains "handle"; targets are links with a handle
// and a revolute/continuous (door) or prismatic (drawer) joint.
CabinetModel loadPartNetCabinet(const std::string& folder, const std::string& id);
// Sub-folders of `folder` holding a mobility.urdf, sorted; with a split,
// those of the split (`folder`/test.txt lists the test ids).
std::vector<std::string> listPartNetCabinets(const std::string& folder);
std::vector<std::string> listPartNetCabinets(const std::string& folder, const std::string& split);

// ---- object ids ------------------------------------------------------------

// "<cabinet>_link_<k>" -> {"<cabinet>", "link_<k>"}; throws MB_NOT_FOUND.
std::pair<std::string, std::string> splitObjectId(const std::string& object_id);

// ---- the state observation, shared with the expert --------------------------

struct ObservationLayout {
  // robot (38 as ManiSkill's agent vector, then the TCP pose)
  static constexpr uint32_t kFingertipPositions = 0;    // 6: left, right pad
  static constexpr uint32_t kFingertipVelocities = 6;   // 6
  static constexpr uint32_t kBasePosition = 12;         // 2: x, y
  static constexpr uint32_t kBaseYaw = 14;              // 1
  static constexpr uint32_t kBaseVelocity = 15;         // 2: world x, y
  static constexpr uint32_t kBaseAngularVelocity = 17;  // 1
  static constexpr uint32_t kJointPositions = 18;       // 13
  static constexpr uint32_t kJointVelocities = 31;      // 13
  static constexpr uint32_t kTcpPose = 44;              // 7: position, quaternion wxyz
  // object
  static constexpr uint32_t kTargetLinkPose = 51;       // 7
  static constexpr uint32_t kTargetJoint = 58;          // 4: q, qdot, lower, upper
  static constexpr uint32_t kTargetJointType = 62;      // 1: 0 door (revolute), 1 drawer
  static constexpr uint32_t kJointAxis = 63;            // 3: world, opening direction
  static constexpr uint32_t kJointOrigin = 66;          // 3: a point on the axis, world
  static constexpr uint32_t kHandlePose = 69;           // 7: grasp frame, world
  static constexpr uint32_t kHandleHalfLength = 76;     // 1
  static constexpr uint32_t kCabinetCenter = 77;        // 3: cabinet bounding box centre
  static constexpr uint32_t kDim = 80;
};

constexpr uint32_t kRobotDof = 13;

// ---- reward (C.1.1) -------------------------------------------------------------

constexpr double kContactDistance = 0.06;  // m: the second stage starts
constexpr double kOpenFraction = 0.9;      // B.4

// Three stages, each strictly above every reward of the one before, and
// continuous where the first two meet: d = gripper-handle distance (m), f =
// opened fraction of the joint range, v / w = target link speed (m/s, rad/s).
inline double calcStagedReward(double d, double open_fraction, double v, double w) {
  const double f = std::clamp(open_fraction, 0.0, 1.0);
  // Stage 3 (opened enough): at least -3 + 2 * 0.9, above every stage-2
  // reward; settle the link (speed penalty bounded by tanh), open fully.
  if (f >= kOpenFraction)
    return -3.0 + 2.0 * kOpenFraction + 0.5 * (1.0 - std::tanh(v + 0.5 * w)) +
           0.5 * std::min(1.0, (f - kOpenFraction) / (1.0 - kOpenFraction));
  // Stage 2 (gripper within reach of the handle): opening pays; equal to
  // stage 1 at d = kContactDistance, f = 0, and above all of it inside.
  if (d < kContactDistance) return -3.0 - 2.0 * d + 2.0 * f;
  // Stage 1 (approach): the gripper-handle distance.
  return -3.0 - 2.0 * d;
}

class OpenCabinetTask : public manibench::sdk::Task {
 public:
  OpenCabinetTask(const manibench::sdk::Config& config, TargetKind kind);

  manibench::sdk::TaskSpec describe() const override;
  std::vector<std::string> listObjects(const std::string& split) const override;
  void buildScene(manibench::sdk::SceneView& scene, const std::string& object_id) override;
  void reset(manibench::sdk::SceneView& scene, uint64_t seed) override;
  void observe(const manibench::sdk::SceneView& scene, Eigen::Map<Eigen::VectorXd> out) override;
  double computeReward(const manibench::sdk::SceneView& scene,
                       Eigen::Map<const Eigen::VectorXd> action) override;
  std::vector<manibench::sdk::Condition> evaluateSuccess(
      const manibench::sdk::SceneView& scene) override;

  // The reward as a function of the quantities it reads (C.1.1), for tests:
  // gripper-handle distance (m), opened fraction of the joint range, target
  // link speed (m/s) and angular speed (rad/s).
  static double calcStagedReward(double handle_distance, double open_fraction,
                                 double linear_speed, double angular_speed) {
    return open_cabinet::calcStagedReward(handle_distance, open_fraction, linear_speed, angular_speed);
  }

 private:
  const CabinetModel& getCabinet(const std::string& cabinet_id) const;
  struct Measured {
    double q = 0, qdot = 0, open_fraction = 0;
    double handle_distance = 0;
    double linear_speed = 0, angular_speed = 0;
  };
  Measured measure(const manibench::sdk::SceneView& scene) const;
  manibench::sdk::Pose calcHandlePose(const manibench::sdk::SceneView& scene) const;
  Eigen::Vector3d calcGripperPoint(const manibench::sdk::SceneView& scene) const;

  TargetKind kind_;
  std::string partnet_dir_;
  std::string robot_dir_;
  double static_speed_, static_angular_speed_;
  uint32_t hold_steps_;
  // the robot's facts (assets/robots/mobile_panda_single.yaml) and state
  std::unique_ptr<manibench::kit::mobile_panda::AgentState> robot_;
  mutable std::map<std::string, std::shared_ptr<CabinetModel>> cabinets_;
  // PartNet cabinets listObjects skipped (and warned about once).
  mutable std::set<std::string> skipped_;
  // the scene
  std::shared_ptr<CabinetModel> cabinet_;
  const TargetLink* target_ = nullptr;
  mb_id robot_id_ = -1, cabinet_id_ = -1, target_link_ = -1, tcp_ = -1;
  uint32_t target_joint_ = 0;
  double lower_ = 0, upper_ = 1;
  Eigen::Vector3d joint_axis_local_ = Eigen::Vector3d::UnitZ();
  uint32_t cabinet_joint_count_ = 0;
};

class OpenCabinetDoorTask : public OpenCabinetTask {
 public:
  explicit OpenCabinetDoorTask(const manibench::sdk::Config& config)
      : OpenCabinetTask(config, TargetKind::kDoor) {}
};
class OpenCabinetDrawerTask : public OpenCabinetTask {
 public:
  explicit OpenCabinetDrawerTask(const manibench::sdk::Config& config)
      : OpenCabinetTask(config, TargetKind::kDrawer) {}
};

// Scripted expert over the mobile_panda_ee controller; reads the
// privileged state observation.
class OpenCabinetExpert : public manibench::sdk::Policy {
 public:
  explicit OpenCabinetExpert(const manibench::sdk::PolicyContext& context);
  void reset(uint64_t seed) override;
  Eigen::VectorXd act(const manibench::sdk::Observation& observation) override;

 private:
  enum class Phase { kApproach, kPreGrasp, kGrasp, kClose, kPull, kHold };
  Phase phase_ = Phase::kApproach;
  uint32_t phase_steps_ = 0;
  Eigen::Index action_dim_ = 11;
  uint32_t base_ = 0, ee_linear_ = 4, ee_angular_ = 7, gripper_ = 10;
  bool nominal_ready_ = false;
  Eigen::Vector2d nominal_offset_ = Eigen::Vector2d::Zero();  // TCP from the base, base frame
  double nominal_height_ = 0;  // TCP height minus lift at the start
  double yaw_follow_ = 1.0;     // how much the base turns with a door
  double door_speed_ = 0.3;   // m/s of the handle along its arc
  double base_follow_ = 1.0;   // how much the base follows while pulling
};

}  // namespace open_cabinet
