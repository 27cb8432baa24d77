#include <manibench/outcome.hpp>

#include <algorithm>

namespace manibench {

namespace {

// A fraction of the goal below which the object has not moved: 5 % of
// the way (a door 4 degrees of v1's 90 % of its range, a drawer a few cm),
// more than the play a closed joint has under a push.
constexpr double kMoved = 0.05;
// Moved back by more than that: the wrong way.
constexpr double kBackwards = -0.05;

int findSignal(const std::vector<std::string>& signals, const char* name) {
  const auto it = std::find(signals.begin(), signals.end(), name);
  return it == signals.end() ? -1 : int(it - signals.begin());
}

}  // namespace

const std::vector<std::string>& listOutcomes() {
  static const std::vector<std::string> names = {
      outcome::kSuccess,  outcome::kFallen, outcome::kNotStatic, outcome::kWrongWay,    outcome::kBlocked,
      outcome::kNeverReached, outcome::kGraspLost, outcome::kNotMoved, outcome::kNotGrasped,
      outcome::kTimeLimit, outcome::kUnknown,  outcome::kError,       outcome::kRefused};
  return names;
}

OutcomeTracker::OutcomeTracker(const std::vector<std::string>& signals)
    : reached_(findSignal(signals, "reached")),
      holding_(findSignal(signals, "holding")),
      progress_(findSignal(signals, "progress")),
      blocked_(findSignal(signals, "blocked")),
      fallen_(findSignal(signals, "fallen")) {}

void OutcomeTracker::add(const std::vector<double>& values) {
  const auto get = [&](int index) { return index >= 0 && std::size_t(index) < values.size() ? values[std::size_t(index)] : 0.0; };
  const bool reached = get(reached_) > 0.5, holding = get(holding_) > 0.5, blocked = get(blocked_) > 0.5;
  if (reached && first_reached_ < 0) first_reached_ = steps_;
  if (holding && first_held_ < 0) first_held_ = steps_;
  if (blocked) {
    ever_blocked_ = true;
    if (first_reached_ < 0) blocked_before_reach_ = true;
  }
  holding_at_end_ = holding;
  fallen_at_end_ = get(fallen_) > 0.5;
  if (progress_ >= 0) {
    const double p = get(progress_);
    max_progress_ = std::max(max_progress_, p);
    min_progress_ = std::min(min_progress_, p);
    final_progress_ = p;
  }
  ++steps_;
}

std::string OutcomeTracker::classify(bool success) const {
  if (success) return outcome::kSuccess;
  if (progress_ < 0 && reached_ < 0 && holding_ < 0) return outcome::kUnknown;
  if (fallen_at_end_) return outcome::kFallen;
  if (progress_ >= 0 && final_progress_ >= 1) return outcome::kNotStatic;
  if (progress_ >= 0 && min_progress_ < kBackwards && max_progress_ < kMoved) return outcome::kWrongWay;
  const bool moved = progress_ >= 0 && max_progress_ >= kMoved;
  if (reached_ >= 0 && first_reached_ < 0 && !moved)
    return blocked_before_reach_ ? outcome::kBlocked : outcome::kNeverReached;
  if (holding_ >= 0 && first_held_ >= 0) {
    if (!holding_at_end_) return outcome::kGraspLost;
    if (!moved) return outcome::kNotMoved;
    return outcome::kTimeLimit;
  }
  if (!moved) return ever_blocked_ ? outcome::kBlocked : holding_ >= 0 ? outcome::kNotGrasped : outcome::kNotMoved;
  return outcome::kTimeLimit;
}

}  // namespace manibench
