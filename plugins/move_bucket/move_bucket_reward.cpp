// MoveBucket's dense reward (supplement C.1.3) with ManiSkill v1's terms and
// constants (maniskill-v1-facts.md), in four stages that are strictly
// ordered as C.1 promises: ManiSkill adds +2 per stage, which its own
// shaping terms outweigh (its lift term alone spans 20 x 0.2 m), so here
// each term is bounded and each stage's base lies 2 above the best reward
// of the stage before minus the worst of its own.
#include "move_bucket.hpp"

#include <algorithm>
#include <cmath>

namespace move_bucket {

namespace {

using C = RewardConstants;

double clip(double x, double lo, double hi) { return std::clamp(x, lo, hi); }

// Stage bases, from the bounds of each stage's shaping (the `range` of each
// term below; plugins/move_bucket/tests checks the ordering by sampling):
//   approach [-4.63, 4.21], lift (-7.43, 17.4), carry [-10.63, 21.4), hold (-4.63, 26]
// base_{k+1} = base_k + ceil(sup_k - inf_{k+1}) + 2.
constexpr double kBase[5] = {0, -20, -6, 25, 54};

}  // namespace

RewardStage calcRewardStage(const RewardInputs& in) {
  const bool lifted = std::abs(in.lift - C::kLiftHeight) < C::kLiftTolerance;
  if (lifted) return in.platform_distance <= C::kOnPlatform ? RewardStage::kHold : RewardStage::kCarry;
  return in.gripper_distance < C::kNear ? RewardStage::kLift : RewardStage::kApproach;
}

double calcStagedReward(const RewardInputs& in) {
  const RewardStage stage = calcRewardStage(in);
  const double d = std::max(in.gripper_distance, 0.0);
  const double tilt = clip(in.tilt, 0, manibench::sdk::kPi);
  // Every stage: approach the bucket (distance and its log; range [-2, 10]),
  // grippers level in the bucket frame ([0, 2]), bucket upright
  // ([-0.2 pi, 0], and -2 once tipped past 0.4 pi), small actions.
  double r = -std::min(d, 2.0) - clip(std::log(d + 1e-5), -10, 0);
  r += -0.2 * clip(std::log(std::max(in.height_difference, 0.0) + 1e-5), -10, 0);
  r += -0.2 * tilt - (tilt > C::kTipped ? 2.0 : 0.0);
  r += -1e-6 * std::min(in.action_norm, 10.0);
  if (stage != RewardStage::kApproach) r += 2 * clip(in.opposition, 0, 2);  // grippers opposed, [0, 4]
  switch (stage) {
    case RewardStage::kApproach:
      break;
    case RewardStage::kLift:  // rise ([-2, 2)) to 0.2 m ([-5, -0.6])
      r += 2 * clip(1 - std::exp(-in.up_speed), -1, 1) -
           20 * std::min(std::abs(in.lift - C::kLiftHeight), 0.25);
      break;
    case RewardStage::kCarry:  // upright (log, [0, 4]); towards the platform ([-2, 2), [-4, -0.6))
      r += -clip(std::log(tilt + 1e-5), -4, 0);
      r += 2 * clip(1 - std::exp(-in.speed_to_platform), -1, 1) - 2 * std::min(in.platform_distance, 2.0);
      break;
    case RewardStage::kHold:  // upright (log); slow ((0, 2]), static (2), upright (2)
      r += -clip(std::log(tilt + 1e-5), -4, 0);
      r += 2 * std::exp(-10 * std::max(in.speed, 0.0));
      if (in.speed <= C::kStaticSpeed && in.angular_speed <= C::kStaticAngularSpeed) r += 2;
      if (tilt <= C::kUpright) r += 2;
      break;
  }
  return kBase[int(stage)] + r;
}

}  // namespace move_bucket
