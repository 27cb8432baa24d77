// Demonstration files on Reach-v0 (fast): generated in worker processes,
// written, read back, replayed bit for bit; what a stopped run, a file cut
// short and bad files give.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "hdf5.hpp"
#include "demos_support.hpp"

namespace manibench {
namespace {

using testing::catchMessage;
using testing::DemoSetup;
using testing::expectMentions;
using testing::getBuildTreeRegistry;

const DemoSetup kReach{"Reach-v0", "reach_expert", ""};

template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

class ReachDemos : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::makeDemoDir("reach");
    path_ = (dir_ / "reach.h5").string();
    result_ = testing::generateDemoFile(kReach, path_, 2, 2, {"0", "1", "2", "3", "4"});
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static std::filesystem::path dir_;
  static std::string path_;
  static GenerationResult result_;
};
std::filesystem::path ReachDemos::dir_;
std::string ReachDemos::path_;
GenerationResult ReachDemos::result_;

TEST_F(ReachDemos, TenTrajectoriesAreWrittenInObjectAndLevelOrder) {
  ASSERT_TRUE(result_.isComplete(2));
  EXPECT_EQ(result_.trajectories, 10u);
  const DemoReader reader(path_);
  EXPECT_EQ(reader.getInfo().task, "Reach-v0");
  EXPECT_EQ(reader.getInfo().observation_mode, ObservationMode::State);
  EXPECT_FALSE(reader.getInfo().controller.empty());
  EXPECT_EQ(reader.getInfo().condition_names.back(), "success");
  ASSERT_EQ(reader.getTrajectoryNames().size(), 10u);
  for (std::size_t i = 0; i < 10; ++i) {
    const Trajectory t = reader.read(reader.getTrajectoryNames()[i]);
    EXPECT_EQ(t.object_id, std::to_string(i / 2));
    EXPECT_EQ(t.level, i % 2);
    EXPECT_EQ(t.seed, calcEpisodeSeed(0, t.object_id, t.level));
    ASSERT_GT(t.steps, 0u);
    EXPECT_TRUE(t.success);
    // Each ends at its first success (C.2): success only at the last step.
    EXPECT_EQ(t.success_flags.back(), 1);
    EXPECT_EQ(t.terminated.back(), 1);
    EXPECT_EQ(t.truncated.back(), 0);
    for (uint32_t k = 0; k + 1 < t.steps; ++k) EXPECT_EQ(t.success_flags[k], 0) << "step " << k;
    EXPECT_EQ(t.getObservationCount(), t.steps + 1);
    EXPECT_EQ(t.getStateCount(), t.steps + 1);
    EXPECT_EQ(t.actions.size(), std::size_t(t.steps) * t.action_dim);
    double total = 0;
    for (double r : t.rewards) total += r;
    EXPECT_DOUBLE_EQ(total, t.total_reward);
  }
  // The sidecar lists them too.
  std::ifstream json(getDemoJsonPath(path_));
  std::stringstream text;
  text << json.rdbuf();
  expectMentions(text.str(), {"\"env_id\": \"Reach-v0\"", "\"traj_9\"", "\"elapsed_steps\""});
}

TEST_F(ReachDemos, EveryTrajectoryReplaysBitIdentically) {
  const DemoReader reader(path_);
  const auto env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  for (const std::string& name : reader.getTrajectoryNames()) {
    const Trajectory t = reader.read(name);
    const ReplayResult r = replayTrajectory(*env, t, true);
    EXPECT_TRUE(r.matches) << name << ": " << r.divergence;
    EXPECT_EQ(r.steps, t.steps) << name;
  }
}

TEST_F(ReachDemos, TheFileDoesNotDependOnTheNumberOfWorkers) {
  const std::string one = (dir_ / "one_worker.h5").string();
  testing::generateDemoFile(kReach, one, 2, 1, {"0", "1", "2", "3", "4"});
  const DemoReader a(path_), b(one);
  ASSERT_EQ(a.getTrajectoryNames(), b.getTrajectoryNames());
  for (const std::string& name : a.getTrajectoryNames()) {
    const Trajectory x = a.read(name), y = b.read(name);
    EXPECT_TRUE(sameBits(x.actions, y.actions)) << name;
    const auto env = makeDemoEnvironment(getBuildTreeRegistry(), a.getInfo());
    for (uint32_t k = 0; k < x.getStateCount() && k < y.getStateCount(); ++k) {
      const std::string difference = env->findStateDifference(x.getEnvState(k), y.getEnvState(k));
      EXPECT_EQ(difference, "") << name << ", state " << k;
      if (!difference.empty()) break;
    }
    EXPECT_TRUE(sameBits(x.state, y.state)) << name;
  }
}

TEST_F(ReachDemos, ReplayNamesTheFirstDifference) {
  const DemoReader reader(path_);
  Trajectory t = reader.read("traj_3");
  ASSERT_GT(t.steps, 8u);
  t.actions[5 * t.action_dim] += 0.25;  // the action of step 5
  const auto env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  const ReplayResult r = replayTrajectory(*env, t, true);
  EXPECT_FALSE(r.matches);
  EXPECT_EQ(r.steps, 6u);
  expectMentions(r.divergence, {"step 6"});
}

TEST_F(ReachDemos, AStateOfAnotherTaskIsRefusedNamingBoth) {
  const DemoReader reader(path_);
  const Trajectory t = reader.read("traj_0");
  DemoFileInfo other = reader.getInfo();
  Environment env(getBuildTreeRegistry(), "OpenCabinetDrawer-v0");
  const std::string message = catchMessage<manibench::InvalidArgument>([&] { replayTrajectory(env, t, true); });
  expectMentions(message, {"Reach-v0", "OpenCabinetDrawer-v0"});
}

// Two trajectories are the same, field by field, bit for bit (state mode).
void expectSameTrajectory(const Trajectory& a, const Trajectory& b, const std::string& name) {
  SCOPED_TRACE(name);
  EXPECT_EQ(a.object_id, b.object_id);
  EXPECT_EQ(a.level, b.level);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.success, b.success);
  EXPECT_TRUE(sameBits(std::vector<double>{a.total_reward}, {b.total_reward}));
  EXPECT_TRUE(sameBits(a.actions, b.actions));
  EXPECT_TRUE(sameBits(a.rewards, b.rewards));
  EXPECT_TRUE(sameBits(a.terminated, b.terminated));
  EXPECT_TRUE(sameBits(a.truncated, b.truncated));
  EXPECT_TRUE(sameBits(a.success_flags, b.success_flags));
  EXPECT_TRUE(sameBits(a.conditions, b.conditions));
  EXPECT_TRUE(sameBits(a.state, b.state));
  EXPECT_TRUE(sameBits(a.env_states, b.env_states));
  EXPECT_TRUE(sameBits(a.env_state_offsets, b.env_state_offsets));
}

// Where a trajectory's objects lie in the file: from its group's header to
// the end of the last of its headers and data chunks.
struct Extent {
  uint64_t begin = UINT64_MAX, end = 0;
};
Extent findTrajectoryExtent(const std::string& path, const std::string& name) {
  using namespace demos_detail;
  const Handle file = openForReading(path);
  Extent extent;
  auto add_header = [&](const Handle& object) {
    H5O_info_t info{};
    EXPECT_GE(H5Oget_info2(object.get(), &info, H5O_INFO_BASIC | H5O_INFO_HDR), 0);
    EXPECT_EQ(info.hdr.nchunks, 1u) << "a header in one piece: " << info.addr;
    extent.begin = std::min<uint64_t>(extent.begin, info.addr);
    extent.end = std::max<uint64_t>(extent.end, info.addr + info.hdr.space.total);
  };
  const Handle group = openGroup(file, name);
  add_header(group);
  for (const std::string& link : listLinks(group)) {
    add_header(Handle(H5Oopen(group.get(), link.c_str(), H5P_DEFAULT)));
    extent.end = std::max(extent.end, calcDataEnd(group, link));
  }
  return extent;
}

// A file cut anywhere (a full disk, a copy that stopped) keeps exactly the
// trajectories flushed before the cut, equal to the originals; a cut before
// any was complete is an error saying where it fell.
TEST_F(ReachDemos, AFileCutAnywhereKeepsTheTrajectoriesFlushedBeforeTheCut) {
  const DemoReader source(path_);
  std::vector<Trajectory> originals;
  for (const std::string& name : source.getTrajectoryNames()) originals.push_back(source.read(name));
  ASSERT_EQ(originals.size(), 10u);
  // The set written again, noting the file's size once each trajectory is
  // flushed: trajectory k lies entirely before flushed[k].
  const std::string whole = (dir_ / "whole.h5").string();
  std::vector<uint64_t> flushed;
  {
    DemoWriter writer(whole, source.getInfo(), originals.size());
    for (const Trajectory& t : originals) {
      writer.append(t);
      flushed.push_back(std::filesystem::file_size(whole));
    }
    writer.close();
  }
  const uint64_t size = std::filesystem::file_size(whole);
  const uint64_t root_end = demos_detail::readFileLayout(whole).root_header_end;
  ASSERT_GT(root_end, 1000u);
  // Each trajectory lies whole on disk once flushed, after the one before.
  std::vector<Extent> extents;
  for (std::size_t k = 0; k < originals.size(); ++k) {
    extents.push_back(findTrajectoryExtent(whole, "traj_" + std::to_string(k)));
    EXPECT_LE(extents[k].end, flushed[k]) << k;
    EXPECT_GT(extents[k].begin, k ? extents[k - 1].begin : root_end) << k;
  }
  struct Cut {
    std::string where;
    uint64_t bytes;
    long readable;                       // -1: the file does not open
    std::vector<std::string> message;  // what the error says
  };
  const std::vector<Cut> cuts = {
      {"inside the superblock", 20, -1, {"cut short inside its HDF5 superblock", "20 bytes"}},
      {"inside the root group's header", 2000, -1,
       {"cut short: 2000 of the", "inside the root group's header", "no trajectory was complete"}},
      {"inside the set's description", root_end + 100, -1, {"cut short", "meta"}},
      {"at the end of trajectory 0, less a byte", extents[0].end - 1, 0, {}},
      {"after trajectory 1", extents[1].end, 2, {}},
      {"after trajectory 1 was flushed", flushed[1], 2, {}},
      {"in the middle of trajectory 3", (extents[3].begin + extents[3].end) / 2, 3, {}},
      {"one byte short of the end", size - 1,
       long(std::count_if(extents.begin(), extents.end(), [&](const Extent& e) { return e.end < size; })),
       {}},
  };
  for (const Cut& c : cuts) {
    SCOPED_TRACE(c.where);
    const std::string cut = (dir_ / "cut.h5").string();
    std::filesystem::copy_file(whole, cut, std::filesystem::copy_options::overwrite_existing);
    std::filesystem::resize_file(cut, c.bytes);
    if (c.readable < 0) {
      const std::string message = catchMessage<DemoError>([&] { DemoReader reader(cut); });
      expectMentions(message, c.message);
      expectMentions(message, {cut});
      continue;
    }
    const DemoReader reader(cut);
    EXPECT_EQ(reader.getFileBytes(), c.bytes);
    EXPECT_EQ(reader.getRecordedBytes(), size);
    ASSERT_EQ(reader.getTrajectoryNames().size(), originals.size());
    long readable = 0;
    for (std::size_t k = 0; k < originals.size(); ++k) {
      const std::string name = reader.getTrajectoryNames()[k];
      if (long(k) < c.readable) {
        expectSameTrajectory(reader.read(name), originals[k], name);
        ++readable;
      } else {
        expectMentions(catchMessage<DemoError>([&] { reader.read(name); }), {cut, name});
      }
    }
    EXPECT_EQ(readable, c.readable);
  }
  // What is kept replays bit for bit.
  std::filesystem::resize_file((dir_ / "cut.h5"), flushed[1]);
  const DemoReader reader((dir_ / "cut.h5").string());
  const auto env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  EXPECT_TRUE(replayTrajectory(*env, reader.read("traj_1"), true).matches);
}

TEST_F(ReachDemos, AStoppedGenerationKeepsEveryFinishedTrajectory) {
  const std::string stopped = (dir_ / "stopped.h5").string();
  std::size_t kept = 0;
  GenerationHooks hooks;
  hooks.on_progress = [&](const GenerationProgress& p) { kept = p.kept; };
  hooks.should_stop = [&] { return kept >= 3; };
  const GenerationResult result = testing::generateDemoFile(kReach, stopped, 30, 1, {"0", "1"}, hooks);
  EXPECT_TRUE(result.interrupted);
  EXPECT_GE(result.trajectories, 3u);
  EXPECT_LT(result.trajectories, 60u);
  const DemoReader reader(stopped);
  EXPECT_EQ(reader.getTrajectoryNames().size(), result.trajectories);
  const auto env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  for (const std::string& name : reader.getTrajectoryNames())
    EXPECT_TRUE(replayTrajectory(*env, reader.read(name), true).matches) << name;
}

// Issue 51's matrix, `demos generate`: a worker killed mid-run. Its episode
// is a failed attempt (a crash), a worker is started in its place, and the
// generation goes on to further levels until every object has its
// trajectories, each of which replays bit for bit.
TEST_F(ReachDemos, AKilledWorkerIsReplacedAndEveryObjectStillGetsItsTrajectories) {
  const std::string killed = (dir_ / "killed.h5").string();
  std::size_t kills = 0;
  GenerationHooks hooks;
  hooks.on_progress = [&](const GenerationProgress& p) {
    if (p.kept < 1 || kills > 0) return;
    std::vector<pid_t> children;
    for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
      std::ifstream in(task.path() / "children");
      for (pid_t pid = 0; in >> pid;) children.push_back(pid);
    }
    if (children.empty()) return;
    ::kill(children.front(), SIGKILL);
    ++kills;
  };
  const GenerationResult result = testing::generateDemoFile(kReach, killed, 3, 1, {"0", "1"}, hooks);
  ASSERT_EQ(kills, 1u);
  EXPECT_FALSE(result.interrupted);
  EXPECT_TRUE(result.isComplete(3));
  EXPECT_EQ(result.worker_restarts, 1u);
  uint32_t failures = 0;
  for (const GenerationObjectResult& o : result.objects) failures += o.failures;
  EXPECT_EQ(failures, 1u);
  const DemoReader reader(killed);
  ASSERT_EQ(reader.getTrajectoryNames().size(), 6u);
  const auto env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  for (const std::string& name : reader.getTrajectoryNames())
    EXPECT_TRUE(replayTrajectory(*env, reader.read(name), true).matches) << name;
}

TEST_F(ReachDemos, BadFilesAreClearErrors) {
  using namespace demos_detail;
  const std::string missing = (dir_ / "missing.h5").string();
  expectMentions(catchMessage<DemoError>([&] { DemoReader r(missing); }), {missing, "cannot be read"});
  expectMentions(catchMessage<DemoError>([&] { DemoReader r(dir_.string()); }), {dir_.string(), "is a directory"});
  const std::string text = (dir_ / "text.h5").string();
  std::ofstream(text) << "trajectories, honestly\n";
  expectMentions(catchMessage<DemoError>([&] { DemoReader r(text); }), {text, "not an HDF5 file"});

  const std::string foreign = (dir_ / "foreign.h5").string();
  {
    Handle file = createFile(foreign, 0);
    writeAttribute(file, "title", std::string("someone else's data"));
  }
  expectMentions(catchMessage<DemoError>([&] { DemoReader r(foreign); }), {foreign, "not a manibench demonstration file"});

  // A later format version, and a trajectory without its rewards.
  const std::string edited = (dir_ / "edited.h5").string();
  std::filesystem::copy_file(path_, edited, std::filesystem::copy_options::overwrite_existing);
  {
    Handle file(H5Fopen(edited.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    ASSERT_TRUE(file.valid());
    ASSERT_GE(H5Ldelete(file.get(), "traj_1/rewards", H5P_DEFAULT), 0);
  }
  {
    const DemoReader reader(edited);
    expectMentions(catchMessage<DemoError>([&] { reader.read("traj_1"); }), {edited, "traj_1", "rewards"});
    EXPECT_EQ(reader.read("traj_2").object_id, "1");  // the others still read
    expectMentions(catchMessage<DemoError>([&] { reader.read("traj_77"); }), {edited, "traj_77", "no such trajectory"});
  }
  {
    Handle file(H5Fopen(edited.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    writeAttribute(file, "format_version", uint64_t(7));
  }
  expectMentions(catchMessage<DemoError>([&] { DemoReader r(edited); }), {edited, "format version 7", "version 1"});

  // A blob that is not an environment state.
  const DemoReader reader(path_);
  Trajectory t = reader.read("traj_0");
  t.env_states.assign(t.env_states.size(), 0xAB);
  const auto env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  EXPECT_FALSE(catchMessage<std::exception>([&] { replayTrajectory(*env, t, true); }).empty());
}

// The commands as a user runs them: generate, info, replay --check,
// convert in two workers, the converted set replayed, a video, h5ls.
// --action-noise: the executed actions carry the noise (replay is exact),
// the policy's own are kept beside them, and the same seeds give the same
// noise.
TEST(DemoCommands, ActionNoiseKeepsThePolicysActionsAndReplaysExactly) {
  using testing::runCli;
  const auto dir = testing::makeDemoDir("noise");
  const std::string a = (dir / "a.h5").string(), b = (dir / "b.h5").string(), plain = (dir / "plain.h5").string();
  for (const std::string& file : {a, b}) {
    const auto r = runCli({"demos", "generate", "Reach-v0", "--policy", "reach_expert", "--objects", "0,1",
                           "--per-object", "2", "--workers", "2", "--action-noise", "0.05", "--out", file});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const auto r = runCli({"demos", "generate", "Reach-v0", "--policy", "reach_expert", "--objects", "0,1",
                         "--per-object", "2", "--out", plain});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  DemoReader noisy(a), again(b), clean(plain);
  for (const std::string& name : noisy.getTrajectoryNames()) {
    const Trajectory t = noisy.read(name), u = again.read(name);
    ASSERT_EQ(t.policy_actions.size(), t.actions.size()) << name;
    EXPECT_FALSE(sameBits(t.policy_actions, t.actions)) << name;
    double largest = 0;
    for (std::size_t i = 0; i < t.actions.size(); ++i)
      largest = std::max(largest, std::abs(t.actions[i] - t.policy_actions[i]));
    EXPECT_GT(largest, 0.05) << name;  // dozens of draws of N(0, 0.05^2)
    EXPECT_TRUE(sameBits(t.actions, u.actions)) << name;
    EXPECT_TRUE(sameBits(t.policy_actions, u.policy_actions)) << name;
  }
  EXPECT_TRUE(clean.read("traj_0").policy_actions.empty());
  const auto replayed = runCli({"demos", "replay", a, "--check"});
  EXPECT_EQ(replayed.exit_code, 0) << replayed.out << replayed.err;
  expectMentions(replayed.out, {"4 trajectories: 4 bit-identical, 0 differ"});
  const auto bad = runCli({"demos", "generate", "Reach-v0", "--policy", "reach_expert", "--action-noise", "-1",
                           "--out", (dir / "bad.h5").string()});
  EXPECT_EQ(bad.exit_code, 2);
  expectMentions(bad.err, {"--action-noise needs a non-negative number"});
  std::filesystem::remove_all(dir);
}

TEST(DemoCommands, GenerateInfoReplayConvertAndVideo) {
  using testing::runCli;
  const auto dir = testing::makeDemoDir("cli");
  const std::string file = (dir / "reach.h5").string(), cloud = (dir / "reach_pc.h5").string();
  const auto generated = runCli({"demos", "generate", "Reach-v0", "--policy", "reach_expert", "--objects",
                                 "0,1,2", "--per-object", "2", "--workers", "2", "--out", file});
  ASSERT_EQ(generated.exit_code, 0) << generated.err;
  expectMentions(generated.out, {"wrote 6 trajectories of 3 object(s)"});
  const auto info = runCli({"demos", "info", file});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  expectMentions(info.out, {"Reach-v0", "reach_expert", "trajectories   6 of 3 object(s)", "bytes per step"});
  const auto replayed = runCli({"demos", "replay", file, "--check"});
  EXPECT_EQ(replayed.exit_code, 0) << replayed.out << replayed.err;
  expectMentions(replayed.out, {"6 trajectories: 6 bit-identical, 0 differ"});

  const auto converted =
      runCli({"demos", "convert", file, "--obs", "pointcloud", "--out", cloud, "--workers", "2"});
  ASSERT_EQ(converted.exit_code, 0) << converted.out << converted.err;
  expectMentions(converted.out, {"wrote 6 trajectories in pointcloud mode"});
  const auto cloud_replayed = runCli({"demos", "replay", cloud, "--check", "--trajectories", "traj_0,traj_5"});
  EXPECT_EQ(cloud_replayed.exit_code, 0) << cloud_replayed.out;
  expectMentions(cloud_replayed.out, {"2 trajectories: 2 bit-identical"});
  EXPECT_FALSE(std::filesystem::exists(cloud + ".part0"));  // the workers' parts are gone

  // Images with observation.rgb_dtype uint8: stored as bytes, replayed exactly.
  const std::string images = (dir / "reach_rgbd.h5").string();
  const auto to_rgbd = runCli({"demos", "convert", file, "--obs", "rgbd", "--set",
                               "observation.rgb_dtype=uint8", "--out", images, "--workers", "1"});
  ASSERT_EQ(to_rgbd.exit_code, 0) << to_rgbd.out << to_rgbd.err;
  const auto images_replayed = runCli({"demos", "replay", images, "--check", "--trajectories", "traj_2"});
  EXPECT_EQ(images_replayed.exit_code, 0) << images_replayed.out;
  expectMentions(images_replayed.out, {"1 trajectories: 1 bit-identical"});
  {
    DemoReader reader(images);
    const Trajectory t = reader.read("traj_2");
    EXPECT_TRUE(t.image_rgb.empty());
    EXPECT_EQ(t.image_rgb_bytes.size(),
              std::size_t(t.getObservationCount()) * t.height * t.width * 3 * t.camera_count);
  }

  const std::string videos = (dir / "videos").string();
  const auto video = runCli({"demos", "replay", file, "--trajectories", "traj_1", "--video", videos,
                             "--video-size", "96x64"});
  EXPECT_EQ(video.exit_code, 0) << video.out << video.err;
  EXPECT_GT(std::filesystem::file_size(std::filesystem::path(videos) / "traj_1.mp4"), 0u);

  const auto missing = runCli({"demos", "replay", (dir / "none.h5").string()});
  EXPECT_EQ(missing.exit_code, 1);
  expectMentions(missing.err, {"none.h5", "cannot be read"});
  const auto unknown = runCli({"demos", "replay", file, "--trajectories", "traj_9"});
  EXPECT_EQ(unknown.exit_code, 1);
  expectMentions(unknown.out, {"traj_9", "no such trajectory"});

  // Debian's hdf5-tools read it as any HDF5 file.
  if (std::system("command -v h5ls >/dev/null 2>&1") == 0) {
    const std::string listing = (dir / "h5ls.txt").string();
    ASSERT_EQ(std::system(("h5ls -r '" + cloud + "' > '" + listing + "'").c_str()), 0);
    std::ifstream in(listing);
    std::stringstream text;
    text << in.rdbuf();
    expectMentions(text.str(), {"/meta", "/traj_0/actions", "/traj_0/obs/xyz", "/traj_5/env_states"});
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace manibench
