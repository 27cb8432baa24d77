// The staged dense reward of PushChair-v0 (supplement C.1.2) as a pure
// function of measured quantities, so that tests can sample every stage.
#include "push_chair.hpp"

#include <algorithm>
#include <cmath>

namespace push_chair {

namespace {

// Approach term: -d - min(log d, 0), decreasing in d.
double approachTerm(double d) { return -d - std::min(std::log(std::max(d, 1e-6)), 0.0); }

}  // namespace

int calcRewardStage(const RewardInput& in) {
  if (in.tilt >= kFallenTilt) return 1;
  if (in.target_distance < kTargetRadius) return 3;
  if (in.ee_distance < kNearDistance) return 2;
  return 1;
}

double calcStagedReward(const RewardInput& in) {
  const double common = -0.2 * in.tilt - 1e-6 * in.action_norm;
  double r = 0;
  switch (calcRewardStage(in)) {
    case 1:
      // Stage bases -10, -8, -6 (ManiSkill: -10, +2 per stage). Stage 1
      // has no lower bound; its best is -10 + approachTerm(0.1) = -7.80.
      r = -10.0 + approachTerm(std::max(in.ee_distance, kNearDistance)) - (in.tilt >= kFallenTilt ? 5.0 : 0.0);
      break;
    case 2: {
      // The approach term stays at its 10 cm value (pressing closer must
      // not pay more than pushing). Push terms lie in (-1.8, 2): the stage
      // spans (-7.73, -3.80), above stage 1 (tilt < 0.2 pi: -0.2 tilt > -0.126).
      const double towards = std::clamp(1.0 - std::exp(-in.speed_to_target), 0.0, 1.0);
      r = -8.0 + approachTerm(kNearDistance) + 2.0 * towards - 1.8 * std::tanh(in.target_distance);
      break;
    }
    case 3:
      // At the target: at least -6 + 2.20 - 0.126 = -3.92, above stage 2's
      // best (-3.80 - 1.8 tanh(0.15) = -4.07); stillness pays, static more.
      r = -6.0 + approachTerm(kNearDistance) + 2.0 * std::exp(-10.0 * in.speed) + (in.is_static ? 2.0 : 0.0);
      break;
  }
  return 2.0 * (r + common);
}

}  // namespace push_chair
