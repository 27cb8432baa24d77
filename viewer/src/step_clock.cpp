#include "step_clock.hpp"

#include <cmath>

namespace manibench::viewer {

StepClock::StepClock(double step_seconds, uint32_t max_steps_per_frame)
    : step_seconds_(step_seconds), max_steps_(max_steps_per_frame) {}

void StepClock::restart(double now) {
  origin_ = now;
  owed_base_ = 0;
  window_start_ = now;
  window_steps_ = 0;
}

uint32_t StepClock::takeDueSteps(double now) {
  if (window_start_ < 0) restart(now);
  const auto due_total = static_cast<uint64_t>(std::floor((now - origin_) / step_seconds_));
  uint64_t due = due_total > owed_base_ ? due_total - owed_base_ : 0;
  if (due > max_steps_) {
    // Behind: forgive the rest, so the clock does not run a burst later.
    due = max_steps_;
    origin_ = now;
    owed_base_ = 0;
  } else {
    owed_base_ += due;
  }
  if (now - window_start_ >= 1.0) {
    factor_ = double(window_steps_) * step_seconds_ / (now - window_start_);
    window_start_ = now;
    window_steps_ = 0;
  }
  return uint32_t(due);
}

}  // namespace manibench::viewer
