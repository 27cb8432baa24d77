// Why an episode ended as it did, told from the task's progress signals
// (ABI 1.6, abi.h: reached, holding, progress, blocked) read after every
// step: the classification `manibench survey` prints per object and
// category (docs/partnet.md, "Surveying a folder"). It is the policy's
// business how it acts; this only reads what the task says of the scene,
// so it classifies any policy's episodes alike.
#pragma once

#include <string>
#include <vector>

namespace manibench {

// The outcomes, in the order the classifier tries them after success (the
// first that fits wins). "refused" is an object the task cannot load (no episode).
namespace outcome {
inline constexpr const char* kSuccess = "success";
inline constexpr const char* kFallen = "fallen";                // the object knocked over at the end
inline constexpr const char* kNotStatic = "not_static";        // at the goal, but not held still to the end
inline constexpr const char* kWrongWay = "wrong_way";          // the object moved away from the goal
inline constexpr const char* kBlocked = "blocked";             // never reached; the robot's body ran into something
inline constexpr const char* kNeverReached = "never_reached";  // the effector never got to the part
inline constexpr const char* kGraspLost = "grasp_lost";        // held, then let go of, short of the goal
inline constexpr const char* kNotMoved = "not_moved";          // held, but the object did not move
inline constexpr const char* kNotGrasped = "not_grasped";      // reached, never held, the object did not move
// (a task without a "holding" signal: kNotMoved)
inline constexpr const char* kTimeLimit = "time_limit";        // moving towards the goal when time ran out
inline constexpr const char* kUnknown = "failed";              // the task has no progress signals
inline constexpr const char* kError = "error";                 // the episode did not run to its end
inline constexpr const char* kRefused = "refused";             // the object did not load
}  // namespace outcome

// Every outcome name, in the classifier's order (for tables).
const std::vector<std::string>& listOutcomes();

// Fed the progress signals after each step of one episode.
class OutcomeTracker {
 public:
  // `signals`: the task's progress signal names (TaskDescription).
  explicit OutcomeTracker(const std::vector<std::string>& signals);
  void add(const std::vector<double>& values);
  // The episode's outcome: kSuccess when it succeeded, else the first of
  // the outcomes above whose rule fits what was seen.
  std::string classify(bool success) const;

  // What was seen (for reports): -1 where the task has no such signal.
  double getMaxProgress() const { return max_progress_; }
  double getFinalProgress() const { return final_progress_; }
  int getFirstReachedStep() const { return first_reached_; }
  int getFirstHeldStep() const { return first_held_; }

 private:
  int reached_ = -1, holding_ = -1, progress_ = -1, blocked_ = -1, fallen_ = -1;  // indices into the values
  int steps_ = 0;
  int first_reached_ = -1, first_held_ = -1;
  bool ever_blocked_ = false, blocked_before_reach_ = false, holding_at_end_ = false, fallen_at_end_ = false;
  double max_progress_ = -1, min_progress_ = 0, final_progress_ = -1;
};

}  // namespace manibench
