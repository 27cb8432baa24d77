// demos convert --controller: the experts' end-effector demonstrations of
// every mobile-manipulation family converted into mobile_panda's joint
// velocity actions (exactly: mobile_panda_ee is a layer over mobile_panda,
// ABI 1.7) replay bit for bit under mobile_panda, through the same physics
// states as the recording; tracked back into mobile_panda_ee they still
// succeed, and one that does not is left out unless kept.
#include <gtest/gtest.h>

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include "demos_support.hpp"

namespace manibench {
namespace {

using testing::DemoSetup;
using testing::getBuildTreeRegistry;

class ExactConversion : public ::testing::TestWithParam<DemoSetup> {};

TEST_P(ExactConversion, TheExpertsDemonstrationsReplayBitForBitInMobilePandaActions) {
  const DemoSetup& setup = GetParam();
  const PluginRegistry& registry = getBuildTreeRegistry();
  const auto dir = testing::makeDemoDir("controller");
  const std::string source = (dir / "ee.h5").string(), converted = (dir / "joints.h5").string();
  std::vector<std::string> objects;
  {
    Environment probe(registry, setup.task);
    objects = probe.listObjects("train");
  }
  objects.resize(std::min<std::size_t>(objects.size(), 2));
  ASSERT_TRUE(testing::generateDemoFile(setup, source, 1, 2, objects).isComplete(1));
  DemoFileInfo info;
  {
    const DemoReader reader(source);
    info = reader.getInfo();
  }
  const ConversionResult result =
      convertDemonstrations(registry, source, converted, {"control.controller=mobile_panda"}, {}, 2, info);
  EXPECT_TRUE(result.failed.empty()) << result.failed.front();
  ASSERT_EQ(result.converted, objects.size());

  const DemoReader in(source), out(converted);
  EXPECT_EQ(out.getInfo().controller, "mobile_panda");
  EXPECT_EQ(out.getInfo().conversion, "exact");
  EXPECT_EQ(out.getInfo().converted_from, source);
  const auto env = makeDemoEnvironment(registry, out.getInfo());
  EXPECT_EQ(env->getControllerDescription().name, "mobile_panda");
  const uint32_t frame_skip = 5;  // the mobile Panda tasks' (kit/mobile_panda.hpp)
  EXPECT_EQ(env->getTaskDescription().frame_skip, 1u);
  EXPECT_EQ(env->getTaskDescription().max_episode_steps, 200u * frame_skip);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string name = "traj_" + std::to_string(i);
    const Trajectory original = in.read(name), joints = out.read(name);
    EXPECT_EQ(joints.object_id, original.object_id);
    EXPECT_EQ(joints.seed, original.seed);
    EXPECT_TRUE(joints.success) << name;
    // Per arm 7 joint velocities and a gripper for 3 + 3 TCP velocities
    // and a gripper: 11 -> 12 single-arm (cabinets), 18 -> 20 dual.
    const uint32_t arms = (original.action_dim - 4) / 7;
    EXPECT_EQ(joints.action_dim, 4 + 8 * arms);
    EXPECT_EQ(joints.action_dim, env->getControllerDescription().action_dim);
    // Each recorded step is frame_skip control steps; the tasks' hold_steps
    // count steps, so at control rate success comes a few recorded steps
    // sooner (docs/demonstrations.md).
    EXPECT_LE(joints.steps, original.steps * frame_skip);
    EXPECT_GT(joints.steps, original.steps);
    // The same physics: every frame_skip-th state is the recording's.
    for (uint32_t k = 0; k * frame_skip <= joints.steps; ++k)
      ASSERT_EQ(env->findSceneDifference(joints.getEnvState(k * frame_skip), original.getEnvState(k)), "")
          << name << " step " << k;
    // Joint velocity actions inside the controller's range.
    EXPECT_LE(*std::max_element(joints.actions.begin(), joints.actions.end()), 1.0);
    EXPECT_GE(*std::min_element(joints.actions.begin(), joints.actions.end()), -1.0);
    const ReplayResult replay = replayTrajectory(*env, joints, true);
    EXPECT_TRUE(replay.matches) << name << ": " << replay.divergence;
    EXPECT_EQ(replay.steps, joints.steps);
  }
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Experts, ExactConversion,
                         ::testing::Values(DemoSetup{"OpenCabinetDoor-v0", "open_cabinet_expert", "mobile_panda_ee"},
                                           DemoSetup{"OpenCabinetDrawer-v0", "open_cabinet_expert", "mobile_panda_ee"},
                                           DemoSetup{"MoveBucket-v0", "move_bucket_expert", "mobile_panda_ee"},
                                           DemoSetup{"PushChair-v0", "push_chair_expert", "mobile_panda_ee"}),
                         testing::nameDemoSetup);

TEST(ControllerConversion, WhatIsNoLayerOverTheTargetIsTracked) {
  const PluginRegistry& registry = getBuildTreeRegistry();
  // The drawer's default controller is mobile_panda, no layer: into
  // mobile_panda_ee its demonstrations are tracked, at the file's rate.
  DemoFileInfo info = testing::makeDemoInfo(registry, {"OpenCabinetDrawer-v0", "zero", ""});
  info.controller = "mobile_panda";
  const std::optional<ControllerConversion> tracked =
      planControllerConversion(registry, info, {"control.controller=mobile_panda_ee"});
  ASSERT_TRUE(tracked);
  EXPECT_EQ(tracked->method, "tracked");
  EXPECT_EQ(tracked->source, "mobile_panda");
  EXPECT_EQ(tracked->target, "mobile_panda_ee");
  EXPECT_EQ(std::count(tracked->target_overrides.begin(), tracked->target_overrides.end(), "control.frame_skip=1"), 0);
  // The same controller is no controller conversion.
  EXPECT_FALSE(planControllerConversion(registry, info, {"control.controller=mobile_panda"}));
}

// Back from mobile_panda into mobile_panda_ee (no layer that way): tracked,
// each trajectory kept while it still succeeds, with its tracking error.
class TrackedConversion : public ::testing::TestWithParam<DemoSetup> {};

TEST_P(TrackedConversion, JointVelocityDemonstrationsTrackedInEndEffectorActionsStillSucceed) {
  const DemoSetup& setup = GetParam();
  const PluginRegistry& registry = getBuildTreeRegistry();
  const auto dir = testing::makeDemoDir("tracked");
  const std::string ee = (dir / "ee.h5").string(), joints = (dir / "joints.h5").string(),
                    tracked = (dir / "tracked.h5").string(), cut = (dir / "cut.h5").string();
  std::vector<std::string> objects;
  {
    Environment probe(registry, setup.task);
    objects = probe.listObjects("train");
  }
  objects.resize(2);
  ASSERT_TRUE(testing::generateDemoFile(setup, ee, 1, 2, objects).isComplete(1));
  auto infoOf = [](const std::string& path) {
    const DemoReader reader(path);
    return reader.getInfo();
  };
  ASSERT_EQ(convertDemonstrations(registry, ee, joints, {"control.controller=mobile_panda"}, {}, 2, infoOf(ee)).converted, 2u);
  const ConversionResult result =
      convertDemonstrations(registry, joints, tracked, {"control.controller=mobile_panda_ee"}, {}, 2, infoOf(joints));
  EXPECT_TRUE(result.failed.empty() && result.dropped.empty());
  ASSERT_EQ(result.converted, 2u);
  const DemoReader out(tracked);
  EXPECT_EQ(out.getInfo().controller, "mobile_panda_ee");
  EXPECT_EQ(out.getInfo().conversion, "tracked");
  const auto env = makeDemoEnvironment(registry, out.getInfo());
  for (const std::string& name : out.getTrajectoryNames()) {
    const Trajectory t = out.read(name);
    EXPECT_TRUE(t.success) << name;
    // Millimetres: the TCP follows the recorded one closely.
    EXPECT_GE(t.tracking_error, 0) << name;
    EXPECT_LT(t.tracking_error, 0.01) << name;
    EXPECT_EQ(t.action_dim, 11u);
    const ReplayResult replay = replayTrajectory(*env, t, true);
    EXPECT_TRUE(replay.matches) << name << ": " << replay.divergence;
  }
  // With a time limit too short to succeed, every trajectory is left out,
  // unless --keep-failed, which keeps them with success 0.
  const std::vector<std::string> short_limit = {"control.controller=mobile_panda_ee", "episode.max_steps=20"};
  const ConversionResult left = convertDemonstrations(registry, joints, cut, short_limit, {}, 1, infoOf(joints));
  EXPECT_EQ(left.converted, 0u);
  ASSERT_EQ(left.dropped.size(), 2u);
  EXPECT_NE(left.dropped.front().find("traj_0: no success in 20 steps"), std::string::npos) << left.dropped.front();
  const ConversionResult kept =
      convertDemonstrations(registry, joints, cut, short_limit, {}, 1, infoOf(joints), {}, /*keep_failed=*/true);
  EXPECT_EQ(kept.converted, 2u);
  EXPECT_TRUE(kept.dropped.empty());
  const DemoReader failed(cut);
  const Trajectory first = failed.read("traj_0");
  EXPECT_FALSE(first.success);
  EXPECT_EQ(first.steps, 20u);
  EXPECT_GE(first.tracking_error, 0);
  std::filesystem::remove_all(dir);
}

// This process's children (the conversion workers), from /proc.
std::vector<pid_t> listChildren() {
  std::vector<pid_t> children;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream in(task.path() / "children");
    pid_t pid = 0;
    while (in >> pid) children.push_back(pid);
  }
  return children;
}

// Issue 51's case: a conversion worker killed mid-run. Its trajectory is
// handed out again to a worker started in its place: every trajectory is
// in the output, the same as a run nobody killed, and the redone one is
// named. Interrupted, a run keeps what it finished and names the rest.
TEST(ConversionFaults, AKilledWorkersTrajectoryIsRedoneAndAnInterruptionNamesTheRest) {
  const DemoSetup setup{"OpenCabinetDrawer-v0", "open_cabinet_expert", "mobile_panda_ee"};
  const PluginRegistry& registry = getBuildTreeRegistry();
  const auto dir = testing::makeDemoDir("faults");
  const std::string source = (dir / "ee.h5").string();
  std::vector<std::string> objects;
  {
    Environment probe(registry, setup.task);
    objects = probe.listObjects("train");
  }
  ASSERT_GE(objects.size(), 2u);
  objects.resize(2);
  ASSERT_TRUE(testing::generateDemoFile(setup, source, 1, 2, objects).isComplete(1));
  DemoFileInfo info;
  {
    const DemoReader reader(source);
    info = reader.getInfo();
  }
  const std::vector<std::string> to_joints = {"control.controller=mobile_panda"};
  const std::string clean = (dir / "clean.h5").string(), killed = (dir / "killed.h5").string();
  ASSERT_EQ(convertDemonstrations(registry, source, clean, to_joints, {}, 1, info).converted, objects.size());

  // One worker converts everything; it is killed once it has finished the
  // first trajectory, as it is handed the second.
  ConversionHooks hooks;
  std::size_t kills = 0;
  hooks.on_progress = [&](std::size_t finished, std::size_t, double) {
    const std::vector<pid_t> children = listChildren();
    if (finished == 1 && kills == 0 && !children.empty()) {
      ::kill(children.front(), SIGKILL);
      ++kills;
    }
  };
  const ConversionResult redone = convertDemonstrations(registry, source, killed, to_joints, {}, 1, info, hooks);
  ASSERT_EQ(kills, 1u);
  EXPECT_TRUE(redone.failed.empty()) << redone.failed.front();
  EXPECT_EQ(redone.converted, objects.size());
  EXPECT_EQ(redone.worker_restarts, 1u);
  ASSERT_EQ(redone.redone.size(), 1u);
  EXPECT_NE(redone.redone.front().find("killed by signal 9 (SIGKILL"), std::string::npos) << redone.redone.front();
  {
    const DemoReader a(clean), b(killed);
    ASSERT_EQ(b.getTrajectoryNames(), a.getTrajectoryNames());
    for (const std::string& name : a.getTrajectoryNames()) {
      const Trajectory x = a.read(name), y = b.read(name);
      EXPECT_EQ(y.actions, x.actions) << name;
      EXPECT_EQ(y.object_id, x.object_id) << name;
    }
  }

  // Stopped once the first trajectory is done: it is kept, the other named.
  ConversionHooks stop;
  std::size_t done = 0;
  stop.on_progress = [&](std::size_t finished, std::size_t, double) { done = finished; };
  stop.should_stop = [&] { return done >= 1; };
  const std::string cut = (dir / "cut.h5").string();
  const ConversionResult interrupted = convertDemonstrations(registry, source, cut, to_joints, {}, 1, info, stop);
  EXPECT_TRUE(interrupted.interrupted);
  EXPECT_EQ(interrupted.converted, 1u);
  ASSERT_EQ(interrupted.failed.size(), objects.size() - 1);
  EXPECT_NE(interrupted.failed.front().find("interrupted"), std::string::npos) << interrupted.failed.front();
  const DemoReader kept(cut);
  EXPECT_EQ(kept.getTrajectoryNames().size(), 1u);
  EXPECT_FALSE(std::filesystem::exists(cut + ".parts"));
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Cabinets, TrackedConversion,
                         ::testing::Values(DemoSetup{"OpenCabinetDoor-v0", "open_cabinet_expert", "mobile_panda_ee"},
                                           DemoSetup{"OpenCabinetDrawer-v0", "open_cabinet_expert", "mobile_panda_ee"}),
                         testing::nameDemoSetup);

}  // namespace
}  // namespace manibench
