// `manibench run --video`: an expert's whole episode as an MP4 in the state
// observation mode (the expert's), which ffprobe decodes to one frame per
// state the policy saw plus the last: steps + 1. Also: the expert chose its
// controller (no --controller), and a conflicting --controller is refused
// naming both.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>

#include "test_registry.hpp"

namespace manibench {
namespace {

// stdout of a shell command.
std::string capture(const std::string& command) {
  std::string out;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    char buffer[256];
    while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
    pclose(pipe);
  }
  return out;
}

TEST(RunVideo, ExpertEpisodeHasStepsPlusOneFrames) {
  if (std::system("command -v ffprobe >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "no ffprobe program (scripts/install-deps installs ffmpeg)";
  const std::filesystem::path dir = std::filesystem::path(MANIBENCH_TEST_BINARY_DIR) / "run_video_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string video = (dir / "chair.mp4").string();
  const testing::CommandResult r = testing::runCli(
      {"run", "PushChair-v0", "--policy", "push_chair_expert", "--seed", "3", "--video", video, "--video-size",
       "160x120"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("controller mobile_panda_ee"), std::string::npos) << r.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("wrote .*chair\\.mp4: (\\d+) frames, (\\d+) steps"))) << r.out;
  const int frames = std::stoi(m[1]), steps = std::stoi(m[2]);
  EXPECT_GT(steps, 10);
  EXPECT_EQ(frames, steps + 1);
  const std::string probed = capture("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                     "stream=nb_read_frames,width,height -of csv=p=0 '" + video + "'");
  EXPECT_EQ(probed, "160,120," + std::to_string(steps + 1) + "\n");
}

TEST(RunVideo, ConflictingControllerIsRefusedNamingBoth) {
  const testing::CommandResult r =
      testing::runCli({"run", "PushChair-v0", "--policy", "push_chair_expert", "--controller", "mobile_panda"});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("push_chair_expert drives the mobile_panda_ee controller, but --controller mobile_panda"),
            std::string::npos)
      << r.err;
}

TEST(RunVideo, AConfigFileNamingAnotherControllerIsRefusedNamingTheFileLine) {
  const std::filesystem::path dir = std::filesystem::path(MANIBENCH_TEST_BINARY_DIR) / "run_controller_file_test";
  std::filesystem::create_directories(dir);
  const std::string config = (dir / "other_controller.yaml").string();
  std::FILE* file = std::fopen(config.c_str(), "w");
  ASSERT_NE(file, nullptr);
  std::fputs("control:\n  frequency: 20\n  controller: mobile_panda\n", file);
  std::fclose(file);
  const testing::CommandResult r =
      testing::runCli({"run", "PushChair-v0", "--policy", "push_chair_expert", "--config", config});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find(config + ":3: control.controller is mobile_panda, but --policy push_chair_expert drives the "
                                "mobile_panda_ee controller"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace manibench
