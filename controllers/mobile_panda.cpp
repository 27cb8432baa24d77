// mobile_panda: the composite controller of the mobile Panda robots
// (assets/robots/, supplement B.7). Action layout, all normalized to [-1, 1]:
//   0 base_forward  base velocity along the robot's own x  (+-0.5 m/s)
//   1 base_left     base velocity along the robot's own y  (+-0.5 m/s)
//   2 base_yaw      yaw rate                               (+-3.14 rad/s)
//   3 lift          lift velocity                          (+-0.5 m/s)
//   then per arm (right before left): its 7 joint velocities (+-3.14 rad/s)
//   and one gripper action (finger position target, -1 closed .. +1 open).
// Base x/y are egocentric: they are rotated by the current root_yaw into the
// world-aligned root_x/root_y joints. All velocities pass the shared low-pass
// filter and a damping drive; the fingers get a position drive. Joints are
// found by name among the task's actuated joints.
//
// Configuration (YAML, all optional):
//   base_max_velocity: 0.5  yaw_max_velocity: 3.14  lift_max_velocity: 0.5
//   arm_max_velocity: 3.14  cutoff_hz: 40
//   base_damping: 1000      (root_x, root_y, root_yaw, lift)
//   arm_damping: 100
//   gripper_stiffness: 1000 gripper_damping: 50  (N/m, N s/m)
//   gripper_closed: 0.0     gripper_open: 0.04   (m per finger)
#include "velocity_stage.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>

namespace {

using manibench::controllers::readLowPassAlpha;
using manibench::controllers::requirePositive;
using manibench::controllers::setDampingDrive;
using manibench::controllers::VelocityStage;
using manibench::sdk::Config;
using manibench::sdk::ControllerContext;
using manibench::sdk::ControllerSpec;
using manibench::sdk::DriveCommand;
using manibench::sdk::Error;
using manibench::sdk::SceneView;
using manibench::sdk::Segment;

constexpr int kArmJoints = 7;
const char* const kSides[] = {"right", "left"};  // action order of the arms

struct Arm {
  std::string side;
  std::vector<std::size_t> joints;   // context slots of joint1..7
  std::vector<std::size_t> fingers;  // context slots of finger_joint1..2
};

class MobilePandaController : public manibench::sdk::Controller {
 public:
  MobilePandaController(const Config& config, const ControllerContext& context)
      : context_(context),
        base_max_(requirePositive(config, "base_max_velocity", 0.5)),
        yaw_max_(requirePositive(config, "yaw_max_velocity", 3.14)),
        lift_max_(requirePositive(config, "lift_max_velocity", 0.5)),
        arm_max_(requirePositive(config, "arm_max_velocity", 3.14)),
        base_damping_(requirePositive(config, "base_damping", 1000.0)),
        arm_damping_(requirePositive(config, "arm_damping", 100.0)),
        gripper_stiffness_(requirePositive(config, "gripper_stiffness", 1000.0)),
        gripper_damping_(requirePositive(config, "gripper_damping", 50.0)),
        gripper_closed_(config.get<double>("gripper_closed", 0.0)),
        gripper_open_(config.get<double>("gripper_open", 0.04)) {
    if (!std::isfinite(gripper_closed_) || !std::isfinite(gripper_open_) ||
        !(gripper_open_ > gripper_closed_))
      throw Error("mobile_panda configuration: gripper_open must be a number above gripper_closed",
                  MB_INVALID_ARGUMENT);
    resolveJoints();
    // The filtered quantities are the velocity actions (base x/y still
    // egocentric), so that a yawing base keeps a steady command.
    stage_ = std::make_unique<VelocityStage>(4 + kArmJoints * arms_.size(),
                                             readLowPassAlpha(config, context.control_frequency));
  }

  ControllerSpec describe() const override {
    ControllerSpec spec;
    spec.flags = MB_CONTROLLER_BALANCE_PASSIVE_FORCES;
    const std::string base = "(m/s, action 1 = " + number(base_max_) + ")";
    spec.action = {
        {"base_forward", 1, "base velocity along the robot's own x " + base},
        {"base_left", 1, "base velocity along the robot's own y " + base},
        {"base_yaw", 1, "yaw rate (rad/s, action 1 = " + number(yaw_max_) + ")"},
        {"lift", 1, "lift velocity (m/s, action 1 = " + number(lift_max_) + ")"},
    };
    for (const Arm& arm : arms_) {
      for (std::size_t slot : arm.joints)
        spec.action.push_back({context_.joints[slot].name, 1,
                               "joint velocity (rad/s, action 1 = " + number(arm_max_) + ")"});
      spec.action.push_back({arm.side + "_gripper", 1,
                             "both fingers' position target: -1 closed (" + number(gripper_closed_) +
                                 " m), +1 open (" + number(gripper_open_) + " m)"});
    }
    return spec;
  }

  void reset(const SceneView&) override { stage_->reset(); }

  void compute(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action,
               std::vector<DriveCommand>& drives) override {
    Eigen::VectorXd velocity(4 + kArmJoints * Eigen::Index(arms_.size()));
    velocity.head<4>() << action[0] * base_max_, action[1] * base_max_, action[2] * yaw_max_,
        action[3] * lift_max_;
    Eigen::Index a = 4;  // next action index
    Eigen::Index v = 4;  // next filtered velocity
    std::vector<double> finger_targets;
    for (std::size_t i = 0; i < arms_.size(); ++i) {
      for (int j = 0; j < kArmJoints; ++j) velocity[v++] = action[a++] * arm_max_;
      finger_targets.push_back(gripper_closed_ +
                               0.5 * (action[a++] + 1.0) * (gripper_open_ - gripper_closed_));
    }
    const Eigen::VectorXd& filtered = stage_->filter(velocity);

    // Egocentric base velocity into the world-aligned x/y joints.
    const double yaw = scene.getJointPositions(context_.articulation)[yaw_index_];
    const double c = std::cos(yaw), s = std::sin(yaw);
    setDampingDrive(drives[root_x_], c * filtered[0] - s * filtered[1], base_damping_);
    setDampingDrive(drives[root_y_], s * filtered[0] + c * filtered[1], base_damping_);
    setDampingDrive(drives[root_yaw_], filtered[2], base_damping_);
    setDampingDrive(drives[lift_], filtered[3], base_damping_);
    v = 4;
    for (std::size_t i = 0; i < arms_.size(); ++i) {
      for (std::size_t slot : arms_[i].joints) setDampingDrive(drives[slot], filtered[v++], arm_damping_);
      for (std::size_t slot : arms_[i].fingers) {
        DriveCommand& d = drives[slot];
        d.position_target = finger_targets[i];
        d.velocity_target = 0;
        d.stiffness = gripper_stiffness_;
        d.damping = gripper_damping_;
        d.force = 0;
      }
    }
  }

 private:
  static std::string number(double x) {
    std::ostringstream s;
    s << x;
    return s.str();
  }

  // Finds every joint by name among the context's joints; lists all missing
  // (and all unexpected) names in one error.
  void resolveJoints() {
    std::map<std::string, std::size_t> slots;
    for (std::size_t i = 0; i < context_.joints.size(); ++i) slots[context_.joints[i].name] = i;
    std::vector<std::string> missing;
    std::vector<bool> used(context_.joints.size(), false);
    auto take = [&](const std::string& name) -> std::size_t {
      const auto it = slots.find(name);
      if (it == slots.end()) {
        missing.push_back(name);
        return 0;
      }
      used[it->second] = true;
      return it->second;
    };
    root_x_ = take("root_x");
    root_y_ = take("root_y");
    root_yaw_ = take("root_yaw");
    lift_ = take("lift");
    for (const char* side : kSides) {
      const std::string prefix = std::string(side) + "_panda_";
      const bool present = std::any_of(slots.begin(), slots.end(), [&](const auto& entry) {
        return entry.first.rfind(prefix, 0) == 0;
      });
      if (!present) continue;
      Arm arm;
      arm.side = side;
      for (int j = 1; j <= kArmJoints; ++j) arm.joints.push_back(take(prefix + "joint" + std::to_string(j)));
      for (int f = 1; f <= 2; ++f) arm.fingers.push_back(take(prefix + "finger_joint" + std::to_string(f)));
      arms_.push_back(std::move(arm));
    }
    if (arms_.empty()) missing.push_back("right_panda_joint1..7 or left_panda_joint1..7");
    std::string problems;
    if (!missing.empty()) {
      problems += "missing actuated joints:";
      for (const std::string& name : missing) problems += " " + name;
    }
    std::string unexpected;
    for (std::size_t i = 0; i < used.size(); ++i)
      if (!used[i] && missing.empty()) unexpected += " " + context_.joints[i].name;
    if (!unexpected.empty()) problems += "actuated joints it does not drive:" + unexpected;
    if (!problems.empty())
      throw Error("mobile_panda controller: " + problems +
                      " (it expects root_x, root_y, root_yaw, lift and per arm "
                      "<side>_panda_joint1..7, <side>_panda_finger_joint1..2)",
                  MB_INVALID_ARGUMENT);
    yaw_index_ = Eigen::Index(context_.joints[root_yaw_].index);
  }

  ControllerContext context_;
  double base_max_, yaw_max_, lift_max_, arm_max_;
  double base_damping_, arm_damping_;
  double gripper_stiffness_, gripper_damping_, gripper_closed_, gripper_open_;
  std::size_t root_x_ = 0, root_y_ = 0, root_yaw_ = 0, lift_ = 0;  // context slots
  Eigen::Index yaw_index_ = 0;  // root_yaw in the articulation's joint vector
  std::vector<Arm> arms_;
  std::unique_ptr<VelocityStage> stage_;
};

}  // namespace

MANIBENCH_REGISTER_CONTROLLER(MobilePandaController, "mobile_panda",
                              "mobile Panda robots: egocentric base, lift, arm joint velocities, one "
                              "gripper action per arm (B.7)");
