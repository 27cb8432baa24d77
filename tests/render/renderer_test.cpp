// The headless renderer against real EGL (llvmpipe on CI) and real Scenes:
// metric depth, point clouds, segmentation, lighting, threads, memory.
// EGL across fork() is renderer_fork_test.cpp.
#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/renderer.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "render_scenes.hpp"
#include "test_support.hpp"

namespace manibench {
namespace {

using namespace render_test;

CameraSpec makeCamera(const std::string& name, int width, int height,
                      double fovy = CameraSpec().fovy) {
  CameraSpec camera;
  camera.name = name;
  camera.width = width;
  camera.height = height;
  camera.fovy = fovy;
  return camera;
}

// A base with a box on a prismatic joint along y (the moving link).
std::string sliderUrdf() {
  return "<robot name='slider'><link name='base'>" + inertial() +
         "</link><link name='carriage'>" + inertial() +
         "<visual><geometry><box size='0.1 0.1 0.1'/></geometry>"
         "<material name='red'><color rgba='1 0 0 1'/></material></visual></link>"
         "<joint name='slide' type='prismatic'><parent link='base'/><child link='carriage'/>"
         "<axis xyz='0 1 0'/><limit lower='-1' upper='1' effort='10' velocity='1'/></joint>"
         "</robot>";
}

// Signed distance-like measure of p (box frame) to the surface of a box of
// half extents h: 0 on the surface.
double boxSurfaceDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& h) {
  const Eigen::Vector3d q = p.cwiseAbs() - h;
  const double outside = q.cwiseMax(0.0).norm();
  const double inside = std::min(q.maxCoeff(), 0.0);
  return std::abs(outside + inside);
}

using testing::readRssKb;

TEST(Renderer, DescribesTheDeviceAndRendererOnce) {
  RenderContext& context = RenderContext::get();
  EXPECT_EQ(&context, &RenderContext::get());
  const RenderDeviceInfo& info = context.getInfo();
  EXPECT_FALSE(info.gl_renderer.empty());
  EXPECT_FALSE(info.platform.empty());
  EXPECT_NE(context.describe().find(info.gl_renderer), std::string::npos);
  std::printf("render context: %s\n", context.describe().c_str());
  RenderOptions no_software;
  no_software.allow_software = false;
  if (info.software) {
    try {
      RenderContext::get(no_software);
      ADD_FAILURE() << "software rendering was not refused";
    } catch (const RenderError& e) {
      EXPECT_NE(std::string(e.what()).find("software"), std::string::npos) << e.what();
    }
  } else {
    EXPECT_NO_THROW(RenderContext::get(no_software));
  }
}

TEST(Renderer, PlaneDepthIsMetricWithinAMillimetre) {
  Scene scene;
  // Plate face toward the camera at x = 1.99 (box centre 2, thickness 0.02).
  scene.addUrdfString(boxUrdf("plate", 0.02, 10, 10), "", "plate", at(2, 0.3, 0.1), true);
  scene.finalize();
  SceneRenderer renderer(scene);
  CameraSpec camera = makeCamera("front", 64, 48, 1.2);
  CameraImages images;
  Pose pose;
  pose.position = Eigen::Vector3d(0, 0.1, 0.2);
  renderer.render(camera, pose, images);
  ASSERT_EQ(images.depth.size(), 64u * 48u);
  double worst = 0;
  for (float z : images.depth) worst = std::max(worst, std::abs(z - 1.99));
  std::printf("plane depth: worst error %.1f um\n", worst * 1e6);
  EXPECT_LT(worst, 1e-3);
  const Eigen::Matrix3Xf world = calcCameraPoints(images, true);
  ASSERT_EQ(world.cols(), 64 * 48);
  EXPECT_LT((world.row(0).array() - 1.99f).abs().maxCoeff(), 1e-3f);
  // Unprojection spans the field of view: the top rows are above the
  // camera, the image's left is +y (SAPIEN: y left).
  const Eigen::Matrix3Xf local = calcCameraPoints(images, false);
  EXPECT_GT(local(2, 0), 0.5f);               // top-left pixel: up
  EXPECT_GT(local(1, 0), 0.5f);               // and left
  EXPECT_LT(local(2, 64 * 48 - 1), -0.5f);    // bottom-right: down
  EXPECT_LT(local(1, 64 * 48 - 1), -0.5f);    // and right
  EXPECT_NEAR(std::tan(0.6) * 1.99 * (1 - 1.0 / 48), local(2, 0), 1e-3);

  // Farther than `far`: nothing.
  camera.far = 1.5;
  renderer.render(camera, pose, images);
  EXPECT_EQ(countHits(images), 0);
  EXPECT_EQ(*std::max_element(images.depth.begin(), images.depth.end()), 0.0f);
}

TEST(Renderer, BoxPointCloudLiesOnItsFaces) {
  Scene scene;
  scene.addGround(0);  // drawn as background: depth, but visual -1
  const Eigen::Vector3d half(0.15, 0.1, 0.05);
  Pose box_pose = at(0.4, -0.2, 0.3, 0.5);
  box_pose.orientation =
      box_pose.orientation * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX());
  scene.addUrdfString(boxUrdf("box", 0.3, 0.2, 0.1), "", "box", box_pose, true);
  scene.finalize();
  SceneRenderer renderer(scene);
  CameraSpec camera = makeCamera("oblique", 160, 120, 0.8);
  CameraImages images;
  renderer.render(camera, calcLookAtPose({1.2, 0.5, 0.9}, box_pose.position), images);
  std::vector<int> pixels;
  const Eigen::Matrix3Xf world = calcCameraPoints(images, true, &pixels);
  ASSERT_GT(world.cols(), 500);
  const Eigen::Isometry3d box_to_world =
      Eigen::Translation3d(box_pose.position) * box_pose.orientation;
  double worst = 0, worst_ground = 0;
  int box_points = 0, ground_points = 0;
  for (Eigen::Index k = 0; k < world.cols(); ++k) {
    const std::size_t i = static_cast<std::size_t>(pixels[static_cast<std::size_t>(k)]);
    if (images.visual[i] < 0) {  // the ground, at z = 0
      ++ground_points;
      EXPECT_EQ(images.link[i], -1);
      worst_ground = std::max(worst_ground, std::abs(static_cast<double>(world(2, k))));
      continue;
    }
    ++box_points;
    const Eigen::Vector3d p = box_to_world.inverse() * world.col(k).cast<double>();
    worst = std::max(worst, boxSurfaceDistance(p, half));
    EXPECT_EQ(images.visual[i], 0);
  }
  std::printf("box point cloud: %d points, worst distance to a face %.1f um; "
              "%d ground points, worst height %.1f um\n",
              box_points, worst * 1e6, ground_points, worst_ground * 1e6);
  EXPECT_GT(box_points, 500);
  EXPECT_LT(worst, 1e-3);
  EXPECT_EQ(box_points + ground_points, 160 * 120) << "the ground fills the rest of the view";
  EXPECT_LT(worst_ground, 1e-3);
  // Three faces are visible from this corner: the points span all axes.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (Eigen::Index k = 0; k < world.cols(); ++k) {
    if (images.visual[static_cast<std::size_t>(pixels[static_cast<std::size_t>(k)])] < 0) continue;
    const Eigen::Vector3d p = box_to_world.inverse() * world.col(k).cast<double>();
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  EXPECT_GT((hi - lo).minCoeff(), 0.05);
}

TEST(Renderer, GroundIsBackgroundWithMetricDepth) {
  const double height = 0.25;
  const auto build = [&](Scene& scene, bool ground) {
    if (ground) scene.addGround(height);
    // A block standing on the ground, off the image centre.
    scene.addUrdfString(boxUrdf("block", 0.1, 0.1, 0.1, "1 0 0 1"), "", "block",
                        at(0.3, 0, height + 0.05), true);
    scene.finalize();
  };
  Scene scene;
  build(scene, true);
  SceneRenderer renderer(scene);
  CameraSpec camera = makeCamera("down", 64, 48, 0.9);
  // 1 m straight above the ground: every ground pixel is at depth 1.
  const Pose down = calcLookAtPose({0, 0, height + 1}, {0, 0, height});
  CameraImages images;
  renderer.render(camera, down, images);
  int ground = 0, block = 0;
  double worst = 0;
  for (std::size_t i = 0; i < images.depth.size(); ++i) {
    if (images.visual[i] == 0) {
      ++block;
      EXPECT_TRUE(images.depth[i] > 0.899f && images.depth[i] < 1.0f) << "block top or side";
      continue;
    }
    ++ground;
    EXPECT_EQ(images.visual[i], -1);
    EXPECT_EQ(images.link[i], -1);
    worst = std::max(worst, std::abs(images.depth[i] - 1.0));
  }
  std::printf("ground depth: %d pixels, worst error %.1f um\n", ground, worst * 1e6);
  EXPECT_GT(block, 20);
  EXPECT_GT(ground, 64 * 48 / 2);
  EXPECT_LT(worst, 1e-3);
  // Lit in the ground color (grey: r = g = b), the block red.
  const std::size_t corner = 0;
  EXPECT_EQ(images.visual[corner], -1);
  EXPECT_GT(images.rgba[4 * corner], 20);
  EXPECT_EQ(images.rgba[4 * corner], images.rgba[4 * corner + 1]);
  EXPECT_EQ(images.rgba[4 * corner + 1], images.rgba[4 * corner + 2]);

  // Grazing view toward the horizon: the plane reaches past `far` (no
  // edge), every point lies at the ground height, up to the far plane.
  CameraSpec wide = camera;
  wide.name = "wide";
  wide.width = 160;
  wide.height = 64;
  wide.far = 6;
  renderer.render(wide, calcLookAtPose({-1, 0.5, height + 0.6}, {1, 0, height + 0.3}), images);
  std::vector<int> pixels;
  const Eigen::Matrix3Xf world = calcCameraPoints(images, true, &pixels);
  double worst_height = 0;
  float deepest = 0;
  int ground_rows_hit = 0;
  for (Eigen::Index k = 0; k < world.cols(); ++k) {
    const std::size_t i = static_cast<std::size_t>(pixels[static_cast<std::size_t>(k)]);
    if (images.visual[i] >= 0) continue;
    worst_height = std::max(worst_height, std::abs(world(2, k) - height));
    deepest = std::max(deepest, images.depth[i]);
  }
  for (int row = 0; row < wide.height; ++row)
    ground_rows_hit += images.depth[static_cast<std::size_t>(row * wide.width)] > 0;
  std::printf("grazing ground: %ld points, worst height error %.1f um, deepest %.2f m\n",
              static_cast<long>(world.cols()), worst_height * 1e6, deepest);
  EXPECT_LT(worst_height, 1e-3);
  EXPECT_GT(deepest, 5.5f) << "the ground reaches the far plane";
  EXPECT_GT(ground_rows_hit, 5);
  EXPECT_LT(ground_rows_hit, wide.height) << "the sky above the horizon stays empty";

  // From below, the ground (a half-space's surface) is not seen.
  renderer.render(camera, calcLookAtPose({2, 0, height - 1}, {2, 0, height}), images);
  EXPECT_EQ(*std::max_element(images.depth.begin(), images.depth.end()), 0.0f);

  // Hidden by the lighting option, or a scene without ground: nothing there.
  LightingSpec no_ground;
  no_ground.draw_ground = false;
  renderer.setLighting(no_ground);
  renderer.render(camera, down, images);
  EXPECT_EQ(images.depth[corner], 0.0f);
  EXPECT_EQ(countHits(images), block);
  Scene bare;
  build(bare, false);
  SceneRenderer bare_renderer(bare);
  bare_renderer.render(camera, down, images);
  EXPECT_EQ(images.depth[corner], 0.0f);
  EXPECT_EQ(images.visual[corner], -1);
  EXPECT_EQ(countHits(images), block);
  for (std::size_t i = 0; i < images.depth.size(); ++i) {
    if (images.visual[i] < 0) {
      ASSERT_EQ(images.depth[i], 0.0f) << "pixel " << i;
    }
  }
}

TEST(Renderer, SegmentationNamesTheVisualAndFollowsTheLink) {
  Scene scene;
  scene.addUrdfString(boxUrdf("table", 1.0, 1.0, 0.04, "0.5 0.5 0.5 1"), "", "table",
                      at(0, 0, -0.02), true);
  const int slider = scene.addUrdfString(sliderUrdf(), "", "slider", at(0, 0, 0.05), true);
  scene.finalize();
  const std::vector<VisualShape>& shapes = scene.getVisualShapes();
  ASSERT_EQ(shapes.size(), 2u);
  const int carriage = scene.findLink(slider, "carriage");
  ASSERT_EQ(shapes[1].link, carriage);
  SceneRenderer renderer(scene);
  CameraSpec camera = makeCamera("top", 120, 120, 1.0);
  const Pose pose = calcLookAtPose({0.0, 0.0, 1.5}, {0, 0, 0}, Eigen::Vector3d::UnitX());
  CameraImages images;
  for (const double y : {0.0, 0.25}) {
    scene.setJointPositions(slider, Eigen::VectorXd::Constant(1, y));
    renderer.render(camera, pose, images);
    std::vector<int> pixels;
    const Eigen::Matrix3Xf world = calcCameraPoints(images, true, &pixels);
    int on_box = 0, background = 0;
    for (Eigen::Index k = 0; k < world.cols(); ++k) {
      const std::size_t i = static_cast<std::size_t>(pixels[static_cast<std::size_t>(k)]);
      const Eigen::Vector3f p = world.col(k);
      // Inside the carriage's box (1 mm slack) <=> labelled carriage.
      const bool footprint = std::abs(p.x()) < 0.051f && std::abs(p.y() - y) < 0.051f;
      if (footprint && std::abs(p.z()) < 0.002f) continue;  // where box meets table
      const bool inside = footprint && p.z() > 0 && p.z() < 0.101f;
      const bool labelled = images.visual[i] == 1;
      EXPECT_EQ(inside, labelled) << "pixel " << i << " at " << p.transpose() << ", y " << y;
      if (labelled) {
        ++on_box;
        EXPECT_EQ(images.link[i], carriage);
        EXPECT_GT(images.rgba[4 * i], 2 * images.rgba[4 * i + 1]);  // red
      } else {
        EXPECT_EQ(images.visual[i], 0);
        EXPECT_EQ(images.link[i], shapes[0].link);
      }
    }
    for (std::size_t i = 0; i < images.visual.size(); ++i) {
      if (images.visual[i] < 0) {
        ++background;
        EXPECT_EQ(images.link[i], -1);
        EXPECT_EQ(images.depth[i], 0.0f);
      }
    }
    EXPECT_GT(on_box, 40) << "y " << y;
    EXPECT_GT(background, 100) << "the table does not fill the view";
    if (y > 0) {
      // The carriage's points moved with it (its -y side shows a little).
      double mean_y = 0;
      for (Eigen::Index k = 0; k < world.cols(); ++k) {
        if (images.visual[static_cast<std::size_t>(pixels[static_cast<std::size_t>(k)])] == 1) {
          mean_y += world(1, k);
        }
      }
      EXPECT_NEAR(mean_y / on_box, 0.25, 0.02);
    }
  }
  // Hidden visuals vanish from every image.
  renderer.setVisualVisible(1, false);
  renderer.render(camera, pose, images);
  EXPECT_EQ(std::count(images.visual.begin(), images.visual.end(), 1), 0);
  EXPECT_THROW(renderer.setVisualVisible(2, false), RenderError);
}

TEST(Renderer, LightingIsAmbientPlusLambert) {
  Scene scene;
  scene.addUrdfString(boxUrdf("plate", 0.02, 10, 10, "1 1 1 1"), "", "plate", at(2, 0, 0), true);
  scene.finalize();
  LightingSpec ambient_only;
  ambient_only.directional.clear();
  SceneRenderer renderer(scene, ambient_only);
  CameraSpec camera = makeCamera("front", 16, 16);
  CameraImages images;
  renderer.render(camera, Pose(), images);
  EXPECT_NEAR(images.rgba[0], 0.3 * 255, 1.5);  // white x ambient 0.3
  EXPECT_EQ(images.rgba[3], 255);

  LightingSpec lit = ambient_only;
  lit.directional.push_back({Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(0.5f, 0.5f, 0.5f)});
  renderer.setLighting(lit);  // head on: 0.3 + 0.5 Lambert + 0.1 x 0.5 specular
  renderer.render(camera, Pose(), images);
  EXPECT_NEAR(images.rgba[4 * (8 * 16 + 8)], 0.85 * 255, 4);
  lit.directional.back().direction = Eigen::Vector3f(-1, 0, 0);  // from behind: no light
  renderer.setLighting(lit);
  renderer.render(camera, Pose(), images);
  EXPECT_NEAR(images.rgba[0], 0.3 * 255, 1.5);

  LightingSpec point = ambient_only;
  point.point.push_back({Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(0.4f, 0.4f, 0.4f)});
  renderer.setLighting(point);  // 0.99 m in front of the face: falls off with 1/r^2
  renderer.render(camera, Pose(), images);
  EXPECT_NEAR(images.rgba[4 * (8 * 16 + 8)], (0.3 + 1.1 * 0.4 / (0.99 * 0.99)) * 255, 5);

  LightingSpec too_many = ambient_only;
  too_many.point.resize(LightingSpec::kMaxLights + 1);
  EXPECT_THROW(renderer.setLighting(too_many), RenderError);
}

TEST(Renderer, AnyThreadMayRenderOneAtATime) {
  PlateScene plate;
  SceneRenderer first(plate.scene), second(plate.scene);
  CameraSpec camera = makeCamera("front", 32, 32);
  std::vector<int> hits(4, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      CameraImages images;
      SceneRenderer& renderer = t % 2 ? first : second;
      for (int i = 0; i < 20; ++i) {
        renderer.render(camera, Pose(), images);
        hits[static_cast<std::size_t>(t)] += countHits(images) == 32 * 32 ? 1 : 0;
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(hits, std::vector<int>(4, 20));
}

TEST(Renderer, TessellatesPrimitivesCoarselyAndCountsTriangles) {
  Scene scene;
  const std::string urdf =
      "<robot name='shapes'><link name='a'>" + inertial() +
      "<visual><geometry><box size='0.1 0.1 0.1'/></geometry></visual>"
      "<visual><geometry><sphere radius='0.05'/></geometry></visual>"
      "<visual><geometry><cylinder radius='0.05' length='0.2'/></geometry></visual>"
      "<visual><geometry><capsule radius='0.05' length='0.2'/></geometry></visual>"
      "<visual><origin xyz='0.3 0 0'/><geometry><box size='0.1 0.1 0.1'/></geometry></visual>"
      "</link></robot>";
  scene.addUrdfString(urdf, "", "shapes", Pose(), true);
  scene.finalize();
  SceneRenderer renderer(scene);
  // box 12, sphere 16 x 8 bands - 2 x 16 pole triangles, cylinder 16 x 4,
  // capsule 16 x 10 bands - 32; the second box shares the first's buffers.
  EXPECT_EQ(renderer.getTriangleCount(), 12u + 224u + 64u + 256u + 12u);
}

TEST(Renderer, RejectsBadCamerasByName) {
  PlateScene plate;
  SceneRenderer renderer(plate.scene);
  CameraImages images;
  CameraSpec camera;
  camera.name = "hand";
  camera.width = 0;
  try {
    renderer.render(camera, Pose(), images);
    ADD_FAILURE() << "a 0-pixel camera was accepted";
  } catch (const RenderError& e) {
    EXPECT_NE(std::string(e.what()).find("'hand'"), std::string::npos) << e.what();
  }
  camera.width = 8;
  camera.near = 2;
  camera.far = 1;
  EXPECT_THROW(renderer.render(camera, Pose(), images), RenderError);
  camera.far = 10;
  Pose bad;
  bad.position.x() = std::nan("");
  EXPECT_THROW(renderer.render(camera, bad, images), RenderError);
}

TEST(Renderer, RefusesASceneThatGainedVisualsAfterIt) {
  Scene scene;
  scene.addUrdfString(boxUrdf("plate", 0.02, 10, 10), "", "plate", at(2, 0, 0), true);
  SceneRenderer renderer(scene);
  scene.addUrdfString(boxUrdf("late", 0.1, 0.1, 0.1), "", "late", at(1, 0, 0), true);
  scene.finalize();
  CameraSpec camera;
  camera.name = "front";
  CameraImages images;
  try {
    renderer.render(camera, Pose(), images);
    ADD_FAILURE() << "rendered a scene with an undrawn visual";
  } catch (const RenderError& e) {
    EXPECT_NE(std::string(e.what()).find("after the scene is built"), std::string::npos);
  }
}

// Scenes come and go (every reset of every env): their GL objects must go
// with them (~3 ms per cycle here).
TEST(Renderer, SceneCyclesDoNotGrowMemory) {
  const auto cycle = [] {
    Scene scene;
    scene.addUrdfString(boxUrdf("plate", 0.02, 10, 10), "", "plate", at(2, 0, 0), true);
    scene.addUrdfString(sliderUrdf(), "", "slider", at(1, 0, 0), true);
    scene.finalize();
    SceneRenderer renderer(scene);
    CameraSpec camera = makeCamera("front", 128, 64);
    CameraImages images;
    renderer.render(camera, Pose(), images);
    return countHits(images);
  };
  if (testing::kAddressSanitized) GTEST_SKIP() << "AddressSanitizer's quarantine grows resident memory";
  for (int i = 0; i < 50; ++i) ASSERT_EQ(cycle(), 128 * 64);  // warm-up
  const long before = readRssKb();
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(cycle(), 128 * 64);
  const long after = readRssKb();
  std::printf("VmRSS %ld kB -> %ld kB over 1000 scene cycles\n", before, after);
  EXPECT_LT(after, before * 1.10);
}

// A camera the renderer refuses fails the episode like a diverged
// simulation (EpisodeFailure naming task, object, seed and step), not with a
// bare RenderError from inside reset().
TEST(RendererEnvironment, RenderFailureIsAnEpisodeFailureNamingTheEpisode) {
  PluginRegistry registry;
  registry.loadDirectories({MANIBENCH_TEST_BUILD_PLUGIN_DIR});
  registry.loadLibrary(std::string(MANIBENCH_TEST_FIXTURE_DIR) + "/libfixture_robot_testbed.so");
  ConfigSources sources;
  sources.overrides = {"observation.mode=rgbd"};
  EnvironmentOptions options =
      calcEnvironmentOptions(loadTaskConfig(registry, "RobotTestbed-v0", sources));
  ASSERT_FALSE(options.observation.cameras.empty());
  options.observation.cameras[0].spec.fovy = 3.5;  // > pi: refused at the first render
  Environment env(registry, "RobotTestbed-v0", options);
  try {
    env.reset("0", 7);
    ADD_FAILURE() << "the refused camera rendered";
  } catch (const EpisodeFailure& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("task 'RobotTestbed-v0', object '0', seed 7, step 0"), std::string::npos)
        << message;
    EXPECT_NE(message.find("'" + options.observation.cameras[0].spec.name + "'"), std::string::npos) << message;
    EXPECT_NE(message.find("fovy"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace manibench
