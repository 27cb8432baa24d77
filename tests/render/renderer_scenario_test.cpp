// The renderer on the real single-arm robot (assets/robots/
// mobile_panda_single.urdf) with its three 400x160 head cameras: a timing
// print (ms per render, never asserted) and memory over many robot scenes.
#include <manibench/renderer.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <set>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include "test_support.hpp"

namespace manibench {
namespace {

const std::string kRobotUrdf =
    std::string(MANIBENCH_TEST_SOURCE_DIR) + "/assets/robots/mobile_panda_single.urdf";

const std::string kFloorUrdf =
    "<robot name='floor'><link name='floor'><inertial><mass value='1'/><inertia ixx='1' "
    "iyy='1' izz='1' ixy='0' ixz='0' iyz='0'/></inertial><visual><geometry><box size='20 20 "
    "0.02'/></geometry><material name='grey'><color rgba='0.6 0.6 0.6 1'/></material></visual>"
    "</link></robot>";

using testing::readRssKb;

struct RobotScene {
  Scene scene;
  int robot = -1;
  int base_link = -1;
  RobotScene() {
    scene.addUrdfString(kFloorUrdf, "", "floor", [] {
      Pose p;
      p.position.z() = -0.01;
      return p;
    }(), true);
    robot = scene.addUrdfFile(kRobotUrdf, "robot", Pose(), true);
    scene.finalize();
    base_link = scene.findLink(robot, "base_link");
  }
};

// The three head mounts of assets/robots/mobile_panda_single.yaml: 1.5 m
// above base_link, pitched 45 degrees down, yaw 0 and +-120 degrees.
std::vector<std::pair<CameraSpec, Pose>> getHeadCameras() {
  std::vector<std::pair<CameraSpec, Pose>> cameras;
  const char* names[3] = {"head_front", "head_left", "head_right"};
  const double yaws[3] = {0, 2 * M_PI / 3, -2 * M_PI / 3};
  for (int k = 0; k < 3; ++k) {
    CameraSpec spec;
    spec.name = names[k];
    Pose mount;
    mount.position = Eigen::Vector3d(0, 0, 1.5);
    mount.orientation = Eigen::AngleAxisd(yaws[k], Eigen::Vector3d::UnitZ()) *
                        Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY());
    cameras.emplace_back(spec, mount);
  }
  return cameras;
}

Pose compose(const Pose& a, const Pose& b) {
  Pose out;
  out.position = a.position + a.orientation * b.position;
  out.orientation = a.orientation * b.orientation;
  return out;
}

TEST(RendererScenario, SingleArmRobotThreeHeadCamerasTiming) {
  RobotScene robot;
  SceneRenderer renderer(robot.scene);
  const auto cameras = getHeadCameras();
  std::vector<CameraImages> images(cameras.size());
  const Eigen::VectorXd q0 = robot.scene.getJointPositions(robot.robot);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> noise(-0.3, 0.3);

  const auto step = [&](int i) {
    Eigen::VectorXd q = q0;
    for (Eigen::Index j = 4; j < q.size() - 2; ++j) q[j] += noise(random);  // arm joints
    q[2] = 0.05 * i;                                                         // base yaw
    robot.scene.setJointPositions(robot.robot, q);
    const Pose base = robot.scene.getLinkPose(robot.base_link);
    for (std::size_t k = 0; k < cameras.size(); ++k) {
      renderer.render(cameras[k].first, compose(base, cameras[k].second), images[k]);
    }
  };
  for (int i = 0; i < 5; ++i) step(i);  // warm-up (shader compile, first allocations)
  const int steps = 100;
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();  // all threads (llvmpipe's too)
  for (int i = 0; i < steps; ++i) step(i);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  std::printf("%s\n", RenderContext::get().describe().c_str());
  std::printf("single-arm robot: %zu triangles, %zu visuals; 3 cameras 400x160: %.2f ms per "
              "render (%.2f ms CPU, all threads), %.1f steps/s (3 renders + readback each)\n",
              renderer.getTriangleCount(), robot.scene.getVisualShapes().size(),
              1e3 * seconds / (steps * 3.0), 1e3 * cpu_seconds / (steps * 3.0), steps / seconds);

  // Each head camera sees the floor (visual 0); a camera facing the robot
  // sees its links, each pixel labelled with a robot link.
  for (const CameraImages& image : images) {
    const auto floor = std::count(image.visual.begin(), image.visual.end(), 0);
    EXPECT_GT(floor, image.width * image.height / 4) << image.camera;
  }
  robot.scene.setJointPositions(robot.robot, q0);  // arm toward -y, not behind the column
  CameraSpec overview;
  overview.name = "overview";
  CameraImages image;
  renderer.render(overview, calcLookAtPose({2.0, 0.5, 1.5}, {0, 0, 0.8}), image);
  std::set<int> links;
  for (std::size_t i = 0; i < image.visual.size(); ++i) {
    if (image.visual[i] > 0) links.insert(image.link[i]);
  }
  EXPECT_GE(links.size(), 5u) << "robot links seen by the overview camera";
}

TEST(RendererScenario, RobotScenesComeAndGoWithoutGrowingMemory) {
  const auto cameras = getHeadCameras();
  const auto cycle = [&] {
    RobotScene robot;
    SceneRenderer renderer(robot.scene);
    CameraImages image;
    const Pose base = robot.scene.getLinkPose(robot.base_link);
    for (const auto& camera : cameras) {
      renderer.render(camera.first, compose(base, camera.second), image);
    }
  };
  if (testing::kAddressSanitized) GTEST_SKIP() << "AddressSanitizer's quarantine grows resident memory";
  for (int i = 0; i < 20; ++i) cycle();
  const long before = readRssKb();
  const auto start = std::chrono::steady_clock::now();
  const int cycles = 200;
  for (int i = 0; i < cycles; ++i) cycle();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const long after = readRssKb();
  std::printf("VmRSS %ld kB -> %ld kB over %d robot scenes (%.1f ms each)\n", before, after,
              cycles, 1e3 * seconds / cycles);
  EXPECT_LT(after, before * 1.10);
}

}  // namespace
}  // namespace manibench
