// The survey's classifier (manibench/outcome.hpp) on signal sequences made
// to show each outcome, as a task's measure_progress gives them step by
// step; tests/cli/survey_test.cpp runs it on real episodes.
#include <manibench/outcome.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace manibench {
namespace {

const std::vector<std::string> kCabinet = {"reached", "holding", "progress", "blocked"};

// Each step: reached, holding, progress, blocked.
std::string classify(const std::vector<std::vector<double>>& steps, bool success = false,
                     const std::vector<std::string>& signals = kCabinet) {
  OutcomeTracker tracker(signals);
  for (const std::vector<double>& values : steps) tracker.add(values);
  return tracker.classify(success);
}

TEST(Outcome, EachRuleOnTheSignalsThatShowIt) {
  EXPECT_EQ(classify({{0, 0, 0, 0}}, true), outcome::kSuccess);
  EXPECT_EQ(classify({{0, 0, 0, 0}, {0, 0, 0, 0}}), outcome::kNeverReached);
  EXPECT_EQ(classify({{0, 0, 0, 1}, {0, 0, 0, 0}}), outcome::kBlocked);
  // Reached, held, the door opened a third of the way, then the grip went.
  EXPECT_EQ(classify({{1, 0, 0, 0}, {1, 1, 0.1, 0}, {1, 1, 0.3, 0}, {0, 0, 0.3, 0}}), outcome::kGraspLost);
  // Held to the end without the joint moving: pulled the wrong way or stuck.
  EXPECT_EQ(classify({{1, 1, 0, 0}, {1, 1, 0.01, 0}}), outcome::kNotMoved);
  // Held and opening when time ran out.
  EXPECT_EQ(classify({{1, 1, 0.2, 0}, {1, 1, 0.6, 0}}), outcome::kTimeLimit);
  EXPECT_EQ(classify({{1, 0, 0, 0}, {1, 0, 0, 0}}), outcome::kNotGrasped);
  // Pushed open without holding: moving, out of time.
  EXPECT_EQ(classify({{1, 0, 0.4, 0}}), outcome::kTimeLimit);
  // Opened past the goal but still swinging at the end.
  EXPECT_EQ(classify({{1, 1, 0.5, 0}, {1, 1, 1.05, 0}}), outcome::kNotStatic);
  EXPECT_EQ(classify({{1, 1, -0.2, 0}}), outcome::kWrongWay);
}

TEST(Outcome, TasksWithFewerSignals) {
  const std::vector<std::string> chair = {"reached", "progress", "fallen"};
  EXPECT_EQ(classify({{1, 0.5, 0}, {1, 0.8, 1}}, false, chair), outcome::kFallen);
  EXPECT_EQ(classify({{1, 0.0, 0}}, false, chair), outcome::kNotMoved);
  EXPECT_EQ(classify({{0, 0.0, 0}}, false, chair), outcome::kNeverReached);
  EXPECT_EQ(classify({{}}, false, {}), outcome::kUnknown);
  EXPECT_EQ(classify({{}}, true, {}), outcome::kSuccess);
}

TEST(Outcome, EveryNameIsListedOnce) {
  const std::vector<std::string>& names = listOutcomes();
  for (const char* name : {outcome::kSuccess, outcome::kFallen, outcome::kNotStatic, outcome::kWrongWay,
                           outcome::kBlocked, outcome::kNeverReached, outcome::kGraspLost, outcome::kNotMoved,
                           outcome::kNotGrasped, outcome::kTimeLimit, outcome::kUnknown, outcome::kError,
                           outcome::kRefused})
    EXPECT_EQ(std::count(names.begin(), names.end(), name), 1) << name;
}

}  // namespace
}  // namespace manibench
