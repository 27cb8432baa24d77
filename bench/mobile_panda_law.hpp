// The mobile_panda controller's drive law (controllers/mobile_panda.cpp with
// the defaults of controllers/mobile_panda_common.hpp), written against no
// engine, so that the MuJoCo twin drives its robot exactly as manibench's
// Environment::step does. The twin checks the copy: replayed on the
// manibench scene it must reproduce Environment::step bit for bit.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "manibench/scene.hpp"

namespace manibench::bench {

class MobilePandaLaw {
 public:
  // The single-arm robot's actuated joints, in the order compute() fills.
  static const std::vector<std::string>& getJointNames();
  static constexpr int kActionDim = 12;

  explicit MobilePandaLaw(double control_frequency);
  // The low-pass filter's state back to zero (the controller's reset).
  void reset();
  // One control tick: `action` in [-1, 1] (12 values), `yaw` the robot's
  // root_yaw now; one command per actuated joint.
  void compute(const Eigen::VectorXd& action, double yaw, std::vector<DriveCommand>& commands);

 private:
  double alpha_;
  Eigen::VectorXd filtered_;  // base forward, left, yaw rate, lift, arm joint 1-7
};

}  // namespace manibench::bench
