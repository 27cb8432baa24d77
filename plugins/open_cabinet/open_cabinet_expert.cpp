// Scripted expert for OpenCabinetDoor-v0 / OpenCabinetDrawer-v0 over the
// mobile_panda_ee controller. Privileged: it reads the handle's grasp frame
// and the target joint from the state observation.
//
// The whole robot servos to one goal for the TCP: the base keeps the TCP
// goal at the offset from the base it had at the start (the canonical arm
// pose, comfortable for the arm) and faces the handle, the lift keeps the
// goal's height within the arm's reach, the arm closes the rest. Phases:
// pre-grasp 12 cm in front of the grip, grasp, close, pull (drawers along
// their axis, doors along the handle's arc: the goal leads the handle along
// its direction of motion, the grasp frame and the base turn with the door),
// hold. A handle that slips out while pulling is let go and grasped again
// (a quarter turn about the hand's axis if the grasp never held).
#include "open_cabinet.hpp"

#include <manibench/kit/policy_math.hpp>

#include <algorithm>
#include <cmath>

namespace open_cabinet {
namespace {

constexpr double kBaseSpeed = MobilePandaSpeeds::kBase;  // per unit action
constexpr double kEeSpeed = MobilePandaSpeeds::kEeLinear, kEeAngularSpeed = MobilePandaSpeeds::kEeAngular;
constexpr double kDoorLead = 0.02;  // m: how far the goal leads a door's handle
// A finger's travel over the gripper action's range (-1 closed, +1 open:
// assets/robots/mobile_panda_single.yaml, finger_position 0 to 0.04 m).
constexpr double kFingerTravel = 0.04;
// The fingers open this much wider than the handle on each side: the
// approach hands over to the grasp within 1 cm of its goal (approach()),
// and 5 mm more keeps a pad off the handle's edge. Opened fully (8 cm),
// a finger reached past the handle into what stands around it: a table
// top over a drawer, a door's frame (the survey's not_grasped: 12 of 28
// table drawer episodes, 10 of 50 cabinet door episodes, before).
constexpr double kFingerClearance = 0.015;
// The level hand's TCP comes no lower than this above the ground: its
// palm spans some 20 cm across the grip, and on a horizontal bar the
// fingers close vertically (on the survey's lowest level bar the TCP
// stopped at 0.100 m over a handle at 0.063 m: docs/partnet.md). Lower
// grips are grasped tilted, by up to kLowGripTilt for a grip at the
// ground.
constexpr double kLowestLevelGrasp = 0.11;
constexpr double kLowGripTilt = M_PI / 3;

}  // namespace

OpenCabinetExpert::OpenCabinetExpert(const sdk::PolicyContext& context)
    : Expert(context, "open_cabinet_expert", {"OpenCabinetDoor-v0", "OpenCabinetDrawer-v0"}, ObservationLayout::kDim, 1) {}

void OpenCabinetExpert::reset(uint64_t seed) {
  Expert::reset(seed);
  nominal_ready_ = false;
  grasp_turned_ = false;
  grasp_across_ = false;
}

struct OpenCabinetExpert::View {
  mobile_panda::AgentOffsets::Reading robot;
  Eigen::Vector3d tcp;
  Eigen::Vector3d handle, hx;  // the handle's grasp frame: position, x (out of the handle)
  Eigen::Matrix3d handle_rotation;  // that frame's axes
  bool door = false;
  double open_fraction = 0;
  double angle = 0;              // a door's: its joint from closed (rad)
  Eigen::Vector3d axis, origin;  // the target joint's
  double qdot = 0;               // its speed
  double fingers = 0;            // opening, m
  double open_action = 1;        // the gripper action that opens the fingers just around the handle
  double length = 0;             // the handle's extent along the grip (handle_size's z)
  Eigen::Vector3d motion;        // the handle's direction of motion as the joint opens
  Eigen::Matrix3d grasp_rotation;       // the TCP's at the grasp
  Eigen::Vector3d out;                  // the way the hand comes to the grip from (hx unless tilted)
  Eigen::AngleAxisd orientation_error;  // from the TCP to the grasp orientation
};

struct OpenCabinetExpert::Command {
  Eigen::Vector3d goal;
  double gripper = 1.0;
  double lead_speed = 0.0;  // m/s along the motion while pulling
};

OpenCabinetExpert::View OpenCabinetExpert::read(const sdk::Observation& observation) const {
  using L = ObservationLayout;
  const Eigen::VectorXd s = observation.state;
  View v;
  v.robot = agent_.read(s);
  v.tcp = v.robot.tcp[0];
  v.handle = getVector3(s, L::kHandlePose);
  const Eigen::Matrix3d hr = getQuaternion(s, L::kHandlePose + 3).toRotationMatrix();
  const Eigen::Vector3d hx = hr.col(0), hy = hr.col(1), hz = hr.col(2);
  v.hx = hx;
  v.handle_rotation = hr;
  v.door = s[L::kTargetJointType] < 0.5;
  const double q = s[L::kTargetJoint], lower = s[L::kTargetJoint + 2], upper = s[L::kTargetJoint + 3];
  v.open_fraction = (q - lower) / (upper - lower);
  v.angle = v.door ? q - lower : 0.0;
  v.axis = getVector3(s, L::kJointAxis);
  v.origin = getVector3(s, L::kJointOrigin);
  v.qdot = s[L::kTargetJoint + 1];
  v.fingers = s[agent_.joint_positions + 11] + s[agent_.joint_positions + 12];
  // Each finger half the handle's width out from the grip, plus the
  // clearance; the whole travel where the handle is wider than that.
  const double across = s[L::kHandleSize + (grasp_across_ ? 2 : 1)];
  const double finger = std::min(across / 2 + kFingerClearance, kFingerTravel);
  v.open_action = 2 * finger / kFingerTravel - 1;
  v.length = s[L::kHandleSize + 2];
  const Eigen::Vector3d motion = v.door ? v.axis.cross(v.handle - v.origin) : v.axis;
  v.motion = motion.norm() > 1e-9 ? Eigen::Vector3d(motion.normalized()) : Eigen::Vector3d(hx);
  v.grasp_rotation = (Eigen::Matrix3d() << hz, hy, -hx).finished();
  if (grasp_turned_) v.grasp_rotation = v.grasp_rotation * Eigen::Vector3d(-1, -1, 1).asDiagonal();
  if (grasp_across_)
    v.grasp_rotation = v.grasp_rotation * Eigen::AngleAxisd(across_sign_ * M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  v.out = hx;
  // A level grip lower than the hand's reach down: tilted about the grip
  // (the TCP's x) so that the hand comes from above, the fingers still
  // closing across the grip.
  if (std::abs(hz.z()) < 0.5 && v.handle.z() < kLowestLevelGrasp) {
    const double tilt = kLowGripTilt * std::clamp((kLowestLevelGrasp - v.handle.z()) / kLowestLevelGrasp, 0.0, 1.0);
    for (const double sign : {1.0, -1.0}) {
      const Eigen::Matrix3d r = v.grasp_rotation * Eigen::AngleAxisd(sign * tilt, Eigen::Vector3d::UnitX()).toRotationMatrix();
      if (-r.col(2).z() > 0) {
        v.grasp_rotation = r;
        v.out = -r.col(2);
        break;
      }
    }
  }
  v.orientation_error = Eigen::AngleAxisd(v.grasp_rotation * v.robot.tcp_rotation[0].transpose());
  return v;
}

// The Panda's hand is symmetric under half a turn about its own axis, so
// either of two TCP rotations grasps the handle. Taking always the first
// drove the wrist (joint 7) into its limit on most objects: on a drawer the
// hand stopped 0.5 rad short and the approach waited out its 90-step
// timeout at the pre-grasp pose, a pause the state does not explain (so a
// policy cloned from it learned to stay there). Chosen once per episode,
// in the base's frame with the base facing the handle as it will.
bool OpenCabinetExpert::calcGraspTurned(const View& v) const {
  const double yaw_goal = std::atan2(-v.hx.y(), -v.hx.x());
  const Eigen::Matrix3d base_goal = Eigen::AngleAxisd(yaw_goal, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d tcp_in_base = v.robot.base_rotation.transpose() * v.robot.tcp_rotation[0];
  const Eigen::Matrix3d grasp_in_base = base_goal.transpose() * v.grasp_rotation;
  const Eigen::Matrix3d turned_in_base = grasp_in_base * Eigen::Vector3d(-1, -1, 1).asDiagonal();
  const auto angle = [&](const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r * tcp_in_base.transpose()).angle(); };
  return angle(turned_in_base) < angle(grasp_in_base);
}

// The yaw that faces the handle: the closed door's facing (its grasp
// frame's x turned back by the joint's angle, level) turned by the door's
// turn about the vertical. A door hinged on a vertical side turns the base
// with it, as before; a flap hinged at its top or bottom does not turn it
// at all: its grasp frame's x tilts up or down as it opens, and level
// it points straight up or down at 90 degrees, where the yaw read from it
// would flip by half a turn.
double OpenCabinetExpert::calcFacingYaw(const View& v) const {
  Eigen::Vector3d facing = v.hx;
  if (v.door) {
    const Eigen::Vector3d closed = Eigen::AngleAxisd(-v.angle, v.axis) * v.hx;
    facing = Eigen::AngleAxisd(v.angle * v.axis.z(), Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(closed.x(), closed.y(), 0);
  }
  return std::atan2(-facing.y(), -facing.x());
}

// To 12 cm in front of the grip (after a slip: open in place first).
void OpenCabinetExpert::approach(const View& v, Command& c) {
  c.goal = v.handle + 0.12 * v.out;
  if (phase_ == Phase::kPreGrasp && phase_steps_ < 5) {
    c.goal = v.tcp;
    return;
  }
  const double error = (c.goal - v.tcp).norm();
  const double angle_error = std::abs(v.orientation_error.angle());
  if ((error < 0.025 && angle_error < 0.1) || (phase_steps_ > 90 && error < 0.04)) enter(Phase::kGrasp);
}

// A pull whose part did not move with the hand slipped off a grasp that
// never held: on the survey's recessed table drawers (25913) the pull
// stands in a slot hardly taller than the fingers, which are about 1 cm
// thick outside their pads and closing across the slot met its frame
// (docs/partnet.md). Where the handle is no longer than the fingers open
// around, the next grasp turns the hand a quarter turn about its axis: the
// fingers close along the handle's length and stand only their width
// (about 2 cm) across it. A pull that opened the part by more than
// kHeldMotion of its range held it (the slips of grasps that never held
// moved it 0-0.2 %).
constexpr double kHeldMotion = 0.02;

// Turns the grasp a quarter turn about the hand's axis, or back: of the
// two quarter turns, the one nearer the hand as it is.
void OpenCabinetExpert::toggleAcross(const View& v) {
  if (grasp_across_) {
    grasp_across_ = false;
    return;
  }
  const auto error = [&](double sign) {
    const Eigen::Matrix3d r =
        v.grasp_rotation * Eigen::AngleAxisd(sign * M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    return Eigen::AngleAxisd(r * v.robot.tcp_rotation[0].transpose()).angle();
  };
  across_sign_ = error(1.0) <= error(-1.0) ? 1.0 : -1.0;
  grasp_across_ = true;
}

void OpenCabinetExpert::grasp(const View& v, Command& c) {
  c.goal = v.handle + 0.005 * v.out;
  if ((c.goal - v.tcp).norm() < 0.01 || phase_steps_ > 20) enter(Phase::kClose);
}

void OpenCabinetExpert::closeFingers(const View& v, Command& c) {
  c.gripper = -1.0;
  if (phase_steps_ > 5) {
    enter(Phase::kPull);
    pull_lift_ = v.robot.lift;
    pull_handle_height_ = v.handle.z();
    pull_open_fraction_ = v.open_fraction;
    pull_grip_ = v.handle_rotation.transpose() * (v.tcp - v.handle);
  }
}

void OpenCabinetExpert::pull(const View& v, Command& c) {
  c.gripper = -1.0;
  // ramp up: breaking the joint's friction loose at full speed tears
  // the handle out of the fingers
  c.lead_speed = std::min(v.door ? door_speed_ : 0.18, 0.05 + 0.02 * phase_steps_);
  // Drawers: the goal leads the handle. Doors: a short lead with a stiff
  // gain, so that the pull never exceeds what the fingers hold by
  // friction (a heavily damped door then just opens slower).
  //
  //
  // A door's goal leads the point where the fingers closed (pull_grip_,
  // moving with the handle), not the handle's centre: where the hand could
  // not reach the centre (the grasp phase timed out with the fingertips
  // against the door, 2.4 cm out on procedural door 1038), the fingers
  // held the bar's front, ahead of the centre by more than the door's 2 cm
  // lead, so a goal that led the centre lay behind the hand, and the pull
  // pressed the door shut for the rest of the episode: all of the
  // procedural doors' 40 failures in 1020 episodes (max opened 0). A
  // drawer's lead grows to 3.6 cm with its speed and pulled such grips
  // open; leading its grip too pulled harder at the end, and 4 of the
  // survey's 80 drawer episodes (1 before) ended not static.
  const Eigen::Vector3d grip = v.door ? Eigen::Vector3d(v.handle + v.handle_rotation * pull_grip_) : v.handle;
  c.goal = grip + (v.door ? kDoorLead : c.lead_speed / 5.0) * v.motion;
  const bool empty = v.fingers < 0.004;  // closed on nothing: the handle slipped out
  if (v.open_fraction > 0.94) {
    enter(Phase::kHold);
  } else if ((empty || (v.handle - v.tcp).norm() > 0.05) && phase_steps_ > 3) {
    // Let go and grasp again; if the part had not moved with the hand (the
    // grasp never held), the other way about the hand's axis where the
    // handle's length fits between the fingers (toggleAcross). A grasp
    // that moved it is kept: turned after every slip, also those at 47-99 %
    // open, 3 of the survey's 102 door episodes were lost and none gained.
    const bool held = v.open_fraction - pull_open_fraction_ > kHeldMotion;
    if (!held && (grasp_across_ || v.length / 2 + 0.005 <= kFingerTravel)) toggleAcross(v);
    enter(Phase::kPreGrasp);
  }
}

Eigen::VectorXd OpenCabinetExpert::calcAction(const View& v, const Command& c) const {
  const mobile_panda::AgentOffsets::Reading& robot = v.robot;
  const Eigen::Vector3d& tcp = v.tcp;
  const Eigen::Vector3d& goal = c.goal;
  const bool door = v.door;
  // Base: keep the goal at the nominal offset from the base.
  // Facing the handle; while a door turns, the base turns with it (the
  // arm alone runs out of wrist range), compensated in the arm below.
  const double yaw_goal = calcFacingYaw(v);
  const Eigen::Matrix2d goal_rotation = Eigen::Rotation2Dd(yaw_goal).toRotationMatrix();
  const Eigen::Vector2d base_goal = goal.head<2>() - goal_rotation * nominal_offset_;
  Eigen::Vector2d base_velocity = 3.0 * (base_goal - robot.base);
  const Eigen::Vector3d handle_velocity =
      door ? Eigen::Vector3d(v.qdot * v.axis.cross(v.handle - v.origin)) : Eigen::Vector3d(v.qdot * v.axis);
  if (phase_ == Phase::kPull)
    base_velocity = base_follow_ * (base_velocity + (door ? handle_velocity.head<2>() : Eigen::Vector2d(c.lead_speed * v.motion.head<2>())));
  // Where the arm alone falls short (reach, joint limits), the base helps.
  base_velocity += 1.5 * (goal - tcp).head<2>();
  if (phase_ == Phase::kHold || phase_ == Phase::kClose) base_velocity.setZero();
  base_velocity = clipNorm(base_velocity, kBaseSpeed);
  const Eigen::Vector2d base_local = Eigen::Rotation2Dd(-robot.yaw).toRotationMatrix() * base_velocity;
  double yaw_rate = 2.0 * std::remainder(yaw_goal - robot.yaw, 2 * M_PI);
  if (phase_ == Phase::kPull) yaw_rate *= yaw_follow_;
  if (phase_ == Phase::kHold || phase_ == Phase::kClose) yaw_rate = 0.0;
  yaw_rate = std::clamp(yaw_rate, -1.0, 1.0);
  // Lift: the goal's height at the arm's nominal height; still while the
  // fingers close, pull and hold, except where the handle's motion has a
  // vertical part (more than a tenth of its speed): a flap hinged at its
  // top or bottom moves the handle up or down by its height, and at a
  // fixed lift the hand ran out of reach at 85 % open. There it rises and
  // falls as the handle has since the grasp; the arm takes the lift's
  // motion out below. Drawers and doors on a vertical hinge move their
  // handle level and keep the lift where the grasp left it.
  double lift_goal = std::clamp(goal.z() - nominal_height_, 0.0, 1.5);
  const bool lift_follows = phase_ == Phase::kPull && std::abs(v.motion.z()) > 0.1;
  if (lift_follows) lift_goal = std::clamp(pull_lift_ + v.handle.z() - pull_handle_height_, 0.0, 1.5);
  const bool lift_still = phase_ == Phase::kClose || phase_ == Phase::kHold || (phase_ == Phase::kPull && !lift_follows);
  const double lift_rate =
      lift_still ? 0.0 : std::clamp(3.0 * (lift_goal - robot.lift), -MobilePandaSpeeds::kLift, MobilePandaSpeeds::kLift);
  // Arm: the rest of the way, in the base frame.
  const double gain = phase_ == Phase::kPull && door ? door_speed_ / kDoorLead : 5.0;
  Eigen::Vector3d tcp_velocity = clipNorm(gain * (goal - tcp), kEeSpeed);
  if (phase_ == Phase::kHold) tcp_velocity.setZero();
  Eigen::Vector3d arm_velocity = tcp_velocity;
  // The arm's command is relative to the moving base: take out what the
  // base's own motion does to the TCP.
  const Eigen::Vector3d lever = tcp - Eigen::Vector3d(robot.base.x(), robot.base.y(), tcp.z());
  arm_velocity -= Eigen::Vector3d(base_velocity.x(), base_velocity.y(), 0) +
                  Eigen::Vector3d(0, 0, yaw_rate).cross(lever);
  if (lift_follows) arm_velocity.z() -= lift_rate;
  Eigen::Vector3d angular = 4.0 * v.orientation_error.angle() * v.orientation_error.axis();
  angular.z() -= yaw_rate;  // the base turns the hand too
  if (phase_ == Phase::kPull && door) angular += v.axis * v.qdot;  // turn with the door
  angular = clipNorm(angular, kEeAngularSpeed);

  Eigen::VectorXd action = Eigen::VectorXd::Zero(action_.dim);
  setBaseAction(action, action_.base, base_local, yaw_rate, lift_rate);
  setEeAction(action, action_.arms[0].linear, action_.arms[0].angular, robot.base_rotation, arm_velocity, angular);
  action[action_.arms[0].gripper] = c.gripper;
  return action;
}

Eigen::VectorXd OpenCabinetExpert::act(const sdk::Observation& observation) {
  View v = read(observation);
  if (!nominal_ready_) {  // the canonical arm pose's TCP, relative to the base
    grasp_turned_ = calcGraspTurned(v);
    if (grasp_turned_) v = read(observation);
    const Eigen::Vector3d offset =
        v.robot.base_rotation.transpose() * (v.tcp - Eigen::Vector3d(v.robot.base.x(), v.robot.base.y(), 0));
    nominal_offset_ = Eigen::Vector2d(offset.x(), offset.y());
    nominal_height_ = v.tcp.z() - v.robot.lift;
    nominal_ready_ = true;
  }
  ++phase_steps_;
  Command c;
  c.goal = v.handle;
  c.gripper = v.open_action;
  switch (phase_) {
    case Phase::kApproach:
    case Phase::kPreGrasp: approach(v, c); break;
    case Phase::kGrasp: grasp(v, c); break;
    case Phase::kClose: closeFingers(v, c); break;
    case Phase::kPull: pull(v, c); break;
    case Phase::kHold: c.gripper = -1.0; break;
  }
  return calcAction(v, c);
}

}  // namespace open_cabinet
