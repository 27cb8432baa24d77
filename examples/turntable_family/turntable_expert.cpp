// turntable_expert: a turn rate proportional to the heading error (the
// task's default joint_velocity controller), reading the observation's
// segments by name, so a task that grows its observation does not break it.
#include "turntable.hpp"

#include <algorithm>

namespace turntable {

TurntableExpert::TurntableExpert(const sdk::PolicyContext& context)
    : heading_(context.observation.get("heading").offset),
      target_(context.observation.get("target_heading").offset) {}

Eigen::VectorXd TurntableExpert::act(const sdk::Observation& o) {
  const double turn = 2.0 * (o.state[target_] - o.state[heading_]);
  return Eigen::VectorXd::Constant(1, std::clamp(turn, -1.0, 1.0));
}

}  // namespace turntable
