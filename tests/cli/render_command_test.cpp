// `manibench render`: the cameras' images, masks and point clouds of
// RobotTestbed-v0 as files (PNG, PLY), and a video of an episode through
// ffmpeg.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>

#include "test_registry.hpp"

namespace manibench {
namespace {

using manibench::testing::readFile;

// A PNG's width and height, from its IHDR chunk (big-endian, bytes 16-23).
std::pair<uint32_t, uint32_t> readPngSize(const std::string& png) {
  EXPECT_GT(png.size(), 33u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  if (png.size() < 24) return {0, 0};
  auto word = [&](std::size_t at) {
    uint32_t v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = v << 8 | uint8_t(png[at + i]);
    return v;
  };
  return {word(16), word(20)};
}

TEST(RenderCommand, WritesImagesMasksAndPointClouds) {
  const std::filesystem::path dir =
      std::filesystem::path(MANIBENCH_TEST_BINARY_DIR) / "render_command_test_images";
  std::filesystem::remove_all(dir);
  const std::string plugin_path = std::string("MANIBENCH_PLUGIN_PATH=") + MANIBENCH_TEST_FIXTURE_DIR;
  const testing::CommandResult r = testing::runCli(
      {"render", "RobotTestbed-v0", "--seed", "2", "--obs", "pointcloud", "--out", dir.string()},
      {plugin_path});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* camera : {"head_front", "head_left", "head_right"}) {
    const std::string color = readFile(dir / (std::string(camera) + "_color.png"));
    const std::string depth = readFile(dir / (std::string(camera) + "_depth.png"));
    const std::string mask = readFile(dir / (std::string(camera) + "_mask_robot.png"));
    ASSERT_GT(color.size(), 33u) << camera;
    // IHDR: width 400, height 160, then bit depth and color type.
    EXPECT_EQ(readPngSize(color), std::make_pair(400u, 160u)) << camera;
    EXPECT_EQ(int(color[24]), 8);
    EXPECT_EQ(int(color[25]), 2) << "rgb";
    ASSERT_GT(depth.size(), 33u);
    EXPECT_EQ(int(depth[24]), 16) << "depth is 16-bit millimetres";
    EXPECT_EQ(int(depth[25]), 0) << "gray";
    ASSERT_GT(mask.size(), 33u);
    EXPECT_EQ(int(mask[25]), 0);
  }
  const std::string ply = readFile(dir / "pointcloud.ply");
  EXPECT_EQ(ply.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(ply.find("element vertex 1200\n"), std::string::npos);
  EXPECT_NE(ply.find("property uchar mask_robot\n"), std::string::npos);
  const std::size_t body = ply.find("end_header\n") + 11;
  EXPECT_EQ(ply.size() - body, 1200u * (12 + 3 + 1)) << "x y z float, r g b and one mask uchar";
  const std::string full = readFile(dir / "pointcloud_full.ply");
  EXPECT_NE(full.find("element vertex "), std::string::npos);
  EXPECT_EQ(full.find("element vertex 1200\n"), std::string::npos) << "the full cloud is larger";

  const testing::CommandResult bad =
      testing::runCli({"render", "RobotTestbed-v0", "--out", dir.string(), "--obs", "state"},
                      {plugin_path});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--obs must be pointcloud or rgbd"), std::string::npos) << bad.err;
}

// Two head cameras of different sizes: rgbd's stacking could not hold
// them, but render writes each camera's own images in either mode, while an
// episode that observes rgbd (run, a render --video policy) still refuses.
TEST(RenderCommand, RendersEachCameraAtItsOwnSize) {
  const std::string plugin_path = std::string("MANIBENCH_PLUGIN_PATH=") + MANIBENCH_TEST_FIXTURE_DIR;
  const std::string cameras =
      "cameras=[{name: wide, articulation: robot, width: 64, height: 24,"
      "  pose: {position: [0, 0, 1.5], rpy: [0, 0.785, 0]}},"
      " {name: tall, articulation: robot, width: 20, height: 50,"
      "  pose: {position: [0, 0, 1.5], rpy: [0, 0.785, 2.094]}}]";
  for (const char* mode : {"rgbd", "pointcloud"}) {
    const std::filesystem::path dir = std::filesystem::path(MANIBENCH_TEST_BINARY_DIR) /
                                      (std::string("render_command_test_sizes_") + mode);
    std::filesystem::remove_all(dir);
    const testing::CommandResult r = testing::runCli(
        {"render", "RobotTestbed-v0", "--obs", mode, "--set", cameras, "--out", dir.string()},
        {plugin_path});
    ASSERT_EQ(r.exit_code, 0) << mode << ": " << r.err;
    EXPECT_NE(r.out.find("2 cameras"), std::string::npos) << r.out;
    for (const auto& [camera, size] : {std::make_pair("wide", std::make_pair(64u, 24u)),
                                       std::make_pair("tall", std::make_pair(20u, 50u))})
      for (const char* image : {"_color.png", "_depth.png", "_mask_robot.png"})
        EXPECT_EQ(readPngSize(readFile(dir / (std::string(camera) + image))), size)
            << mode << " " << camera << image;
    EXPECT_NE(readFile(dir / "pointcloud.ply").find("element vertex 1200\n"), std::string::npos);
  }

  const testing::CommandResult run = testing::runCli(
      {"run", "RobotTestbed-v0", "--policy", "random", "--obs", "rgbd", "--set", cameras,
       "--set", "episode.max_steps=1"},
      {plugin_path});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("observation mode 'rgbd' stacks the cameras' images, so they must be of "
                         "one size: camera 'wide' is 64x24, camera 'tall' is 20x50"),
            std::string::npos)
      << run.err;
}

TEST(RenderCommand, RecordsAVideoWithFfmpeg) {
  if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "no ffmpeg program (scripts/install-deps installs it)";
  const std::filesystem::path dir =
      std::filesystem::path(MANIBENCH_TEST_BINARY_DIR) / "render_command_test_video";
  std::filesystem::remove_all(dir);
  const std::string video = (dir / "episode.mp4").string();
  const testing::CommandResult r = testing::runCli(
      {"render", "RobotTestbed-v0", "--out", dir.string(), "--video", video, "--policy", "random",
       "--video-size", "160x120", "--set", "episode.max_steps=4"},
      {std::string("MANIBENCH_PLUGIN_PATH=") + MANIBENCH_TEST_FIXTURE_DIR});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("5 frames, 4 steps"), std::string::npos) << r.out;
  const std::string mp4 = readFile(video);
  ASSERT_GT(mp4.size(), 12u);
  EXPECT_EQ(mp4.substr(4, 4), "ftyp") << "an MP4 container";
}

}  // namespace
}  // namespace manibench
