#include "teleop.hpp"

#include <stdexcept>
#include <utility>

namespace manibench::viewer {
namespace {

// GLFW's codes for the keys that are not characters (window.cpp checks
// them against glfw3.h).
constexpr int kKeyLeftShift = 340, kKeyRightShift = 344;

struct MotionKey {
  int key;
  TeleopMotion motion;
};
constexpr MotionKey kMotionKeys[] = {
    {'W', TeleopMotion::BaseForward},    {'S', TeleopMotion::BaseBack},
    {'A', TeleopMotion::BaseLeft},       {'D', TeleopMotion::BaseRight},
    {'Q', TeleopMotion::TurnLeft},       {'E', TeleopMotion::TurnRight},
    {'R', TeleopMotion::LiftUp},         {'F', TeleopMotion::LiftDown},
    {'I', TeleopMotion::GripperForward}, {'K', TeleopMotion::GripperBack},
    {'J', TeleopMotion::GripperLeft},    {'L', TeleopMotion::GripperRight},
    {'U', TeleopMotion::GripperUp},      {'O', TeleopMotion::GripperDown},
};

int findSegment(const ControllerDescription& controller, const std::string& name, uint32_t size) {
  for (const sdk::Segment& s : controller.action_segments)
    if (s.name == name) {
      if (s.size != size)
        throw InvalidArgument("teleoperation: the controller '" + controller.name +
                                    "' has action segment '" + name + "' of " +
                                    std::to_string(s.size) + " values, expected " +
                                    std::to_string(size));
      return int(s.offset);
    }
  return -1;
}

}  // namespace

TeleopLayout findTeleopLayout(const ControllerDescription& controller) {
  TeleopLayout layout;
  layout.action_dim = controller.action_dim;
  std::pair<const char*, int*> base[] = {{"base_forward", &layout.base_forward},
                                         {"base_left", &layout.base_left},
                                         {"base_yaw", &layout.base_yaw},
                                         {"lift", &layout.lift}};
  std::string missing;
  for (auto& [name, index] : base) {
    *index = findSegment(controller, name, 1);
    if (*index < 0) missing += std::string(missing.empty() ? "" : ", ") + name;
  }
  for (const char* side : {"right", "left"}) {
    TeleopLayout::Arm arm;
    arm.side = side;
    arm.linear = findSegment(controller, arm.side + "_ee_linear", 3);
    arm.angular = findSegment(controller, arm.side + "_ee_angular", 3);
    arm.gripper = findSegment(controller, arm.side + "_gripper", 1);
    if (arm.linear >= 0 && arm.angular >= 0 && arm.gripper >= 0) layout.arms.push_back(arm);
  }
  if (layout.arms.empty()) missing += std::string(missing.empty() ? "" : ", ") + "<side>_ee_linear";
  if (!missing.empty())
    throw InvalidArgument(
        "teleoperation drives the robot through the end-effector controller, and the "
        "controller '" + controller.name + "' has no action segment " + missing +
        ": use --controller mobile_panda_ee (the mobile Panda robots), or watch with "
        "--policy NAME or --replay FILE.h5");
  return layout;
}

Teleop::Teleop(TeleopLayout layout)
    : layout_(std::move(layout)), gripper_open_(layout_.arms.size(), true) {}

bool Teleop::handleKey(int key, bool pressed, bool shift) {
  if (key == kKeyLeftShift || key == kKeyRightShift) {
    shift_ = pressed;
    return false;  // the viewer may use Shift too
  }
  shift_ = shift;
  for (const MotionKey& m : kMotionKeys)
    if (m.key == key) {
      held_[std::size_t(m.motion)] = pressed;
      return true;
    }
  if (!pressed) return false;
  if (key == 'G') {
    if (selected_arm_ < 0) {
      const bool open = !gripper_open_[0];
      gripper_open_.assign(gripper_open_.size(), open);
    } else {
      gripper_open_[std::size_t(selected_arm_)] = !gripper_open_[std::size_t(selected_arm_)];
    }
    return true;
  }
  if (key >= '1' && key <= '3' && layout_.arms.size() > 1) {
    selected_arm_ = key == '3' ? -1 : key - '1';
    return true;
  }
  if (key == '-' && speed_ > 0) --speed_;
  if (key == '=' && speed_ + 1 < kSpeeds.size()) ++speed_;
  return key == '-' || key == '=';
}

void Teleop::releaseAll() {
  held_.fill(false);
  shift_ = false;
}

Eigen::VectorXd Teleop::calcAction() const {
  Eigen::VectorXd action = Eigen::VectorXd::Zero(layout_.action_dim);
  const double v = kSpeeds[speed_];
  const auto axis = [&](TeleopMotion plus, TeleopMotion minus) {
    return (isHeld(plus) ? v : 0.0) - (isHeld(minus) ? v : 0.0);
  };
  action[layout_.base_forward] = axis(TeleopMotion::BaseForward, TeleopMotion::BaseBack);
  action[layout_.base_left] = axis(TeleopMotion::BaseLeft, TeleopMotion::BaseRight);
  action[layout_.base_yaw] = axis(TeleopMotion::TurnLeft, TeleopMotion::TurnRight);
  action[layout_.lift] = axis(TeleopMotion::LiftUp, TeleopMotion::LiftDown);
  // Along (translation) or about (rotation) the robot's x, y, z axes:
  // translation forward, left, up; rotation roll (U/O), pitch (I/K), yaw
  // (J/L, positive turning left).
  const double forward = axis(TeleopMotion::GripperForward, TeleopMotion::GripperBack);
  const double left = axis(TeleopMotion::GripperLeft, TeleopMotion::GripperRight);
  const double up = axis(TeleopMotion::GripperUp, TeleopMotion::GripperDown);
  const Eigen::Vector3d motion = shift_ ? Eigen::Vector3d(up, forward, left)
                                        : Eigen::Vector3d(forward, left, up);
  for (std::size_t a = 0; a < layout_.arms.size(); ++a) {
    const TeleopLayout::Arm& arm = layout_.arms[a];
    if (selected_arm_ < 0 || std::size_t(selected_arm_) == a)
      action.segment<3>(shift_ ? arm.angular : arm.linear) = motion;
    action[arm.gripper] = gripper_open_[a] ? 1.0 : -1.0;
  }
  return action;
}

std::vector<KeyBinding> Teleop::describeKeys() const {
  std::vector<KeyBinding> keys = {
      {"W / S", "base forward / back"},
      {"A / D", "base left / right"},
      {"Q / E", "turn left / right"},
      {"R / F", "lift up / down"},
      {"I / K", "gripper forward / back"},
      {"J / L", "gripper left / right"},
      {"U / O", "gripper up / down"},
      {"Shift+U / O", "gripper roll +/- (about x)"},
      {"Shift+I / K", "gripper pitch +/- (about y)"},
      {"Shift+J / L", "gripper yaw left / right"},
      {"G", "gripper close / open"},
  };
  if (layout_.arms.size() > 1) keys.push_back({"1 / 2 / 3", "right arm / left arm / both"});
  keys.push_back({"- / =", "slower / faster"});
  return keys;
}

}  // namespace manibench::viewer
