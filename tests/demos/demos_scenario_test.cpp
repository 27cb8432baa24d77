// Demonstrations of every task family with a scripted expert: 10 generated
// in workers, written, read back and replayed bit for bit; a converted
// point-cloud set against a live point-cloud episode; the command killed
// or stopped while it writes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <thread>

#include "demos_support.hpp"

extern char** environ;

namespace manibench {
namespace {

using testing::DemoSetup;
using testing::getBuildTreeRegistry;

class FamilyDemos : public ::testing::TestWithParam<DemoSetup> {};

TEST_P(FamilyDemos, TenTrajectoriesReplayBitIdentically) {
  const DemoSetup& setup = GetParam();
  const auto dir = testing::makeDemoDir("family");
  const std::string path = (dir / "family.h5").string();
  // Five objects, two each, in two workers.
  std::vector<std::string> objects;
  {
    Environment probe(getBuildTreeRegistry(), setup.task);
    objects = probe.listObjects("train");
  }
  objects.resize(std::min<std::size_t>(objects.size(), 5));
  const GenerationResult result = testing::generateDemoFile(setup, path, 10 / uint32_t(objects.size()), 2, objects);
  EXPECT_TRUE(result.isComplete(10 / uint32_t(objects.size())));
  const DemoReader reader(path);
  ASSERT_EQ(reader.getTrajectoryNames().size(), 10u);
  const auto env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  for (const std::string& name : reader.getTrajectoryNames()) {
    const Trajectory t = reader.read(name);
    EXPECT_TRUE(t.success) << name;
    const ReplayResult r = replayTrajectory(*env, t, true);
    EXPECT_TRUE(r.matches) << name << ": " << r.divergence;
    EXPECT_EQ(r.steps, t.steps);
  }
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Experts, FamilyDemos,
                         ::testing::Values(DemoSetup{"Reach-v0", "reach_expert", ""},
                                           DemoSetup{"OpenCabinetDoor-v0", "open_cabinet_expert", "mobile_panda_ee"},
                                           DemoSetup{"OpenCabinetDrawer-v0", "open_cabinet_expert", "mobile_panda_ee"},
                                           DemoSetup{"MoveBucket-v0", "move_bucket_expert", "mobile_panda_ee"},
                                           DemoSetup{"PushChair-v0", "push_chair_expert", "mobile_panda_ee"}),
                         testing::nameDemoSetup);

TEST(DemoConversion, PointCloudsOfAConvertedSetAreThoseOfALiveEpisode) {
  const DemoSetup setup{"OpenCabinetDrawer-v0", "open_cabinet_expert", "mobile_panda_ee"};
  const auto dir = testing::makeDemoDir("convert");
  const std::string path = (dir / "state.h5").string(), converted_path = (dir / "pointcloud.h5").string();
  testing::generateDemoFile(setup, path, 1, 1, {"2000_link_0", "2001_link_1"});
  PluginRegistry& registry = getBuildTreeRegistry();
  const DemoFileInfo info = DemoReader(path).getInfo();
  const ConversionResult conversion =
      convertDemonstrations(registry, path, converted_path, {"observation.mode=pointcloud"}, {}, 2, info);
  EXPECT_EQ(conversion.converted, 2u);
  EXPECT_TRUE(conversion.failed.empty());

  const DemoReader state_file(path), cloud_file(converted_path);
  ASSERT_EQ(cloud_file.getTrajectoryNames().size(), 2u);
  const Trajectory recorded = state_file.read("traj_1");
  const Trajectory converted = cloud_file.read("traj_1");
  EXPECT_EQ(converted.mode, ObservationMode::PointCloud);
  ASSERT_EQ(converted.getObservationCount(), recorded.steps + 1);
  // A live point-cloud episode with the recorded actions.
  EXPECT_EQ(cloud_file.getInfo().observation_mode, ObservationMode::PointCloud);
  EnvironmentOptions options = calcEnvironmentOptions(calcDemoConfig(registry, info, {"observation.mode=pointcloud"}));
  options.stop_on_success = true;
  Environment live(registry, setup.task, options);
  live.reset(recorded.object_id, recorded.seed);
  const uint32_t compare_at = std::min<uint32_t>(20, recorded.steps);
  for (uint32_t k = 0; k < compare_at; ++k) live.step(recorded.getAction(k));
  const VisualObservation expected = live.getVisualObservation();
  const VisualObservation got = converted.getVisualObservation(compare_at);
  ASSERT_GT(expected.points.size(), 0u);
  EXPECT_EQ(expected.points.xyz, got.points.xyz);
  EXPECT_EQ(expected.points.rgb, got.points.rgb);
  EXPECT_EQ(expected.points.masks, got.points.masks);
  const Eigen::VectorXd agent = live.getObservation();
  EXPECT_EQ(std::memcmp(agent.data(), converted.getObservationState(compare_at).data(),
                        sizeof(double) * std::size_t(agent.size())),
            0);
  // And the converted set replays bit for bit in its own mode.
  const auto env = makeDemoEnvironment(registry, cloud_file.getInfo());
  const ReplayResult replay = replayTrajectory(*env, converted, true);
  EXPECT_TRUE(replay.matches) << replay.divergence;
  std::filesystem::remove_all(dir);
}

// `manibench demos generate` as a user runs it, stopped by `signal` once
// the file holds a trajectory: the file keeps every finished trajectory.
void stopGenerationWith(int signal_number) {
  const auto dir = testing::makeDemoDir("signal" + std::to_string(signal_number));
  const std::string path = (dir / "stopped.h5").string();
  std::vector<std::string> words = {MANIBENCH_TEST_CLI, "demos", "generate", "Reach-v0", "--policy",
                                    "reach_expert", "--per-object", "500", "--max-attempts", "500",
                                    "--out", path, "--no-progress"};
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  // Wait for the first trajectories (the file is being written: reads may
  // fail until a flush completes).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  std::size_t seen = 0;
  while (seen < 3 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    try {
      seen = DemoReader(path).getTrajectoryNames().size();
    } catch (const DemoError&) {
    }
  }
  ASSERT_GE(seen, 3u) << "no trajectories appeared";
  kill(pid, signal_number);
  int status = 0;
  waitpid(pid, &status, 0);
  if (signal_number == SIGKILL) {
    EXPECT_TRUE(WIFSIGNALED(status));
  } else {
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 130);
    EXPECT_TRUE(std::filesystem::exists(getDemoJsonPath(path)));
  }
  const DemoReader reader(path);
  const auto env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  std::size_t replayed = 0;
  for (const std::string& name : reader.getTrajectoryNames()) {
    Trajectory t;
    try {
      t = reader.read(name);
    } catch (const DemoError&) {
      // Only the last one, written when the signal came, may be cut.
      EXPECT_EQ(name, reader.getTrajectoryNames().back());
      continue;
    }
    EXPECT_TRUE(replayTrajectory(*env, t, true).matches) << name;
    ++replayed;
  }
  EXPECT_GE(replayed, 3u);
  std::filesystem::remove_all(dir);
}

TEST(DemoGeneration, CtrlCKeepsEveryFinishedTrajectoryAndTheSidecar) { stopGenerationWith(SIGINT); }
TEST(DemoGeneration, AKilledRunKeepsEveryFlushedTrajectory) { stopGenerationWith(SIGKILL); }

}  // namespace
}  // namespace manibench
