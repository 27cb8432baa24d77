// What the mobile Panda controllers (mobile_panda, mobile_panda_ee) share:
// their common configuration, the joints found by name, the base/lift
// action segments with their egocentric drives, and the gripper drives.
#pragma once

#include "velocity_stage.hpp"

#include <manibench/kit/policy_math.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace manibench::controllers {

constexpr int kPandaArmJoints = 7;
inline const char* const kPandaSides[] = {"right", "left"};  // action order of the arms

inline std::string formatNumber(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// Configuration both controllers read (YAML, all optional):
//   base_max_velocity: 0.5  yaw_max_velocity: 3.14  lift_max_velocity: 0.5
//   arm_max_velocity: 3.14  cutoff_hz: 40 (read by the VelocityStage)
//   base_damping: 1000      (root_x, root_y, root_yaw, lift)
//   arm_damping: [200, 300, 200, 100, 100, 100, 100]  (joint1..7, or one
//                           number for all; ManiSkill: 100, see README.md)
//   gripper_stiffness: 5000 gripper_damping: 800  (N/m, N s/m; see below)
//   gripper_closed: 0.0     gripper_open: 0.04   (m per finger)
// ManiSkill damps every arm joint with 100. The shoulder and elbow (joints
// 1-3) carry most of the arm: their drive time constant, inertia / damping,
// then needs 6-11 control steps to reach 95% of a velocity step; 200-250
// gets them within 5. The others keep 100: they already react within 5
// steps, and every stiffer drive makes the integrator's steps smaller
// (400 on joints 1-4 cost 15% of the cabinet expert's speed).
inline std::array<double, kPandaArmJoints> readArmDamping(const sdk::Config& config,
                                                          const std::string& controller) {
  std::array<double, kPandaArmJoints> damping = {200, 300, 200, 100, 100, 100, 100};
  if (!config.has("arm_damping")) return damping;
  if (config.node()["arm_damping"].IsSequence()) {
    const auto values = config.get<std::vector<double>>("arm_damping", {});
    if (values.size() != damping.size())
      throw sdk::Error(controller + " configuration: 'arm_damping' needs 7 values (joint1..7), got " +
                           std::to_string(values.size()),
                       MB_INVALID_ARGUMENT);
    std::copy(values.begin(), values.end(), damping.begin());
  } else {
    damping.fill(config.get<double>("arm_damping", 0.0));
  }
  for (double d : damping)
    if (!(d > 0) || !std::isfinite(d))
      throw sdk::Error(controller + " configuration: 'arm_damping' values must be positive numbers",
                       MB_INVALID_ARGUMENT);
  return damping;
}

// The fingers: a position drive whose squeeze is what the Panda hand gives
// (70 N continuous): 5000 N/m presses 25-75 N on a 10-30 mm handle or rim.
// At 1000 N/m (5-15 N) real PartNet doors did not open: their handles are
// fins that the pads hold by friction alone, and the fingers slid to the
// fin's edge while the door, damped with up to 20 N m s, stood (door expert
// 15/100 on the development set's 10 real doors; 89/100 at 5000 N/m, drawers
// 100/100 either way); a bucket slipped out of the fingers. The damping
// keeps a closing finger under 0.25 m/s (5000 x 0.04 / 800), as a real
// hand's: at the 3 m/s that 5000 N/m reaches with 50 N s/m, a pad moves
// 6 mm per 2 ms step and passes through a thin rim (and 10000 N/m with 50
// N s/m opened 68/100 real doors).
struct MobilePandaSettings {
  double base_max, yaw_max, lift_max, arm_max;
  double base_damping;
  std::array<double, kPandaArmJoints> arm_damping;  // joint1..7
  double gripper_stiffness, gripper_damping, gripper_closed, gripper_open;

  MobilePandaSettings(const sdk::Config& config, const std::string& controller)
      : base_max(requirePositive(config, "base_max_velocity", kit::MobilePandaSpeeds::kBase)),
        yaw_max(requirePositive(config, "yaw_max_velocity", kit::MobilePandaSpeeds::kYaw)),
        lift_max(requirePositive(config, "lift_max_velocity", kit::MobilePandaSpeeds::kLift)),
        arm_max(requirePositive(config, "arm_max_velocity", 3.14)),
        base_damping(requirePositive(config, "base_damping", 1000.0)),
        arm_damping(readArmDamping(config, controller)),
        gripper_stiffness(requirePositive(config, "gripper_stiffness", 5000.0)),
        gripper_damping(requirePositive(config, "gripper_damping", 800.0)),
        gripper_closed(config.get<double>("gripper_closed", 0.0)),
        gripper_open(config.get<double>("gripper_open", 0.04)) {
    if (!std::isfinite(gripper_closed) || !std::isfinite(gripper_open) ||
        !(gripper_open > gripper_closed))
      throw sdk::Error(controller + " configuration: gripper_open must be a number above gripper_closed",
                       MB_INVALID_ARGUMENT);
  }
};

struct PandaArm {
  std::string side;
  std::vector<std::size_t> joints;   // context slots of joint1..7
  std::vector<std::size_t> fingers;  // context slots of finger_joint1..2
};

// The robot's actuated joints by role, as context slots.
struct MobilePandaJoints {
  std::size_t root_x = 0, root_y = 0, root_yaw = 0, lift = 0;
  Eigen::Index yaw_index = 0;  // root_yaw in the articulation's joint vector
  std::vector<PandaArm> arms;  // right first

  // Finds every joint by name among the context's joints; lists all missing
  // (and all unexpected) names in one error naming `controller`.
  MobilePandaJoints(const sdk::ControllerContext& context, const std::string& controller) {
    std::map<std::string, std::size_t> slots;
    for (std::size_t i = 0; i < context.joints.size(); ++i) slots[context.joints[i].name] = i;
    std::vector<std::string> missing;
    std::vector<bool> used(context.joints.size(), false);
    auto take = [&](const std::string& name) -> std::size_t {
      const auto it = slots.find(name);
      if (it == slots.end()) {
        missing.push_back(name);
        return 0;
      }
      used[it->second] = true;
      return it->second;
    };
    root_x = take("root_x");
    root_y = take("root_y");
    root_yaw = take("root_yaw");
    lift = take("lift");
    for (const char* side : kPandaSides) {
      const std::string prefix = std::string(side) + "_panda_";
      const bool present = std::any_of(slots.begin(), slots.end(), [&](const auto& entry) {
        return entry.first.rfind(prefix, 0) == 0;
      });
      if (!present) continue;
      PandaArm arm;
      arm.side = side;
      for (int j = 1; j <= kPandaArmJoints; ++j)
        arm.joints.push_back(take(prefix + "joint" + std::to_string(j)));
      for (int f = 1; f <= 2; ++f) arm.fingers.push_back(take(prefix + "finger_joint" + std::to_string(f)));
      arms.push_back(std::move(arm));
    }
    if (arms.empty()) missing.push_back("right_panda_joint1..7 or left_panda_joint1..7");
    std::string problems;
    if (!missing.empty()) {
      problems += "missing actuated joints:";
      for (const std::string& name : missing) problems += " " + name;
    }
    std::string unexpected;
    for (std::size_t i = 0; i < used.size(); ++i)
      if (!used[i] && missing.empty()) unexpected += " " + context.joints[i].name;
    if (!unexpected.empty()) problems += "actuated joints it does not drive:" + unexpected;
    if (!problems.empty())
      throw sdk::Error(controller + " controller: " + problems +
                           " (it expects root_x, root_y, root_yaw, lift and per arm "
                           "<side>_panda_joint1..7, <side>_panda_finger_joint1..2)",
                       MB_INVALID_ARGUMENT);
    yaw_index = Eigen::Index(context.joints[root_yaw].index);
  }
};

// Both mobile Panda controllers filter their velocity actions (base x/y
// still egocentric, so that a yawing base keeps a steady command): the
// base's and lift's 4 and each arm's 7.
inline std::unique_ptr<VelocityStage> makeVelocityStage(const sdk::Config& config,
                                                        const sdk::ControllerContext& context,
                                                        const MobilePandaJoints& joints) {
  return std::make_unique<VelocityStage>(4 + kPandaArmJoints * joints.arms.size(),
                                         readLowPassAlpha(config, context.control_frequency));
}

// Action segments 0-3: base_forward, base_left, base_yaw, lift.
inline std::vector<sdk::Segment> describeBaseActions(const MobilePandaSettings& s) {
  const std::string base = "(m/s, action 1 = " + formatNumber(s.base_max) + ")";
  return {
      {"base_forward", 1, "base velocity along the robot's own x " + base},
      {"base_left", 1, "base velocity along the robot's own y " + base},
      {"base_yaw", 1, "yaw rate (rad/s, action 1 = " + formatNumber(s.yaw_max) + ")"},
      {"lift", 1, "lift velocity (m/s, action 1 = " + formatNumber(s.lift_max) + ")"},
  };
}

inline sdk::Segment describeGripperAction(const MobilePandaSettings& s, const std::string& side) {
  return {side + "_gripper", 1,
          "both fingers' position target: -1 closed (" + formatNumber(s.gripper_closed) +
              " m), +1 open (" + formatNumber(s.gripper_open) + " m)"};
}

// The base/lift velocities of actions 0-3, in their units, still egocentric.
inline Eigen::Vector4d calcBaseVelocity(const MobilePandaSettings& s,
                                        const Eigen::Map<const Eigen::VectorXd>& action) {
  return Eigen::Vector4d(action[0] * s.base_max, action[1] * s.base_max, action[2] * s.yaw_max,
                         action[3] * s.lift_max);
}

// Filtered base velocities (forward, left, yaw rate, lift) to damping
// drives; forward/left are rotated by the current root_yaw into the
// world-aligned root_x/root_y joints.
inline void setBaseDrives(const sdk::SceneView& scene, const sdk::ControllerContext& context,
                          const MobilePandaJoints& joints, const MobilePandaSettings& s,
                          const Eigen::Ref<const Eigen::Vector4d>& filtered,
                          std::vector<sdk::DriveCommand>& drives) {
  const double yaw = scene.getJointPositions(context.articulation)[joints.yaw_index];
  const double c = std::cos(yaw), sn = std::sin(yaw);
  setDampingDrive(drives[joints.root_x], c * filtered[0] - sn * filtered[1], s.base_damping);
  setDampingDrive(drives[joints.root_y], sn * filtered[0] + c * filtered[1], s.base_damping);
  setDampingDrive(drives[joints.root_yaw], filtered[2], s.base_damping);
  setDampingDrive(drives[joints.lift], filtered[3], s.base_damping);
}

// mobile_panda's normalized joint velocity action for `velocity` (action
// 1 = `max`): the a in [-1, 1] whose de-normalisation a * max, the
// expression mobile_panda computes, is `velocity` bit for bit where such a
// double exists, else the a whose a * max lies nearest. velocity / max
// alone does not do: it rounds, and a * max rounds again, and where max > 1
// consecutive a step over some doubles (about a third of those in
// [1.57, 2) for max 3.14). A layer over mobile_panda sends a * max on,
// exactly what mobile_panda sends for a.
inline double normalizeVelocity(double velocity, double max) {
  const double start = std::clamp(velocity / max, -1.0, 1.0);
  double best = start, best_error = std::abs(start * max - velocity);
  // (velocity / max) * max lies within 2 ulp of velocity, so the exact a,
  // where there is one, lies within 2 doubles of the quotient.
  for (double direction : {1.0, -1.0}) {
    double a = start;
    for (int step = 0; step < 3 && best_error != 0; ++step) {
      a = std::nextafter(a, direction * 2.0);
      if (a > 1.0 || a < -1.0) break;
      const double error = std::abs(a * max - velocity);
      if (error < best_error) best = a, best_error = error;
    }
  }
  return best;
}

// The finger position target of a gripper action (-1 closed .. +1 open).
inline double calcFingerTarget(const MobilePandaSettings& s, double action) {
  return s.gripper_closed + 0.5 * (action + 1.0) * (s.gripper_open - s.gripper_closed);
}

inline void setGripperDrives(const PandaArm& arm, const MobilePandaSettings& s, double target,
                             std::vector<sdk::DriveCommand>& drives) {
  for (std::size_t slot : arm.fingers) {
    sdk::DriveCommand& d = drives[slot];
    d.position_target = target;
    d.velocity_target = 0;
    d.stiffness = s.gripper_stiffness;
    d.damping = s.gripper_damping;
    d.force = 0;
  }
}

}  // namespace manibench::controllers
