// OpenCabinetDoor / OpenCabinetDrawer: the mobile Panda opens one door or
// drawer of a cabinet by its handle (ManiSkill v1, supplement B.2-B.4,
// C.1.1). Cabinets come from a procedural generator (cabinet_generator.cpp)
// or, when the task config names a folder, from PartNet-Mobility objects
// (partnet_loader.cpp). An object id names a cabinet AND its target link
// ("1003_link_1"), as ManiSkill's per-link levels do: the masks (handle,
// target link, robot) are assigned while the scene is built.
#pragma once

#include <manibench/kit/family.hpp>

namespace open_cabinet {

using namespace manibench::kit;  // kit/family.hpp

enum class TargetKind { kDoor, kDrawer };

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
  // The handle's extent in its grasp frame (m): x its depth out of the
  // panel, y its width across the grip (what the fingers close on), z its
  // length along the grip.
  Eigen::Vector3d handle_size = Eigen::Vector3d::Zero();
  std::string handle_type;          // bar, knob, boxed (generator); mesh (PartNet)
};

// One cabinet: its URDF and what the tasks need to know about it.
struct CabinetModel {
  std::string id;
  std::string urdf;      // URDF text
  std::string base_dir;  // for relative mesh paths ("" for generated ones)
  std::vector<TargetLink> targets;  // doors and drawers with handles
  // Handled doors and drawers that are no target, each with its reason.
  std::vector<std::pair<TargetKind, std::string>> refused;
  std::vector<std::string> getRefused(TargetKind kind) const;
  // Where the cabinet frame goes in the world (puts its bottom on the
  // ground), and its axis-aligned extent there (front faces -x), m.
  Eigen::Vector3d placement = Eigen::Vector3d::Zero();
  Eigen::Vector3d lower = Eigen::Vector3d::Zero(), upper = Eigen::Vector3d::Zero();
  std::string summary;  // one line: size, grid, handle types
  double scale = 1;     // PartNet: applied to every length of the file

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
// The cabinet's scale and, for ManiSkill v1's own ids, how many door and
// drawer targets v1 had, come from its object facts (`facts`:
// assets/objects/open_cabinet.yaml, kit/object_facts.hpp); it stands with
// its joints at their lower limits.
CabinetModel loadPartNetCabinet(const std::string& folder, const std::string& id, const ObjectFacts& facts);

// ---- object ids ------------------------------------------------------------

// "<cabinet>_link_<k>" -> {"<cabinet>", "link_<k>"}; throws MB_NOT_FOUND.
std::pair<std::string, std::string> splitObjectId(const std::string& object_id);

// ---- the state observation, shared with the expert --------------------------

// After the robot's part (the kit's AgentState: ManiSkill's agent vector,
// then the TCP pose; experts find its segments by name), the cabinet's.
struct ObservationLayout {
  static constexpr uint32_t kAgentDim = 51;
  static constexpr uint32_t kTargetLinkPose = 51;       // 7
  static constexpr uint32_t kTargetJoint = 58;          // 4: q, qdot, lower, upper
  static constexpr uint32_t kTargetJointType = 62;      // 1: 0 door (revolute), 1 drawer
  static constexpr uint32_t kJointAxis = 63;            // 3: world, opening direction
  static constexpr uint32_t kJointOrigin = 66;          // 3: a point on the axis, world
  static constexpr uint32_t kHandlePose = 69;           // 7: grasp frame, world
  static constexpr uint32_t kHandleHalfLength = 76;     // 1
  static constexpr uint32_t kCabinetCenter = 77;        // 3: cabinet bounding box centre
  static constexpr uint32_t kHandleSize = 80;           // 3: TargetLink::handle_size
  static constexpr uint32_t kDim = 83;
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

class OpenCabinetTask : public sdk::Task {
 public:
  OpenCabinetTask(const Config& config, TargetKind kind);

  sdk::TaskSpec describe() const override;
  std::vector<std::string> listObjects(const std::string& split) const override;
  void buildScene(SceneView& scene, const std::string& object_id) override;
  void reset(SceneView& scene, uint64_t seed) override;
  void observe(const SceneView& scene, Eigen::Map<Eigen::VectorXd> out) override;
  double computeReward(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) override;
  std::vector<sdk::Condition> evaluateSuccess(const SceneView& scene) override;
  // reached (the gripper within kContactDistance of the grip), holding
  // (both fingers press on the target link), progress (the opened fraction
  // over B.4's), blocked (the robot's body touches anything), opened (the
  // opened fraction of the joint range: the evaluation's opening curve).
  std::vector<double> measureProgress(const SceneView& scene) const override;
  std::string getObjectCategory(const std::string& object_id) const override;

  // The reward as a function of the quantities it reads (C.1.1), for tests:
  // gripper-handle distance (m), opened fraction of the joint range, target
  // link speed (m/s) and angular speed (rad/s).
  static double calcStagedReward(double handle_distance, double open_fraction,
                                 double linear_speed, double angular_speed) {
    return open_cabinet::calcStagedReward(handle_distance, open_fraction, linear_speed, angular_speed);
  }

 private:
  struct Measured {
    double q = 0, qdot = 0, open_fraction = 0;
    double handle_distance = 0;
    double linear_speed = 0, angular_speed = 0;
  };
  Measured measure(const SceneView& scene) const;
  Pose calcHandlePose(const SceneView& scene) const;
  Eigen::Vector3d calcGripperPoint(const SceneView& scene) const;

  TargetKind kind_;
  double static_speed_, static_angular_speed_;
  uint32_t hold_steps_;
  // the robot's facts (assets/robots/mobile_panda_single.yaml) and state
  std::unique_ptr<mobile_panda::AgentState> robot_;
  ObjectCatalog<CabinetModel> cabinets_;
  // the scene
  std::shared_ptr<const CabinetModel> cabinet_;
  const TargetLink* target_ = nullptr;
  mb_id robot_id_ = -1, cabinet_id_ = -1, target_link_ = -1, tcp_ = -1;
  uint32_t target_joint_ = 0;
  double lower_ = 0, upper_ = 1;
  uint32_t cabinet_joint_count_ = 0;
  Eigen::VectorXd closed_q_;  // every joint at its lower limit (0 if none)
};

class OpenCabinetDoorTask : public OpenCabinetTask {
 public:
  explicit OpenCabinetDoorTask(const Config& config) : OpenCabinetTask(config, TargetKind::kDoor) {}
};
class OpenCabinetDrawerTask : public OpenCabinetTask {
 public:
  explicit OpenCabinetDrawerTask(const Config& config) : OpenCabinetTask(config, TargetKind::kDrawer) {}
};

// The expert's phases, in order (an episode starts in the first).
enum class ExpertPhase { kApproach, kPreGrasp, kGrasp, kClose, kPull, kHold };

// Scripted expert over the mobile_panda_ee controller; reads the
// privileged state observation.
class OpenCabinetExpert : public mobile_panda::Expert<ExpertPhase> {
 public:
  explicit OpenCabinetExpert(const sdk::PolicyContext& context);
  void reset(uint64_t seed) override;
  Eigen::VectorXd act(const sdk::Observation& observation) override;

  struct View;     // what one step reads from the state (open_cabinet_expert.cpp)
  struct Command;  // the phase's TCP goal and gripper

 private:
  using Phase = ExpertPhase;
  View read(const sdk::Observation& observation) const;
  // One function per phase: each sets the TCP goal and gripper and says
  // when the next phase begins.
  void approach(const View& v, Command& c);  // kApproach and kPreGrasp
  void grasp(const View& v, Command& c);
  void closeFingers(const View& v, Command& c);
  void pull(const View& v, Command& c);
  // The whole robot servos the TCP to the goal.
  Eigen::VectorXd calcAction(const View& v, const Command& c) const;
  bool calcGraspTurned(const View& v) const;  // which of the hand's two grasps is nearer
  void toggleAcross(const View& v);            // grasp_across_ on or off
  double calcFacingYaw(const View& v) const;   // the base's yaw goal

  bool grasp_turned_ = false;  // grasps with the hand turned half a turn about its axis
  // After a grasp that never held: the hand turned a quarter turn about
  // its axis (by across_sign_), the fingers closing along the handle's
  // length (open_cabinet_expert.cpp, toggleAcross()).
  bool grasp_across_ = false;
  double across_sign_ = 1.0;

  bool nominal_ready_ = false;
  Eigen::Vector2d nominal_offset_ = Eigen::Vector2d::Zero();  // TCP from the base, base frame
  double nominal_height_ = 0;  // TCP height minus lift at the start
  double yaw_follow_ = 1.0;     // how much the base turns with a door
  double door_speed_ = 0.3;   // m/s of the handle along its arc
  double base_follow_ = 1.0;   // how much the base follows while pulling
  double pull_lift_ = 0;           // the lift when the pull began
  double pull_handle_height_ = 0;  // the handle's height then
  double pull_open_fraction_ = 0;  // the part's opened fraction then
  Eigen::Vector3d pull_grip_ = Eigen::Vector3d::Zero();  // the TCP then, in the handle's frame
};

}  // namespace open_cabinet
