// Segmentation masks (ABI 1.1 add_to_mask) and the visual observation
// modes: pointcloud and rgbd of RobotTestbed-v0 (the mobile Panda with its
// three head cameras and one mask, "robot"), rendered for real with EGL.
#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>
#include <manibench/plugin_instances.hpp>
#include <manibench/renderer.hpp>
#include <manibench/scene.hpp>
#include <manibench/visual_observer.hpp>
#include <manibench/sdk/policy.hpp>

#include "test_registry.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

namespace manibench {
namespace {

const std::string kRobotUrdf =
    std::string(MANIBENCH_TEST_SOURCE_DIR) + "/assets/robots/mobile_panda_single.urdf";

const PluginRegistry& getRegistry() { return testing::getRobotTestbedRegistry(); }

// The testbed's options as the configuration layers give them (its
// default_config declares the head cameras), with `overrides`.
// Whether `p` (world) lies within 1 cm of the bounding box of a visual of
// `articulation` (shape frame: primitives' extents, meshes' vertices).
bool isOnVisualOf(const Scene& scene, int articulation, const Eigen::Vector3d& p) {
  for (const VisualShape& v : scene.getVisualShapes()) {
    if (v.link < 0 || scene.findLink(articulation, scene.getLinkName(v.link)) != v.link) continue;
    const Pose link = scene.getLinkPose(v.link);
    const Eigen::Quaterniond q = link.orientation * v.pose_in_link.orientation;
    const Eigen::Vector3d origin = link.position + link.orientation * v.pose_in_link.position;
    const Eigen::Vector3d local = q.conjugate() * (p - origin);
    Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = lo;  // every kind sets both
    switch (v.kind) {
      case VisualShape::Kind::Box: hi = v.size / 2; lo = -hi; break;
      case VisualShape::Kind::Sphere: hi = Eigen::Vector3d::Constant(v.size.x()); lo = -hi; break;
      case VisualShape::Kind::Cylinder:
        hi = Eigen::Vector3d(v.size.x(), v.size.x(), v.size.y() / 2); lo = -hi; break;
      case VisualShape::Kind::Capsule:
        hi = Eigen::Vector3d(v.size.x(), v.size.x(), v.size.y() / 2 + v.size.x()); lo = -hi; break;
      case VisualShape::Kind::Mesh:
        lo = Eigen::Vector3d::Constant(1e9);
        hi = -lo;
        for (const VisualMesh& mesh : *v.meshes)
          for (const Eigen::Vector3f& x : mesh.positions) {
            lo = lo.cwiseMin(x.cast<double>());
            hi = hi.cwiseMax(x.cast<double>());
          }
        break;
    }
    const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.01);
    if ((local.array() >= (lo - margin).array()).all() && (local.array() <= (hi + margin).array()).all())
      return true;
  }
  return false;
}

EnvironmentOptions makeOptions(const std::vector<std::string>& overrides) {
  ConfigSources sources;
  sources.overrides = overrides;
  return calcEnvironmentOptions(loadTaskConfig(getRegistry(), "RobotTestbed-v0", sources));
}

// ---- add_to_mask ---------------------------------------------------------------

struct MaskFixture {
  Scene scene;
  SegmentationMasks masks{{"hand", "robot"}};
  SceneBridge bridge{scene, &masks};
  int robot = -1;
  char message[512] = {0};
  mb_error err{message, sizeof(message)};

  MaskFixture() {
    bridge.setBuilding(true);
    robot = scene.addUrdfFile(kRobotUrdf, "robot", Pose(), true);
  }
  mb_status add(uint32_t mask, int articulation, int link, const char* part) {
    message[0] = '\0';
    return SceneBridge::getApi()->add_to_mask(bridge.getHandle(), mask, articulation, link, part,
                                              &err);
  }
};

TEST(AddToMask, LinkVisualsByNamePartAndWholeArticulations) {
  MaskFixture f;
  const int hand = f.scene.findLink(f.robot, "right_panda_hand");
  ASSERT_GE(hand, 0);
  ASSERT_EQ(f.add(0, f.robot, hand, "dark"), MB_OK) << f.message;
  ASSERT_EQ(f.add(1, f.robot, -1, nullptr), MB_OK) << f.message;
  const std::vector<VisualShape>& visuals = f.scene.getVisualShapes();
  const std::vector<std::uint64_t> masks = f.masks.getVisualMasks();
  ASSERT_EQ(masks.size(), visuals.size());
  int in_hand = 0;
  for (std::size_t v = 0; v < visuals.size(); ++v) {
    const bool hand_dark =
        visuals[v].link == hand && visuals[v].name.find("dark") != std::string::npos;
    EXPECT_EQ((masks[v] & 1) != 0, hand_dark) << visuals[v].name;
    EXPECT_TRUE(masks[v] & 2) << "every robot visual is in mask 'robot': " << visuals[v].name;
    in_hand += hand_dark;
  }
  EXPECT_EQ(in_hand, 1);
  // An empty part takes every visual of the link.
  ASSERT_EQ(f.add(0, f.robot, hand, ""), MB_OK) << f.message;
  int hand_visuals = 0, hand_masked = 0;
  const std::vector<std::uint64_t> after = f.masks.getVisualMasks();
  for (std::size_t v = 0; v < visuals.size(); ++v)
    if (visuals[v].link == hand) {
      ++hand_visuals;
      hand_masked += (after[v] & 1) != 0;
    }
  EXPECT_GE(hand_visuals, 2);
  EXPECT_EQ(hand_masked, hand_visuals);
}

TEST(AddToMask, ErrorsNameTheMaskLinkAndPart) {
  MaskFixture f;
  const int hand = f.scene.findLink(f.robot, "right_panda_hand");
  EXPECT_EQ(f.add(2, f.robot, hand, nullptr), MB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(f.message).find("mask index 2"), std::string::npos) << f.message;
  EXPECT_NE(std::string(f.message).find("2 masks ('hand', 'robot')"), std::string::npos) << f.message;
  EXPECT_EQ(f.add(0, f.robot, hand, "wheel"), MB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(f.message).find("right_panda_hand"), std::string::npos) << f.message;
  EXPECT_NE(std::string(f.message).find("'wheel'"), std::string::npos) << f.message;
  EXPECT_EQ(f.add(0, 7, -1, nullptr), MB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(f.message).find("articulation"), std::string::npos) << f.message;
  f.bridge.setBuilding(false);
  EXPECT_EQ(f.add(0, f.robot, hand, nullptr), MB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(f.message).find("only allowed while a task builds"), std::string::npos)
      << f.message;
  for (std::uint64_t bits : f.masks.getVisualMasks()) EXPECT_EQ(bits, 0u) << "failed calls assign nothing";
}

// ---- state mode stays away from EGL -----------------------------------------------

TEST(ObservationModes, StateModeNeverInitializesEgl) {
  // In a child process: RenderContext::exists() speaks for this process
  // only, whatever the parent (other tests) created.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    int code = 3;
    try {
      Environment env(getRegistry(), "RobotTestbed-v0", makeOptions({}));
      env.reset("0", 1);
      for (int i = 0; i < 3; ++i)
        env.step(Eigen::VectorXd::Constant(env.getControllerDescription().action_dim, 0.3));
      code = RenderContext::exists() ? 1 : (env.getVisualObservation().points.size() == 0 ? 0 : 2);
    } catch (...) {
      code = 4;
    }
    _exit(code);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: EGL was initialized, 2: visual data, 4: exception";
}

// ---- pointcloud ------------------------------------------------------------------------

TEST(ObservationModes, PointCloudIsSubsampledAndItsRobotMaskLiesOnTheRobot) {
  Environment env(getRegistry(), "RobotTestbed-v0", makeOptions({"observation.mode=pointcloud"}));
  env.reset("0", 3);
  const VisualObservation& visual = env.getVisualObservation();
  EXPECT_EQ(visual.mode, ObservationMode::PointCloud);
  ASSERT_EQ(visual.mask_count, 1u);
  const PointCloud& cloud = visual.points;
  ASSERT_EQ(cloud.size(), 1200u) << "D.1 size (padded)";
  ASSERT_EQ(cloud.masks.size(), cloud.size());

  const Scene& scene = env.getScene();
  const int robot = scene.findArticulation("robot");
  ASSERT_FALSE(isOnVisualOf(scene, robot, Eigen::Vector3d(1.5, 1.5, 0.5))) << "the check can fail";
  int masked = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p(cloud.xyz[3 * i], cloud.xyz[3 * i + 1], cloud.xyz[3 * i + 2]);
    if (!cloud.masks[i]) continue;
    ++masked;
    EXPECT_TRUE(isOnVisualOf(scene, robot, p)) << "robot-mask point " << p.transpose()
                                                << " lies on no visual of the robot";
    EXPECT_GT(p.z(), 0.0);
    EXPECT_LT(p.z(), 2.0);
    const float r = cloud.rgb[3 * i], g = cloud.rgb[3 * i + 1], b = cloud.rgb[3 * i + 2];
    EXPECT_TRUE(r >= 0 && r <= 1 && g >= 0 && g <= 1 && b >= 0 && b <= 1);
  }
  // The robot is the only thing the cameras see (the ground is not drawn
  // or is dropped): every point that is not padding is a robot point.
  int padding = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    padding += !cloud.masks[i] && cloud.xyz[3 * i] == 0 && cloud.xyz[3 * i + 1] == 0 &&
               cloud.xyz[3 * i + 2] == 0;
  EXPECT_GT(masked, 50);
  EXPECT_LE(masked, 800);
  EXPECT_EQ(masked + padding, 1200);
}

TEST(ObservationModes, SameSeedSameBytesAcrossEnvironments) {
  const EnvironmentOptions options = makeOptions({"observation.mode=pointcloud"});
  auto run = [&](uint64_t seed) {
    Environment env(getRegistry(), "RobotTestbed-v0", options);
    env.reset("0", seed);
    Eigen::VectorXd action = Eigen::VectorXd::Zero(env.getControllerDescription().action_dim);
    action[4] = 0.5;  // first arm joint turns
    action[0] = 0.3;  // base moves forward
    for (int i = 0; i < 3; ++i) env.step(action);
    return env.getVisualObservation().points;
  };
  const PointCloud a = run(5), b = run(5), c = run(6);
  EXPECT_EQ(a.xyz, b.xyz);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(a.masks, b.masks);
  EXPECT_NE(a.xyz, c.xyz) << "another seed samples other points";
}

TEST(ObservationModes, PointCloudFromPixelsIsTheD1SampleOfTheFullCloud) {
  // The observation classifies pixels and unprojects only what it keeps;
  // the full cloud (every hit pixel unprojected) sampled by the same rule
  // must agree: the same masked points bit for bit (same candidates, same
  // generator), and background points that are points of the full cloud,
  // in no mask, above the ground, none twice. With ground_height -1 the
  // ground plane is background too.
  for (const std::string ground : {"0.001", "-1"}) {
    SCOPED_TRACE("ground_height " + ground);
    Environment env(getRegistry(), "RobotTestbed-v0",
                    makeOptions({"observation.mode=pointcloud",
                                 "observation.pointcloud.ground_height=" + ground}));
    env.reset("0", 4);
    VisualObserver& observer = env.updObserver();
    VisualObservation observation;
    observer.observe(77, observation);
    const PointCloud& cloud = observation.points;
    PointCloud full;
    observer.fusePointCloud(observer.renderCameras(), 3, full);
    const PointCloudSampling& sampling = env.getOptions().observation.pointcloud;
    const std::vector<uint32_t> reference = selectPointCloudSample(full, sampling, 77);
    ASSERT_EQ(cloud.size(), 1200u);

    std::size_t masked = 0;
    while (masked < cloud.size() && cloud.masks[masked]) ++masked;
    std::size_t reference_masked = 0;
    while (reference_masked < reference.size() && full.masks[reference[reference_masked]])
      ++reference_masked;
    ASSERT_EQ(masked, reference_masked);
    EXPECT_GT(masked, 50u);
    for (std::size_t i = 0; i < masked; ++i)
      for (std::size_t c = 0; c < 3; ++c) {
        ASSERT_EQ(cloud.xyz[3 * i + c], full.xyz[3 * reference[i] + c]) << "point " << i;
        ASSERT_EQ(cloud.rgb[3 * i + c], full.rgb[3 * reference[i] + c]) << "point " << i;
      }

    std::set<std::array<float, 3>> background;
    for (std::size_t i = 0; i < full.size(); ++i)
      if (!full.masks[i] && full.xyz[3 * i + 2] > sampling.ground_height)
        background.insert({full.xyz[3 * i], full.xyz[3 * i + 1], full.xyz[3 * i + 2]});
    const std::size_t expected = std::min<std::size_t>(1200 - masked, background.size());
    if (ground == "-1") {
      EXPECT_EQ(expected, 1200 - masked) << "the ground fills the cloud";
    }
    std::set<std::array<float, 3>> seen;
    for (std::size_t i = masked; i < masked + expected; ++i) {
      const std::array<float, 3> p{cloud.xyz[3 * i], cloud.xyz[3 * i + 1], cloud.xyz[3 * i + 2]};
      EXPECT_FALSE(cloud.masks[i]);
      EXPECT_EQ(background.count(p), 1u) << "point " << i << " is no background point";
      EXPECT_TRUE(seen.insert(p).second) << "point " << i << " twice";
    }
    for (std::size_t i = masked + expected; i < cloud.size(); ++i)
      EXPECT_TRUE(cloud.xyz[3 * i] == 0 && cloud.xyz[3 * i + 1] == 0 && cloud.xyz[3 * i + 2] == 0 &&
                  !cloud.masks[i])
          << "padding at " << i;

    // The environment's own observation keeps its buffers from step to step.
    const float* xyz = env.getVisualObservation().points.xyz.data();
    env.step(Eigen::VectorXd::Zero(env.getControllerDescription().action_dim));
    EXPECT_EQ(env.getVisualObservation().points.xyz.data(), xyz);
  }
}

// ---- rgbd ---------------------------------------------------------------------------------

TEST(ObservationModes, RgbdStacksCamerasAlongChannels) {
  Environment env(getRegistry(), "RobotTestbed-v0", makeOptions({"observation.mode=rgbd"}));
  env.reset("0", 0);
  const VisualObservation& v = env.getVisualObservation();
  ASSERT_EQ(v.camera_count, 3u);
  ASSERT_EQ(v.height, 160u);
  ASSERT_EQ(v.width, 400u);
  const std::size_t pixels = 160 * 400;
  ASSERT_EQ(v.rgb.size(), pixels * 3 * 3);
  ASSERT_EQ(v.depth.size(), pixels * 3);
  ASSERT_EQ(v.masks.size(), pixels * 1 * 3);
  EXPECT_TRUE(v.points.size() == 0);

  // Channel c of depth is camera c; a robot pixel has depth, and the
  // masks agree with the renderer's per-pixel visuals.
  const std::vector<CameraImages> images = env.updObserver().renderCameras();
  ASSERT_EQ(images.size(), 3u);
  std::size_t robot_pixels = 0;
  for (std::size_t c = 0; c < 3; ++c)
    for (std::size_t p = 0; p < pixels; ++p) {
      ASSERT_EQ(v.depth[p * 3 + c], images[c].depth[p]) << "camera " << c << " pixel " << p;
      for (std::size_t channel = 0; channel < 3; ++channel)
        ASSERT_EQ(v.rgb[p * 9 + 3 * c + channel], images[c].rgba[4 * p + channel] / 255.0f);
      const bool robot = v.masks[p * 3 + c] != 0;
      ASSERT_EQ(robot, images[c].visual[p] >= 0) << "only the robot is drawn";
      if (robot) {
        EXPECT_GT(v.depth[p * 3 + c], 0.1f);
      }
      robot_pixels += robot;
    }
  EXPECT_GT(robot_pixels, 500u);

  // The head cameras ride on base_link, 1.5 m up.
  const Scene& scene = env.getScene();
  const Pose base = scene.getLinkPose(scene.findLink(scene.findArticulation("robot"), "base_link"));
  EXPECT_NEAR(env.getObserver().getCameras().calcCameraPose(0).position.z() - base.position.z(), 1.5,
              1e-9);
}

// observation.rgb_dtype uint8: the renderer's bytes where the float32 layout
// has byte / 255.0f, everything else the same; policies still see floats.
TEST(ObservationModes, RgbdRgbAsBytesIsTheFloatLayoutTimes255) {
  Environment floats(getRegistry(), "RobotTestbed-v0", makeOptions({"observation.mode=rgbd"}));
  Environment bytes(getRegistry(), "RobotTestbed-v0",
                    makeOptions({"observation.mode=rgbd", "observation.rgb_dtype=uint8"}));
  ASSERT_EQ(bytes.getOptions().observation.rgb_dtype, RgbDtype::Uint8);
  floats.reset("0", 2);
  bytes.reset("0", 2);
  const VisualObservation& f = floats.getVisualObservation();
  const VisualObservation& b = bytes.getVisualObservation();
  EXPECT_TRUE(f.rgb_bytes.empty() && b.rgb.empty());
  ASSERT_EQ(b.rgb_bytes.size(), f.rgb.size());
  std::size_t lit = 0;
  for (std::size_t i = 0; i < f.rgb.size(); ++i) {
    ASSERT_EQ(float(b.rgb_bytes[i]) / 255.0f, f.rgb[i]) << "value " << i;
    lit += b.rgb_bytes[i] > 0;
  }
  EXPECT_GT(lit, f.rgb.size() / 2);
  EXPECT_EQ(b.depth, f.depth);
  EXPECT_EQ(b.masks, f.masks);
  // A policy gets the float layout's values (mb_observation.image_rgb is float).
  std::vector<float> converted;
  const mb_observation view =
      makeObservationView(bytes.getObservation(), 0, b, converted);
  ASSERT_EQ(view.image_rgb, converted.data());
  EXPECT_EQ(converted, f.rgb);
  EXPECT_EQ(makeObservationView(floats.getObservation(), 0, f, converted).image_rgb, f.rgb.data());
  // And a whole episode of a plugin policy runs with it.
  EnvironmentOptions options =
      makeOptions({"observation.mode=rgbd", "observation.rgb_dtype=uint8", "episode.max_steps=2"});
  Environment env(getRegistry(), "RobotTestbed-v0", options);
  PolicyInstance random(getRegistry(), "random", "", env.calcPolicyLayout());
  EXPECT_EQ(runEpisode(env, random, "0", 4).steps, 2u);
}

// Several masks (the cabinet's handle, target link and robot): each pixel's
// mask bytes are its visual's bits, in the masks' order.
TEST(ObservationModes, RgbdMaskBytesAreTheVisualsMaskBits) {
  Environment env(getRegistry(), "OpenCabinetDrawer-v0", makeOptions({"observation.mode=rgbd"}));
  env.reset(env.listObjects("train").front(), 3);
  const VisualObservation& v = env.getVisualObservation();
  const std::uint32_t k = env.getObserver().getMasks().getCount();
  ASSERT_EQ(k, 3u);
  const std::vector<CameraImages> images = env.updObserver().renderCameras();
  const std::size_t cameras = v.camera_count, pixels = std::size_t(v.height) * v.width;
  std::array<std::size_t, 3> in_mask{};
  for (std::size_t c = 0; c < cameras; ++c)
    for (std::size_t p = 0; p < pixels; ++p) {
      const std::uint64_t bits = env.getObserver().getMasks().calcPixelMasks(images[c], p);
      for (std::uint32_t m = 0; m < k; ++m) {
        ASSERT_EQ(v.masks[(p * cameras + c) * k + m], (bits >> m) & 1u)
            << "camera " << c << " pixel " << p << " mask " << m;
        in_mask[m] += (bits >> m) & 1u;
      }
    }
  for (std::uint32_t m = 0; m < k; ++m) EXPECT_GT(in_mask[m], 0u) << "mask " << m << " seen nowhere";
}

// A policy that reports what it saw through the SDK's views, as its action.
class ProbePolicy : public sdk::Policy {
 public:
  explicit ProbePolicy(const sdk::PolicyContext& context) : mode_(context.observation_mode) {}
  Eigen::VectorXd act(const sdk::Observation& o) override {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(9);
    a << double(o.points_xyz.rows()), o.points_mask.cast<double>().sum(),
        o.points_xyz.rows() ? double(o.points_xyz(o.points_xyz.rows() / 2, 2)) : -1.0,
        double(o.camera_count), double(o.image_height), double(o.image_width),
        o.camera_count ? double(o.depthAt(1, 80, 200)) : -1.0,
        o.image_masks.cast<double>().sum(), double(o.mask_count);
    if (mode_ == "pointcloud" && o.points_xyz.rows() == 0)
      throw sdk::Error("pointcloud mode but no points", MB_ERROR);
    return a;
  }

 private:
  std::string mode_;
};

// The host's C view of an observation, through the SDK's real trampolines.
Eigen::VectorXd probe(const Environment& env) {
  const PolicyLayout layout = env.calcPolicyLayout();
  mb_policy_context context{};
  context.struct_size = sizeof(context);
  context.task_name = layout.task_name.c_str();
  context.observation_mode = toString(layout.observation_mode);
  context.action_dim = 9;
  using Trampolines = sdk::detail::PolicyTrampolines<ProbePolicy>;
  char message[256] = {0};
  mb_error err{message, sizeof(message)};
  mb_policy* policy = nullptr;
  EXPECT_EQ(Trampolines::create("", &context, &policy, &err), MB_OK) << message;
  const mb_observation view =
      makeObservationView(env.getObservation(), env.getElapsedSteps(), env.getVisualObservation());
  Eigen::VectorXd action = Eigen::VectorXd::Zero(9);
  EXPECT_EQ(Trampolines::act(policy, &view, action.data(), 9, &err), MB_OK) << message;
  Trampolines::destroy(policy);
  return action;
}

TEST(ObservationModes, PoliciesSeeTheVisualFieldsThroughTheSdk) {
  Environment rgbd(getRegistry(), "RobotTestbed-v0", makeOptions({"observation.mode=rgbd"}));
  rgbd.reset("0", 0);
  const VisualObservation& v = rgbd.getVisualObservation();
  Eigen::VectorXd seen = probe(rgbd);
  EXPECT_EQ(seen[0], 0) << "no points in rgbd";
  EXPECT_EQ(seen[3], 3);
  EXPECT_EQ(seen[4], 160);
  EXPECT_EQ(seen[5], 400);
  EXPECT_EQ(seen[6], v.depth[(80 * 400 + 200) * 3 + 1]);
  double mask_sum = 0;
  for (std::uint8_t m : v.masks) mask_sum += m;
  EXPECT_EQ(seen[7], mask_sum);
  EXPECT_GT(mask_sum, 0);
  EXPECT_EQ(seen[8], 1);

  Environment cloud(getRegistry(), "RobotTestbed-v0", makeOptions({"observation.mode=pointcloud"}));
  cloud.reset("0", 0);
  const PointCloud& points = cloud.getVisualObservation().points;
  seen = probe(cloud);
  EXPECT_EQ(seen[0], 1200);
  double point_mask_sum = 0;
  for (std::uint8_t m : points.masks) point_mask_sum += m;
  EXPECT_EQ(seen[1], point_mask_sum);
  EXPECT_EQ(seen[2], points.xyz[3 * 600 + 2]);
  EXPECT_EQ(seen[3], 0) << "no images in pointcloud";

  // A host older than ABI 1.1 passes a shorter struct: empty views.
  mb_observation old = makeObservationView(cloud.getObservation(), 0, cloud.getVisualObservation());
  old.struct_size = offsetof(mb_observation, mask_count);
  const sdk::Observation o(old);
  EXPECT_EQ(o.points_xyz.rows(), 0);
  EXPECT_EQ(o.state.size(), cloud.getObservation().size());

  // A whole episode of a plugin policy runs in this mode.
  EnvironmentOptions options = makeOptions({"observation.mode=pointcloud", "episode.max_steps=3"});
  Environment env(getRegistry(), "RobotTestbed-v0", options);
  PolicyInstance random(getRegistry(), "random", "", env.calcPolicyLayout());
  EXPECT_EQ(runEpisode(env, random, "0", 4).steps, 3u);
}

// ---- configuration --------------------------------------------------------------------------

TEST(ObservationModes, ConfigurationMapsCamerasLightsAndSampling) {
  const EnvironmentOptions options = makeOptions(
      {"lights.ambient=[0.1, 0.2, 0.3]", "lights.point=[{position: [1, 2, 3], color: [4, 5, 6]}]",
       "observation.pointcloud.total=500", "observation.pointcloud.masked_total=300"});
  EXPECT_EQ(options.observation.mode, ObservationMode::State);
  EXPECT_TRUE(options.observation.lighting.ambient.isApprox(Eigen::Vector3f(0.1f, 0.2f, 0.3f)));
  ASSERT_EQ(options.observation.lighting.directional.size(), 1u) << "the built-in sun";
  EXPECT_TRUE(options.observation.lighting.directional[0].shadow);
  ASSERT_EQ(options.observation.lighting.point.size(), 1u);
  EXPECT_TRUE(options.observation.lighting.point[0].color.isApprox(Eigen::Vector3f(4, 5, 6)));
  EXPECT_EQ(options.observation.pointcloud.total, 500u);
  EXPECT_EQ(options.observation.pointcloud.masked_total, 300u);
  EXPECT_EQ(options.observation.pointcloud.per_mask, 50u);
  // The testbed's head cameras: rpy (0, pi/4, 2 pi/3) is Rz(yaw) Ry(pitch),
  // so the optical axis (+x) points 45 degrees down, 120 degrees left.
  ASSERT_EQ(options.observation.cameras.size(), 3u);
  const CameraMount& left = options.observation.cameras[1];
  EXPECT_EQ(left.spec.name, "head_left");
  EXPECT_EQ(left.articulation, "robot");
  EXPECT_EQ(left.link, "base_link");
  EXPECT_EQ(left.spec.width, 400);
  EXPECT_EQ(left.spec.height, 160);
  EXPECT_NEAR(left.spec.fovy, 1.0471975511965976, 1e-15);
  const double c = std::sqrt(0.5);
  const Eigen::Vector3d axis = left.pose.orientation * Eigen::Vector3d::UnitX();
  EXPECT_TRUE(axis.isApprox(Eigen::Vector3d(-0.5 * c, std::sqrt(0.75) * c, -c), 1e-12)) << axis.transpose();
  EXPECT_TRUE(left.pose.position.isApprox(Eigen::Vector3d(0, 0, 1.5)));
  try {
    makeOptions({"observation.pointcloud.masked_total=1300"});
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("exceeds observation.pointcloud.total (1200)"), std::string::npos)
        << e.what();
  }
}

// ---- configuration errors ------------------------------------------------------------------

TEST(ObservationModes, CameraErrorsNameTheCamera) {
  EnvironmentOptions none = makeOptions({"observation.mode=rgbd", "cameras=[]"});
  try {
    Environment env(getRegistry(), "RobotTestbed-v0", none);
    FAIL() << "no error";
  } catch (const manibench::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("needs at least one camera"), std::string::npos) << e.what();
  }
  EnvironmentOptions sizes = makeOptions(
      {"observation.mode=rgbd", "cameras=[{name: a, width: 64, height: 48}, {name: b, width: 32, height: 48}]"});
  try {
    Environment env(getRegistry(), "RobotTestbed-v0", sizes);
    FAIL() << "no error";
  } catch (const manibench::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("camera 'a' is 64x48, camera 'b' is 32x48"), std::string::npos)
        << e.what();
  }
  EnvironmentOptions link = makeOptions({"cameras=[{name: c, articulation: robot, link: wheel}]"});
  try {
    Environment env(getRegistry(), "RobotTestbed-v0", link);
    FAIL() << "no error";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("camera 'c'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no link 'wheel'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--set"), std::string::npos) << "names the source: " << e.what();
  }
}

}  // namespace
}  // namespace manibench
