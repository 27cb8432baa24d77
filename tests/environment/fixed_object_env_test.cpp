// Fixed-object environment ids (<Task>_<object>-v<N>, as ManiSkill's
// OpenCabinetDrawer_1000-v0): name resolution, the objects such an
// environment has, its episodes against the plain task's, and the CLI.
#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/task_name.hpp>

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "test_registry.hpp"

namespace manibench {
namespace {

namespace fs = std::filesystem;
using testing::getBuildTreeRegistry;
using testing::runCli;

using testing::contains;

using testing::catchMessage;

// As the CLI builds environments: the id's configuration, then the id.
std::unique_ptr<Environment> makeEnv(const std::string& id) {
  const ConfigNode config = loadTaskConfig(getBuildTreeRegistry(), id, {});
  return std::make_unique<Environment>(getBuildTreeRegistry(), id, calcEnvironmentOptions(config));
}

TEST(FixedObjectEnv, NamesResolveToTheLongestRegisteredBase) {
  const PluginRegistry& registry = getBuildTreeRegistry();
  TaskId id = resolveTaskId(registry, "Reach-v0");
  EXPECT_EQ(id.task, "Reach-v0");
  EXPECT_FALSE(id.isFixed());
  id = resolveTaskId(registry, "Reach_3-v0");
  EXPECT_EQ(id.task, "Reach-v0");
  EXPECT_EQ(id.object_spec, "3");
  id = resolveTaskId(registry, "OpenCabinetDrawer_2100_link_3-v0");
  EXPECT_EQ(id.task, "OpenCabinetDrawer-v0");
  EXPECT_EQ(id.object_spec, "2100_link_3");
  EXPECT_EQ(makeFixedObjectId("OpenCabinetDoor-v0", "1000_link_0"), "OpenCabinetDoor_1000_link_0-v0");
  EXPECT_EQ(makeFixedObjectId("NoVersion", "1"), "");

  // Task names with underscores: the longest base that fits wins.
  const std::vector<std::string> tasks{"Push-v0", "Push_Chair-v0", "Push_Chair-v1"};
  std::optional<TaskId> m = matchTaskId(tasks, "Push_Chair_3001-v0");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->task, "Push_Chair-v0");
  EXPECT_EQ(m->object_spec, "3001");
  m = matchTaskId(tasks, "Push_Chair_3001-v1");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->task, "Push_Chair-v1");
  m = matchTaskId(tasks, "Push_Table_7-v0");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->task, "Push-v0");
  EXPECT_EQ(m->object_spec, "Table_7");
  m = matchTaskId(tasks, "Push_Chair-v0");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->task, "Push_Chair-v0");  // registered: no spec
  EXPECT_FALSE(m->isFixed());
  EXPECT_FALSE(matchTaskId(tasks, "Push_3-v2"));   // no Push-v2
  EXPECT_FALSE(matchTaskId(tasks, "Push_-v0"));    // empty spec
  EXPECT_FALSE(matchTaskId(tasks, "Push_3"));      // no version
  EXPECT_FALSE(matchTaskId(tasks, "Pushy_3-v0"));  // base must end at the '_'

  const std::string unknown =
      catchMessage<PluginError>([&] { resolveTaskId(registry, "NoSuch_1-v0"); });
  EXPECT_TRUE(contains(unknown, "no task named 'NoSuch_1-v0'")) << unknown;
  EXPECT_TRUE(contains(unknown, "Reach-v0")) << unknown;  // the task list
  EXPECT_TRUE(contains(unknown, "<Task>_<object>-v<N>")) << unknown;
  EXPECT_THROW(resolveTaskId(registry, "Reach_3-v1"), PluginError);
}

TEST(FixedObjectEnv, ReachObjectSpecSelectsExactlyItsObjects) {
  Environment one(getBuildTreeRegistry(), "Reach_1-v0");
  // "1" only: "10" and "11" (test split) do not start with "1_".
  EXPECT_EQ(one.listObjects("train"), std::vector<std::string>{"1"});
  EXPECT_EQ(one.listObjects("test"), std::vector<std::string>{"1"});
  EXPECT_EQ(one.getEnvironmentId(), "Reach_1-v0");
  EXPECT_EQ(one.getTaskDescription().name, "Reach-v0");
  EXPECT_EQ(one.calcPolicyLayout().task_name, "Reach-v0");
  EXPECT_EQ(one.getObjectId(), "1");  // the first scene is the fixed object's
  Environment test_object(getBuildTreeRegistry(), "Reach_10-v0");  // a test-split object
  EXPECT_EQ(test_object.listObjects("train"), std::vector<std::string>{"10"});
  EXPECT_EQ(test_object.getObjectId(), "10");

  const std::string other = catchMessage<manibench::InvalidArgument>([&] { one.reset("2", 0); });
  EXPECT_TRUE(contains(other, "Reach_1-v0")) << other;
  EXPECT_TRUE(contains(other, "'2'")) << other;
  const std::string unknown = catchMessage<PluginError>(
      [&] { Environment env(getBuildTreeRegistry(), "Reach_99-v0"); });
  EXPECT_TRUE(contains(unknown, "Reach-v0 has no object '99' nor objects '99_*'")) << unknown;
  EXPECT_TRUE(contains(unknown, "manibench objects Reach-v0")) << unknown;
}

TEST(FixedObjectEnv, SameEpisodesAsThePlainTaskOnThatObject) {
  Environment fixed(getBuildTreeRegistry(), "Reach_3-v0");
  Environment plain(getBuildTreeRegistry(), "Reach-v0");
  for (uint64_t seed : {0, 11}) {
    fixed.reset("3", seed);
    plain.reset("3", seed);
    Eigen::VectorXd action(fixed.calcPolicyLayout().action_dim);
    for (int step = 0; step < 25; ++step) {
      const Eigen::VectorXd& a = fixed.getObservation();
      const Eigen::VectorXd& b = plain.getObservation();
      ASSERT_EQ(a.size(), b.size());
      ASSERT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())), 0)
          << "seed " << seed << ", step " << step;
      for (Eigen::Index i = 0; i < action.size(); ++i)
        action[i] = std::sin(0.37 * double(step) + double(i) + double(seed));
      const StepResult x = fixed.step(action), y = plain.step(action);
      ASSERT_EQ(std::memcmp(&x.reward, &y.reward, sizeof(double)), 0) << "step " << step;
    }
  }
}

TEST(FixedObjectEnv, CabinetAndLinkIdsListTheirTargets) {
  const auto plain_test = makeEnv("OpenCabinetDrawer-v0")->listObjects("test");
  std::vector<std::string> expected;
  for (const std::string& id : plain_test)
    if (id.rfind("2100_link_", 0) == 0) expected.push_back(id);
  ASSERT_GE(expected.size(), 2u);

  const auto cabinet = makeEnv("OpenCabinetDrawer_2100-v0");
  EXPECT_EQ(cabinet->listObjects("train"), expected);
  EXPECT_EQ(cabinet->listObjects("test"), expected);
  EXPECT_EQ(cabinet->getObjectId(), expected.front());
  cabinet->reset(expected[1], 4);
  EXPECT_EQ(cabinet->getObjectId(), expected[1]);
  const std::string other = catchMessage<manibench::InvalidArgument>([&] { cabinet->reset("2101_link_0", 0); });
  EXPECT_TRUE(contains(other, "OpenCabinetDrawer_2100-v0")) << other;
  EXPECT_TRUE(contains(other, expected.front())) << other;

  const auto link = makeEnv("OpenCabinetDrawer_" + expected[1] + "-v0");
  EXPECT_EQ(link->listObjects("test"), std::vector<std::string>{expected[1]});
  EXPECT_EQ(link->getObjectId(), expected[1]);
}

TEST(FixedObjectEnv, CommandsTakeFixedIds) {
  const auto run = runCli({"run", "Reach_3-v0", "--policy", "reach_expert", "--seed", "5"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(contains(run.out, "task Reach_3-v0")) << run.out;
  EXPECT_TRUE(contains(run.out, "object 3, seed 5")) << run.out;
  // The same episode as the plain task on that object.
  const auto plain = runCli({"run", "Reach-v0", "--object", "3", "--policy", "reach_expert", "--seed", "5"});
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(run.out.substr(run.out.find("object 3")), plain.out.substr(plain.out.find("object 3")));

  const auto objects = runCli({"objects", "OpenCabinetDrawer_2100-v0", "--split", "train", "--ids"});
  ASSERT_EQ(objects.exit_code, 0) << objects.err;
  std::istringstream lines(objects.out);
  int count = 0;
  for (std::string id; std::getline(lines, id); ++count) EXPECT_EQ(id.rfind("2100_link_", 0), 0u) << id;
  EXPECT_GE(count, 2);

  const auto info = runCli({"info", "Reach_3-v0"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_TRUE(contains(info.out, "environment Reach_3-v0: task Reach-v0")) << info.out;
  EXPECT_TRUE(contains(info.out, "fixed objects (1): 3\n")) << info.out;
  const auto config = runCli({"config", "Reach_3-v0"});
  EXPECT_EQ(config.exit_code, 0) << config.err;

  const auto unknown = runCli({"info", "NoSuch_1-v0"});
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_TRUE(contains(unknown.err, "no task named 'NoSuch_1-v0'")) << unknown.err;
  EXPECT_TRUE(contains(unknown.err, "<Task>_<object>-v<N>")) << unknown.err;
  const auto list = runCli({"list"});
  EXPECT_TRUE(contains(list.out, "<Task>_<object>-v<N>")) << list.out;
}

using manibench::testing::readFile;

TEST(FixedObjectEnv, EvalOnAFixedIdMatchesTheTaskOnThatObject) {
  char dir[] = "/tmp/manibench_fixed_XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const fs::path out(dir);
  const auto fixed = runCli({"eval", "Reach_3-v0", "--policy", "reach_expert", "--episodes-per-object",
                             "2", "--out", (out / "fixed").string(), "--no-progress"});
  ASSERT_EQ(fixed.exit_code, 0) << fixed.err;
  const auto plain = runCli({"eval", "Reach-v0", "--split", "train", "--objects", "3", "--policy",
                             "reach_expert", "--episodes-per-object", "2", "--out",
                             (out / "plain").string(), "--no-progress"});
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const std::string episodes = readFile(out / "fixed" / "episodes.csv");
  EXPECT_EQ(std::count(episodes.begin(), episodes.end(), '\n'), 3) << episodes;  // header + 2
  // Same objects and seeds, so the same episodes.
  EXPECT_TRUE(contains(episodes, ",3,0,")) << episodes;
  EXPECT_EQ(episodes, readFile(out / "plain" / "episodes.csv"));
  const std::string json = readFile(out / "fixed" / "summary.json");
  EXPECT_TRUE(contains(json, "\"task\": \"Reach_3-v0\"")) << json;

  // An unknown object fails before any worker starts.
  const auto bad = runCli({"eval", "Reach_99-v0", "--policy", "reach_expert", "--out",
                           (out / "bad").string(), "--no-progress"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(contains(bad.err, "Reach-v0 has no object '99'")) << bad.err;
  EXPECT_FALSE(contains(bad.out, "evaluating")) << bad.out;
  fs::remove_all(out);
}

}  // namespace
}  // namespace manibench
