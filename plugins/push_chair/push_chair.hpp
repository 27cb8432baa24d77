// PushChair-v0: the dual-arm mobile Panda pushes a swivel chair on casters
// to a target point on the ground (ManiSkill v1, supplement B.2-B.4,
// C.1.2). Chairs come from a procedural generator (chair_generator.cpp)
// or, when the task config names a folder, from PartNet-Mobility objects
// (partnet_chair_loader.cpp, over the SDK's manibench/kit/partnet.hpp).
#pragma once

#include <manibench/kit/family.hpp>

namespace push_chair {

using namespace manibench::kit;  // kit/family.hpp

// How the task randomizes a chair joint's friction and damping per episode
// (maniskill-v1-facts.md): the seat's swivel differs from the rest.
enum class JointRole { kSeat, kCasterSwivel, kWheel, kBackrest, kArmrest, kOther };

struct ChairJoint {
  std::string name;
  JointRole role = JointRole::kOther;
  // Casters: the wheel's radius (wheel joints) or the trail, swivel axis to
  // wheel axle (swivel joints), m: how far from the joint the floor pushes.
  double lever = 0;
};

// Points on the chair's surface, in one link's frame: what the reward
// measures the end effectors' distance to (ManiSkill uses the chair's
// point cloud).
struct LinkPoints {
  std::string link;
  std::vector<Eigen::Vector3d> points;
};

// One chair: its URDF and what the task needs to know about it.
struct ChairModel {
  std::string id;
  std::string urdf;      // URDF text; the root link is the star base
  std::string base_dir;  // for relative mesh paths ("" for generated ones)
  std::string root_link = "base";  // the chair's pose and speed are this link's
  double root_height = 0;  // where the root frame goes above the ground (wheels on it)
  std::vector<ChairJoint> joints;        // every movable joint, with its role
  std::vector<std::string> wheel_links;  // the links that touch the ground (friction 1.0)
  std::string seat_link;
  Eigen::Vector3d seat_top = Eigen::Vector3d::Zero();  // seat surface centre, seat link frame
  double footprint_radius = 0.35;  // root axis to the farthest wheel, m
  double height = 1.0;             // top of the chair above the ground, m
  std::vector<LinkPoints> surface;
  std::string summary;  // one line: design and sizes
};

// ---- procedural generator (chair_generator.cpp) ----------------------------

enum class BackrestShape { kRectangular, kRounded, kHeadrest, kCurved };
enum class ArmrestType { kNone, kFixedT, kLoop, kAdjustableT };

// Every parameter of a generated chair (see the ranges in the .cpp); m, rad.
struct ChairParams {
  int legs = 5;
  double base_radius = 0.34;     // hub axis to caster swivel axis
  double hub_radius = 0.05, hub_height = 0.13;  // hub centre above the ground
  double wheel_radius = 0.03;
  double caster_trail = 0.03;    // swivel axis to wheel axle, horizontal
  double caster_drop = 0.045;    // swivel mount above the wheel axle
  double column_radius = 0.028;
  double seat_height = 0.46;     // top of the cushion above the ground
  double seat_width = 0.48, seat_depth = 0.46, seat_thickness = 0.08;
  double seat_offset = 0.02;     // cushion centre ahead of the column
  BackrestShape backrest = BackrestShape::kRectangular;
  double backrest_width = 0.44, backrest_height = 0.5, backrest_thickness = 0.05;
  double backrest_gap = 0.07;    // cushion top to backrest bottom
  double backrest_angle = 0.15;  // lean back from vertical at rest
  bool reclining = false;        // backrest on a joint (range [0, backrest_angle])
  ArmrestType armrest = ArmrestType::kNone;
  double armrest_height = 0.22;  // pad above the cushion top
  std::array<double, 3> frame_color{}, seat_color{};
};

// The parameters of a generated chair id (throws MB_NOT_FOUND for ids the
// generator does not know); the same id always gives the same chair.
ChairParams getChairParams(const std::string& chair_id);
ChairModel generateChair(const std::string& chair_id);
ChairModel generateChair(const std::string& chair_id, const ChairParams& params);
// Generated chair ids of a split.
std::vector<std::string> listGeneratedChairs(const std::string& split);
std::string toString(BackrestShape shape);
std::string toString(ArmrestType type);

// ---- PartNet-Mobility (partnet_chair_loader.cpp) -----------------------------

// Loads <folder>/<id>/ through the SDK's PartNet reader, scaled by `scale`
// (ManiSkill: 0.8). Wheels are the links labelled wheel (else caster) in
// semantics.txt; the seat the link labelled seat.
ChairModel loadPartNetChair(const std::string& folder, const std::string& id, double scale);

// Points every `spacing` m over the surface of the shapes of `model`'s
// links (both sources use it).
std::vector<Eigen::Vector3d> sampleBoxSurface(const Eigen::Isometry3d& pose, const Eigen::Vector3d& size,
                                              double spacing);

// ---- the state observation, shared with the expert --------------------------

constexpr uint32_t kRobotDof = 22;
constexpr uint32_t kMaxChairJoints = 20;

// After the robot's part (the kit's AgentState: the dual-arm ManiSkill
// agent vector with all 22 joints, then both TCP poses; experts find its
// segments by name), the chair's and the target.
struct ObservationLayout {
  static constexpr uint32_t kAgentDim = 88;
  static constexpr uint32_t kChairPose = 88;              // 7: root link, position, quaternion wxyz
  static constexpr uint32_t kChairVelocity = 95;          // 3: root link, world
  static constexpr uint32_t kChairAngularVelocity = 98;   // 3
  static constexpr uint32_t kChairJointPositions = 101;   // 20, zero past the chair's joints
  static constexpr uint32_t kChairJointVelocities = 121;  // 20
  static constexpr uint32_t kSeatTop = 141;               // 3: seat surface centre, world
  static constexpr uint32_t kTarget = 144;                // 3: the target point on the ground
  static constexpr uint32_t kDim = 147;
};

// ---- reward (C.1.2) and success (B.4) ----------------------------------------

constexpr double kNearDistance = 0.1;     // m: end effectors at the chair (stage 2)
constexpr double kTargetRadius = 0.15;    // m: the chair at the target (stage 3, success)
constexpr double kUprightTilt = 0.05 * manibench::sdk::kPi;  // success: not fallen
constexpr double kFallenTilt = 0.2 * manibench::sdk::kPi;    // reward: fallen over

// What the reward reads, measured each step.
struct RewardInput {
  double ee_distance = 1;   // mean over the 4 finger pads of the distance to the chair, m
  double target_distance = 1;  // chair root to the target, horizontal, m
  double speed = 0;         // chair root speed, m/s
  double angular_speed = 0;  // rad/s
  double speed_to_target = 0;  // component of the root velocity towards the target, m/s
  double tilt = 0;          // angle between the root's z axis and the vertical, rad
  double action_norm = 0;
  bool is_static = false;   // speed and angular speed within the success thresholds
};

// Three stages with ManiSkill's stage constants (-10, +2 per stage, -5
// fallen, all times 2), each stage strictly above every reward of the one
// before. Stage 1 (approach): -d - min(log d, 0) of the end effectors'
// distance d. Stage 2 (end effectors within 10 cm, chair upright): the
// approach term frozen at its 10 cm value, 2 (1 - exp(-v_t)) for the speed
// towards the target, -1.8 tanh(distance to target). Stage 3 (chair within
// 15 cm of the target, upright): 2 exp(-10 v), +2 while static. Every
// stage: -0.2 tilt and -1e-6 |a|.
double calcStagedReward(const RewardInput& in);
int calcRewardStage(const RewardInput& in);  // 1, 2 or 3

// ---- the task ---------------------------------------------------------------------

class PushChairTask : public sdk::Task {
 public:
  explicit PushChairTask(const Config& config);

  sdk::TaskSpec describe() const override;
  std::vector<std::string> listObjects(const std::string& split) const override;
  void buildScene(SceneView& scene, const std::string& object_id) override;
  void reset(SceneView& scene, uint64_t seed) override;
  void observe(const SceneView& scene, Eigen::Map<Eigen::VectorXd> out) override;
  double computeReward(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) override;
  std::vector<sdk::Condition> evaluateSuccess(const SceneView& scene) override;

 private:
  RewardInput measure(const SceneView& scene) const;
  double calcPadDistance(const SceneView& scene) const;
  // reached (the pads within the reward's 10 cm of the chair), progress
  // (the way to the target's radius covered), fallen (past the upright
  // tilt).
  std::vector<double> measureProgress(const SceneView& scene) const override;
  std::string getObjectCategory(const std::string& object_id) const override {
    return chairs_.getCategory(object_id);
  }

  double static_speed_, static_angular_speed_;
  uint32_t hold_steps_;
  // the robot's facts (assets/robots/mobile_panda_dual.yaml) and state
  std::unique_ptr<mobile_panda::AgentState> robot_;
  ObjectCatalog<ChairModel> chairs_;
  // the scene
  std::shared_ptr<const ChairModel> chair_;
  mb_id robot_id_ = -1, chair_id_ = -1, root_link_ = -1, seat_link_ = -1;
  std::vector<mb_id> surface_links_;
  uint32_t chair_joint_count_ = 0;
  std::vector<ChairJoint> joint_roles_;  // per scene joint
  Eigen::Vector3d target_ = Eigen::Vector3d::Zero();
  double start_distance_ = 1;  // the chair's from the target at reset (m)
};

// The expert's phases, in order (an episode starts in the first).
enum class ExpertPhase { kApproach, kPush, kRelease };

// Scripted expert over the mobile_panda_ee controller (dual arm); reads the
// privileged state observation.
class PushChairExpert : public mobile_panda::Expert<ExpertPhase> {
 public:
  explicit PushChairExpert(const sdk::PolicyContext& context);
  void reset(uint64_t seed) override;
  Eigen::VectorXd act(const sdk::Observation& observation) override;

  struct View;     // what one step reads from the state (push_chair_expert.cpp)
  struct Command;  // the base's velocity and heading

 private:
  using Phase = ExpertPhase;
  View read(const sdk::Observation& observation) const;
  // One function per phase: each sets the base's command and says when
  // the next phase begins.
  void approach(const View& v, Command& c);
  void push(const View& v, Command& c);
  void release(const View& v, Command& c);
  // The base, the lift and the two hands (a rigid paddle) as commanded.
  Eigen::VectorXd calcAction(const View& v, const Command& c) const;

  bool nominal_ready_ = false;
  std::array<Eigen::Matrix3d, 2> nominal_rotation_{};  // TCP orientation in the base frame at the start
  double nominal_height_ = 0;  // the TCPs' mean height above the lift at the start
  int orbit_sign_ = 0;         // the way round the chair, chosen once when it is a half turn
  bool orbiting_ = false;      // going round the chair (last step's choice: the hands ride higher)
};

}  // namespace push_chair
