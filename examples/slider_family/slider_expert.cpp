// slider_expert: proportional control of the block's velocity toward the
// target, reading the observation's segments by name (not by index, so a
// task that grows its observation does not break it).
#include "slider.hpp"

#include <algorithm>

namespace slider {

SliderExpert::SliderExpert(const sdk::PolicyContext& context)
    : position_(context.observation.get("position").offset),
      velocity_(context.observation.get("velocity").offset),
      target_(context.observation.get("target").offset) {}

Eigen::VectorXd SliderExpert::act(const sdk::Observation& o) {
  const double command = 4.0 * (o.state[target_] - o.state[position_]);
  return Eigen::VectorXd::Constant(1, std::clamp(command, -1.0, 1.0));
}

}  // namespace slider
