// Keyboard teleoperation (supplement B.8) through the end-effector
// controller, mobile_panda_ee: held keys drive the mobile base (planar
// velocity, turn, lift) and the selected gripper in Cartesian coordinates
// (translate; rotate with Shift), a key opens and closes it. The action is
// made by segment name (base_forward, base_left, base_yaw, lift, then per
// arm <side>_ee_linear, <side>_ee_angular, <side>_gripper), so the one-arm
// and the two-arm robot work alike. No GLFW here: keys are GLFW's codes,
// which for letters, digits and punctuation are their ASCII characters.
#pragma once

#include <manibench/error.hpp>
#include <manibench/plugin_instances.hpp>

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace manibench::viewer {

// What a held key asks for. Gripper keys translate, or rotate with Shift.
enum class TeleopMotion {
  BaseForward, BaseBack, BaseLeft, BaseRight, TurnLeft, TurnRight, LiftUp, LiftDown,
  GripperForward, GripperBack, GripperLeft, GripperRight, GripperUp, GripperDown,
  Count
};

// One line of the keymap the overlay shows.
struct KeyBinding {
  std::string keys;  // "W / S"
  std::string what;  // "base forward / back"
};

// Where each commanded quantity sits in the controller's action.
struct TeleopLayout {
  int base_forward = -1, base_left = -1, base_yaw = -1, lift = -1;
  struct Arm {
    std::string side;  // "right", "left"
    int linear = -1, angular = -1, gripper = -1;  // first index of 3, 3, 1 values
  };
  std::vector<Arm> arms;
  uint32_t action_dim = 0;
};

// The layout of `controller`, or InvalidArgument naming the segment
// it lacks and the controller to use instead.
TeleopLayout findTeleopLayout(const ControllerDescription& controller);

class Teleop {
 public:
  // Speed steps (fractions of the controller's full speed); `-` and `=`
  // move between them.
  static constexpr std::array<double, 5> kSpeeds{0.1, 0.25, 0.5, 0.75, 1.0};

  explicit Teleop(TeleopLayout layout);

  // A key pressed or released (GLFW key code). Returns whether it is a
  // teleoperation key (then the viewer does nothing else with it). `shift`:
  // the Shift modifier, which turns gripper translation into rotation.
  bool handleKey(int key, bool pressed, bool shift);
  // Releases every held key (the window lost focus: no key-up will come).
  void releaseAll();

  // The action for the held keys, the selected arm(s), the grippers'
  // open/closed state and the speed, in [-1, 1].
  Eigen::VectorXd calcAction() const;

  const TeleopLayout& getLayout() const { return layout_; }
  // -1: every arm; otherwise an index into the layout's arms.
  int getSelectedArm() const { return selected_arm_; }
  bool isGripperOpen(std::size_t arm) const { return gripper_open_.at(arm); }
  double getSpeed() const { return kSpeeds[speed_]; }
  bool isHeld(TeleopMotion motion) const { return held_[std::size_t(motion)]; }
  bool isRotating() const { return shift_; }
  // The keymap for this robot (the arm keys only with two arms).
  std::vector<KeyBinding> describeKeys() const;

 private:
  TeleopLayout layout_;
  std::array<bool, std::size_t(TeleopMotion::Count)> held_{};
  bool shift_ = false;
  int selected_arm_ = 0;
  std::vector<bool> gripper_open_;
  std::size_t speed_ = 2;
};

}  // namespace manibench::viewer
