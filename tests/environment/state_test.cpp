// Environment::saveState / restoreState (ABI 1.2): restoring the blob of
// any step continues bit-identically to the uninterrupted run, in the same
// environment or a fresh one, on real tasks, controllers and physics; bad
// blobs and plugins built before ABI 1.2 are errors that say why.
#include <manibench/environment.hpp>
#include <manibench/plugin_instances.hpp>

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "test_registry.hpp"

namespace manibench {
namespace {

using testing::catchMessage;
using testing::expectMentions;
using testing::getBuildTreeRegistry;

// What one env step gave, compared bit for bit.
struct StepRecord {
  Eigen::VectorXd observation;
  double reward = 0;
  std::vector<uint8_t> flags;
  std::vector<double> values;
  bool done = false;

  bool operator==(const StepRecord& o) const {
    return observation.size() == o.observation.size() &&
           std::memcmp(observation.data(), o.observation.data(),
                       sizeof(double) * std::size_t(observation.size())) == 0 &&
           std::memcmp(&reward, &o.reward, sizeof reward) == 0 && flags == o.flags &&
           values.size() == o.values.size() &&
           std::memcmp(values.data(), o.values.data(), sizeof(double) * values.size()) == 0 &&
           done == o.done;
  }
};

StepRecord takeStep(Environment& env, const Eigen::VectorXd& action) {
  const StepResult result = env.step(action);
  return {env.getObservation(), result.reward, result.flags, result.values, result.isDone()};
}

// Jerky actions in [-1.2, 1.2] (clipped by the environment), fixed by `seed`.
std::vector<Eigen::VectorXd> makeRandomActions(Eigen::Index dim, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.2, 1.2);
  std::vector<Eigen::VectorXd> actions(count, Eigen::VectorXd(dim));
  for (Eigen::VectorXd& a : actions)
    for (Eigen::Index i = 0; i < dim; ++i) a[i] = uniform(rng);
  return actions;
}

// Runs `actions` from a reset on (object, seed); saves at step `save_at`;
// returns the steps after the save.
std::vector<StepRecord> runAndSave(Environment& env, const std::string& object, uint64_t seed,
                                   const std::vector<Eigen::VectorXd>& actions, int save_at,
                                   std::vector<uint8_t>& blob) {
  env.reset(object, seed);
  std::vector<StepRecord> after;
  for (int k = 0; k < int(actions.size()); ++k) {
    if (k == save_at) blob = env.saveState();
    const StepRecord record = takeStep(env, actions[k]);
    if (k >= save_at) after.push_back(record);
    if (record.done) break;
  }
  return after;
}

std::vector<StepRecord> continueFrom(Environment& env, const std::vector<uint8_t>& blob,
                                     const std::vector<Eigen::VectorXd>& actions, int save_at,
                                     std::size_t count) {
  env.restoreState(blob);
  EXPECT_EQ(env.getElapsedSteps(), uint32_t(save_at));
  std::vector<StepRecord> after;
  for (std::size_t k = 0; k < count; ++k) after.push_back(takeStep(env, actions[save_at + k]));
  return after;
}

void expectSameSteps(const std::vector<StepRecord>& a, const std::vector<StepRecord>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_TRUE(a[k] == b[k]) << "step " << k << " after the save";
}

TEST(EnvironmentState, RestoringContinuesBitIdenticallyUnderJerkyActions) {
  // Reach-v0 (joint_velocity: its filter is controller state) and the
  // drawer (mobile_panda: base, arm, fingers in contact with the cabinet).
  for (const char* task : {"Reach-v0", "OpenCabinetDrawer-v0"}) {
    SCOPED_TRACE(task);
    Environment env(getBuildTreeRegistry(), task);
    const std::string object = env.listObjects("train").front();
    const auto actions = makeRandomActions(env.getControllerDescription().action_dim, 60, 7);
    std::vector<uint8_t> blob;
    const auto uninterrupted = runAndSave(env, object, 11, actions, 25, blob);
    ASSERT_FALSE(blob.empty());
    const Environment::StateHeader header = Environment::readStateHeader(blob);
    EXPECT_EQ(header.task, task);
    EXPECT_EQ(header.object_id, object);
    EXPECT_EQ(header.seed, 11u);
    EXPECT_EQ(header.step, 25u);
    // The same environment, after running on: back to the save.
    expectSameSteps(uninterrupted, continueFrom(env, blob, actions, 25, uninterrupted.size()));
    // A fresh environment, and one that was on another object.
    Environment fresh(getBuildTreeRegistry(), task);
    expectSameSteps(uninterrupted, continueFrom(fresh, blob, actions, 25, uninterrupted.size()));
    Environment elsewhere(getBuildTreeRegistry(), task);
    elsewhere.reset(elsewhere.listObjects("test").back(), 3);
    expectSameSteps(uninterrupted, continueFrom(elsewhere, blob, actions, 25, uninterrupted.size()));
    // A restore of a restore: the blob of a restored environment is the same.
    fresh.restoreState(blob);
    EXPECT_EQ(fresh.saveState(), blob);
  }
}

TEST(EnvironmentState, TheExpertsGraspAndTheHoldCountSurviveARestore) {
  // mobile_panda_ee integrates TCP targets (controller state); the task's
  // success holds for 10 steps (the SDK's count, task state); the grasp
  // holds the handle by friction anchors (scene state). Saved inside the
  // hold, the restored run succeeds at the same step.
  Environment env(getBuildTreeRegistry(), "OpenCabinetDrawer-v0",
                  [] {
                    EnvironmentOptions o;
                    o.controller = "mobile_panda_ee";
                    return o;
                  }());
  const std::string object = env.listObjects("test").front();
  PolicyInstance expert(getBuildTreeRegistry(), "open_cabinet_expert", "", env.calcPolicyLayout());
  env.reset(object, 5);
  expert.reset(5);
  std::vector<Eigen::VectorXd> actions;
  int success_step = -1;
  for (int k = 0; k < 200 && success_step < 0; ++k) {
    Eigen::VectorXd action;
    expert.act(env.getObservation(), env.getElapsedSteps(), action, env.getVisualObservation());
    actions.push_back(action);
    if (env.step(action).success) success_step = k;
  }
  ASSERT_GT(success_step, 20) << "the expert opens the test drawer";
  const int save_at = success_step - 4;  // the hold has counted 5 of 10
  std::vector<uint8_t> blob;
  const auto uninterrupted = runAndSave(env, object, 5, actions, save_at, blob);
  ASSERT_EQ(uninterrupted.size(), actions.size() - std::size_t(save_at));
  EXPECT_TRUE(uninterrupted.back().flags.back() == 1);
  Environment fresh(getBuildTreeRegistry(), "OpenCabinetDrawer-v0", env.getOptions());
  expectSameSteps(uninterrupted, continueFrom(fresh, blob, actions, save_at, uninterrupted.size()));
}

TEST(EnvironmentState, BadBlobsNameWhatIsWrong) {
  Environment reach(getBuildTreeRegistry(), "Reach-v0");
  reach.reset(reach.listObjects("train").front(), 1);
  reach.step(Eigen::VectorXd::Constant(reach.getControllerDescription().action_dim, 0.5));
  const std::vector<uint8_t> blob = reach.saveState();

  Environment drawer(getBuildTreeRegistry(), "OpenCabinetDrawer-v0");
  expectMentions(catchMessage<manibench::InvalidArgument>([&] { drawer.restoreState(blob); }),
                 {"a state of task 'Reach-v0'", "'OpenCabinetDrawer-v0'"});
  expectMentions(catchMessage<manibench::InvalidArgument>([&] {
                   reach.restoreState(std::vector<uint8_t>(blob.begin(), blob.begin() + 40));
                 }),
                 {"cut short"});
  std::vector<uint8_t> other = blob;
  other[0] = 'X';
  expectMentions(catchMessage<manibench::InvalidArgument>([&] { reach.restoreState(other); }),
                 {"not a manibench environment state"});
  other = blob;
  other[4] = 99;  // the version
  expectMentions(catchMessage<manibench::InvalidArgument>([&] { reach.restoreState(other); }),
                 {"environment state version 99", "reads version 1"});
  other = blob;
  other.push_back(0);
  expectMentions(catchMessage<manibench::InvalidArgument>([&] { reach.restoreState(other); }),
                 {"1 bytes left over"});
  // The scene's bytes start after the header: flip the structure's
  // fingerprint (8 bytes after the scene part's "MBSC" and version).
  other = blob;
  const uint8_t scene_magic[4] = {'M', 'B', 'S', 'C'};
  const auto at = std::search(other.begin(), other.end(), scene_magic, scene_magic + 4);
  ASSERT_NE(at, other.end());
  at[8] ^= 0xFF;
  expectMentions(catchMessage<manibench::InvalidArgument>([&] { reach.restoreState(other); }),
                 {"scene of another structure"});
  // Another controller's state.
  EnvironmentOptions position;
  position.controller = "joint_position";
  Environment reach_position(getBuildTreeRegistry(), "Reach-v0", position);
  expectMentions(catchMessage<manibench::InvalidArgument>([&] { reach_position.restoreState(blob); }),
                 {"a state of controller 'joint_velocity'", "'joint_position'"});
  // Nothing to save before a reset.
  Environment idle(getBuildTreeRegistry(), "Reach-v0");
  EXPECT_THROW(idle.saveState(), std::logic_error);
  // The environment still works after every refusal.
  reach.restoreState(blob);
  EXPECT_EQ(reach.getElapsedSteps(), 1u);
}

TEST(EnvironmentState, APluginBuiltBeforeAbi12CannotSaveItsState) {
  PluginRegistry registry;
  registry.loadDirectories({MANIBENCH_TEST_BUILD_PLUGIN_DIR});
  registry.loadLibrary(std::string(MANIBENCH_TEST_FIXTURE_DIR) +
                       "/state/libfixture_pre_state_task.so");
  Environment env(registry, "PreState-v0");
  env.reset("0", 0);
  env.step(Eigen::VectorXd::Constant(1, 0.3));  // it runs
  const std::string message = catchMessage<PluginCallError>([&] { env.saveState(); });
  expectMentions(message, {"task 'PreState-v0'", "libfixture_pre_state_task.so",
                           "older than 1.2", "get_state"});
}

}  // namespace
}  // namespace manibench
