// Real-time pacing of env steps: how many steps a frame owes so that
// simulated time keeps up with the wall clock, at most a few per frame so
// that the window stays responsive; when the machine cannot keep up, the
// clock lets the debt go (no burst of steps later) and reports the ratio
// of simulated to wall time as slower than real time.
#pragma once

#include <cstdint>

namespace manibench::viewer {

class StepClock {
 public:
  // `step_seconds`: simulated seconds per env step (frame_skip / control
  // frequency); `max_steps_per_frame`: the catch-up limit.
  StepClock(double step_seconds, uint32_t max_steps_per_frame);

  // (Re)starts counting at wall time `now` (s): after a pause, a reset, a
  // single step.
  void restart(double now);
  // The steps due at `now` since the last call (at most the limit; the
  // rest is dropped, and the ratio shows it).
  uint32_t takeDueSteps(double now);
  // Wall time at which the next step falls due (after takeDueSteps).
  double getNextStepTime() const { return origin_ + double(owed_base_ + 1) * step_seconds_; }
  // Steps actually taken (a step can end the episode before the debt is
  // paid): for the real-time ratio.
  void countSteps(uint32_t steps) { window_steps_ += steps; }
  // Simulated over wall time in the last ~second of running (1: real time);
  // 0 before a full window.
  double getRealTimeFactor() const { return factor_; }
  double getStepSeconds() const { return step_seconds_; }

 private:
  double step_seconds_;
  uint32_t max_steps_;
  double origin_ = 0;       // wall time of step 0 of the count
  uint64_t owed_base_ = 0;  // steps accounted for since origin_
  double window_start_ = -1;
  uint64_t window_steps_ = 0;
  double factor_ = 0;
};

}  // namespace manibench::viewer
