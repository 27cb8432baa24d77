// The viewer without its window: keys to actions, the free camera,
// real-time pacing, sessions on real environments (teleoperation recorded
// and replayed bit for bit, a policy, a replay that reaches the recorded
// final state), and the scene image (EGL, headless) with masks and points.
#include <gtest/gtest.h>

#include <manibench/demos.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "free_camera.hpp"
#include "session.hpp"
#include "step_clock.hpp"
#include "teleop.hpp"
#include "test_registry.hpp"
#include "view_composer.hpp"

namespace manibench::viewer {
namespace {

using manibench::testing::catchMessage;
using manibench::testing::contains;
using manibench::testing::expectMentions;
using manibench::testing::getBuildTreeRegistry;

ControllerDescription makeEeController(bool dual) {
  ControllerDescription c;
  c.name = "mobile_panda_ee";
  uint32_t offset = 0;
  const auto add = [&](const std::string& name, uint32_t size) {
    c.action_segments.push_back({name, size, "", offset});
    offset += size;
  };
  for (const char* base : {"base_forward", "base_left", "base_yaw", "lift"}) add(base, 1);
  for (const char* side_name : {"right", "left"}) {
    if (!dual && std::string(side_name) == "left") break;
    const std::string side = side_name;
    add(side + "_ee_linear", 3);
    add(side + "_ee_angular", 3);
    add(side + "_gripper", 1);
  }
  c.action_dim = offset;
  return c;
}

TEST(Teleop, HeldKeysMakeTheActionBySegmentName) {
  Teleop teleop(findTeleopLayout(makeEeController(false)));
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(11);
  expected[10] = 1;  // the gripper starts open
  EXPECT_EQ(teleop.calcAction(), expected);
  const double v = teleop.getSpeed();
  EXPECT_TRUE(teleop.handleKey('W', true, false));
  EXPECT_TRUE(teleop.handleKey('U', true, false));
  expected[0] = v;   // base_forward
  expected[6] = v;   // right_ee_linear z
  EXPECT_EQ(teleop.calcAction(), expected);
  // Shift turns the gripper keys into rotation: U/O roll about x.
  teleop.handleKey(340, true, true);
  expected[6] = 0;
  expected[7] = v;   // right_ee_angular x
  EXPECT_EQ(teleop.calcAction(), expected);
  teleop.handleKey(340, false, false);
  EXPECT_TRUE(teleop.handleKey('G', true, false));
  teleop.handleKey('W', false, false);
  teleop.handleKey('U', false, false);
  expected.setZero();
  expected[10] = -1;  // closed
  EXPECT_EQ(teleop.calcAction(), expected);
  // Faster, to full speed.
  for (int i = 0; i < 10; ++i) teleop.handleKey('=', true, false);
  teleop.handleKey('S', true, false);
  EXPECT_EQ(teleop.calcAction()[0], -1.0);
  teleop.releaseAll();
  EXPECT_EQ(teleop.calcAction()[0], 0.0);
  EXPECT_FALSE(teleop.handleKey('N', true, false));  // not a teleoperation key
}

TEST(Teleop, TwoArmsMoveOneAtATimeOrBoth) {
  Teleop teleop(findTeleopLayout(makeEeController(true)));
  ASSERT_EQ(teleop.getLayout().arms.size(), 2u);
  teleop.handleKey('J', true, false);  // left (+y)
  Eigen::VectorXd a = teleop.calcAction();
  EXPECT_EQ(a[5], teleop.getSpeed());  // right_ee_linear y
  EXPECT_EQ(a[12], 0.0);               // left_ee_linear y
  teleop.handleKey('2', true, false);
  a = teleop.calcAction();
  EXPECT_EQ(a[5], 0.0);
  EXPECT_EQ(a[12], teleop.getSpeed());
  teleop.handleKey('3', true, false);
  teleop.handleKey('G', true, false);
  a = teleop.calcAction();
  EXPECT_EQ(a[5], teleop.getSpeed());
  EXPECT_EQ(a[12], teleop.getSpeed());
  EXPECT_EQ(a[10], -1.0);
  EXPECT_EQ(a[17], -1.0);
  bool has_arm_keys = false;
  for (const KeyBinding& k : teleop.describeKeys()) has_arm_keys |= contains(k.keys, "1 / 2 / 3");
  EXPECT_TRUE(has_arm_keys);
}

TEST(Teleop, AControllerWithoutEndEffectorSegmentsIsRefusedNamingTheFix) {
  ControllerDescription joints;
  joints.name = "joint_velocity";
  joints.action_dim = 2;
  joints.action_segments = {{"shoulder", 1, "", 0}, {"elbow", 1, "", 1}};
  expectMentions(catchMessage<InvalidArgument>([&] { findTeleopLayout(joints); }),
                 {"joint_velocity", "base_forward", "--controller mobile_panda_ee", "--policy"});
}

TEST(FreeCamera, LooksAtItsTargetAndOrbitsPansZooms) {
  FreeCamera camera;
  camera.aim(Eigen::Vector3d(1, 2, 0.5), 3, 0.3, 0.4);
  const auto forward = [](const Pose& pose) { return pose.orientation * Eigen::Vector3d::UnitX(); };
  Pose pose = camera.calcPose();
  EXPECT_NEAR((pose.position - camera.getTarget()).norm(), 3, 1e-9);
  EXPECT_GT(forward(pose).dot((camera.getTarget() - pose.position).normalized()), 1 - 1e-9);
  camera.orbit(100, -50);
  pose = camera.calcPose();
  EXPECT_NEAR((pose.position - camera.getTarget()).norm(), 3, 1e-9);
  EXPECT_NEAR(camera.getPitch(), 0.4 - 50 * 0.006, 1e-9);
  const Eigen::Vector3d before = camera.getTarget();
  camera.pan(100, 0, 720);
  const Eigen::Vector3d moved = camera.getTarget() - before;
  EXPECT_GT(moved.norm(), 0.1);
  EXPECT_NEAR(moved.dot(forward(camera.calcPose())), 0, 1e-9);  // in the view plane
  camera.zoom(1);
  EXPECT_NEAR(camera.getDistance(), 2.7, 1e-9);
  camera.zoom(-1000);
  EXPECT_EQ(camera.getDistance(), FreeCamera::kMaxDistance);
  camera.orbit(0, 1e6);
  EXPECT_LT(camera.getPitch(), M_PI / 2);  // never straight down (look-at degenerates)
}

TEST(StepClock, PacesStepsToTheWallClockAndForgivesWhatItCannotCatchUp) {
  StepClock clock(0.05, 4);
  clock.restart(10.0);
  EXPECT_EQ(clock.takeDueSteps(10.01), 0u);
  EXPECT_EQ(clock.takeDueSteps(10.051), 1u);
  EXPECT_EQ(clock.takeDueSteps(10.16), 2u);  // steps 2 and 3 (t = 0.10, 0.15)
  clock.countSteps(3);
  // A frame that took a second: four steps, the rest forgiven. The window
  // closing here held the 3 steps taken: 0.15 s simulated in 1.2 s.
  EXPECT_EQ(clock.takeDueSteps(11.2), 4u);
  EXPECT_NEAR(clock.getRealTimeFactor(), 3 * 0.05 / 1.2, 1e-9);
  clock.countSteps(4);
  EXPECT_EQ(clock.takeDueSteps(11.22), 0u);
  EXPECT_EQ(clock.takeDueSteps(11.26), 1u);
}

std::string makeTempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("manibench_viewer_" + std::to_string(getpid()) + "_" + name))
      .string();
}

struct RobotProbe {
  Eigen::Vector3d base, tcp;
  double yaw = 0;
};
RobotProbe probeRobot(const Environment& env) {
  const Scene& scene = env.getScene();
  const int robot = scene.findArticulation(env.getTaskDescription().robot_articulation);
  const Pose base = scene.getLinkPose(scene.findLink(robot, "base_link"));
  RobotProbe p;
  p.base = base.position;
  const Eigen::Vector3d x = base.orientation * Eigen::Vector3d::UnitX();
  p.yaw = std::atan2(x.y(), x.x());
  p.tcp = scene.getLinkPose(scene.findLink(robot, "right_panda_tcp")).position;
  return p;
}

SessionOptions makeDrawerTeleop(const std::string& record) {
  SessionOptions options;
  options.mode = SessionMode::Teleop;
  options.task = "OpenCabinetDrawer-v0";
  options.sources.overrides = {"control.controller=mobile_panda_ee"};
  options.seed = 3;
  options.record_path = record;
  options.command = "viewer_session_test";
  return options;
}

// What the window's keys do, without the window: W drives the base
// forward, U raises the gripper, and the episodes recorded replay bit for
// bit with demos' own replay (the file is what `demos replay --check` reads).
TEST(Session, TeleoperationMovesTheRobotAndRecordsAReplayableFile) {
  const std::string path = makeTempPath("teleop.h5");
  PluginRegistry& registry = getBuildTreeRegistry();
  {
    Session session(registry, makeDrawerTeleop(path));
    Environment& env = session.updEnvironment();
    Teleop teleop(findTeleopLayout(env.getControllerDescription()));
    const RobotProbe start = probeRobot(env);
    teleop.handleKey('W', true, false);
    for (int i = 0; i < 10; ++i) session.step(teleop.calcAction());
    teleop.handleKey('W', false, false);
    teleop.handleKey('U', true, false);
    for (int i = 0; i < 10; ++i) session.step(teleop.calcAction());
    const RobotProbe end = probeRobot(env);
    const Eigen::Vector3d heading(std::cos(start.yaw), std::sin(start.yaw), 0);
    EXPECT_GT((end.base - start.base).dot(heading), 0.05);  // 10 steps at 0.25 m/s: ~0.1 m
    EXPECT_GT(end.tcp.z() - start.tcp.z(), 0.05);
    EXPECT_EQ(session.getRecordedCount(), 0u);  // nothing written before the episode ends
    // Next object: the episode so far is written, a second one starts.
    session.nextObject();
    EXPECT_EQ(session.getRecordedCount(), 1u);
    // A restart that discards: not recorded.
    for (int i = 0; i < 2; ++i) session.step(teleop.calcAction());
    session.restart(/*discard=*/true);
    EXPECT_EQ(session.getRecordedCount(), 1u);
    for (int i = 0; i < 3; ++i) session.step(teleop.calcAction());
    session.close();
    EXPECT_EQ(session.getRecordedCount(), 2u);
  }
  DemoReader reader(path);
  EXPECT_EQ(reader.getInfo().controller, "mobile_panda_ee");
  EXPECT_TRUE(contains(reader.getInfo().policy, "teleop ("));
  ASSERT_EQ(reader.getTrajectoryNames().size(), 2u);
  const std::unique_ptr<Environment> env = makeDemoEnvironment(registry, reader.getInfo());
  for (const std::string& name : reader.getTrajectoryNames()) {
    const Trajectory t = reader.read(name);
    const ReplayResult r = replayTrajectory(*env, t, /*check=*/true);
    EXPECT_TRUE(r.matches) << name << ": " << r.divergence;
  }
  EXPECT_EQ(reader.read("traj_0").steps, 20u);
  EXPECT_EQ(reader.read("traj_1").steps, 3u);
  std::filesystem::remove(path);
  std::filesystem::remove(getDemoJsonPath(path));
}

TEST(Session, ASessionThatRecordsNoStepLeavesNoFile) {
  const std::string path = makeTempPath("empty.h5");
  {
    Session session(getBuildTreeRegistry(), makeDrawerTeleop(path));
    session.restart();
    session.close();
    EXPECT_EQ(session.getRecordedCount(), 0u);
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

// Watching a policy: the expert's episode in the viewer's session ends as
// `manibench run` reports it, and its recording replays to the recorded
// final state in a replay session, bit for bit at every state.
TEST(Session, APolicyEpisodeRecordedThenReplayedReachesTheRecordedFinalState) {
  const std::string path = makeTempPath("expert.h5");
  PluginRegistry& registry = getBuildTreeRegistry();
  SessionOptions options = makeDrawerTeleop(path);
  options.mode = SessionMode::Policy;
  options.policy = "open_cabinet_expert";
  uint32_t steps = 0;
  std::vector<uint8_t> final_state;
  {
    Session session(registry, options);
    while (!session.isOver()) session.step();
    EXPECT_EQ(session.getStatus(), EpisodeStatus::Success) << session.getFailure();
    EXPECT_EQ(session.getRecordedCount(), 1u);  // written as it ended
    steps = session.getEnvironment().getElapsedSteps();
    final_state = session.updEnvironment().saveState();
  }
  SessionOptions replay;
  replay.mode = SessionMode::Replay;
  replay.replay_path = path;
  Session session(registry, replay);
  EXPECT_EQ(session.getReplayLength(), steps);
  while (!session.isOver()) session.step();
  EXPECT_TRUE(session.isReplayExact()) << session.getReplayDivergence();
  EXPECT_EQ(session.getStatus(), EpisodeStatus::Success);
  EXPECT_EQ(session.updEnvironment().saveState(), final_state);
  // The timeline: back to a middle state, and on to the end again.
  session.seek(steps / 2);
  EXPECT_EQ(session.getEnvironment().getElapsedSteps(), steps / 2);
  EXPECT_FALSE(session.isOver());
  while (!session.isOver()) session.step();
  EXPECT_TRUE(session.isReplayExact()) << session.getReplayDivergence();
  EXPECT_EQ(session.updEnvironment().saveState(), final_state);
  expectMentions(catchMessage<DemoError>([&] {
                   SessionOptions bad = replay;
                   bad.trajectory = "traj_9";
                   Session missing(registry, bad);
                 }),
                 {path, "traj_9", "traj_0"});
  std::filesystem::remove(path);
  std::filesystem::remove(getDemoJsonPath(path));
}

std::size_t countColor(const ViewImage& image, const std::array<std::uint8_t, 3>& color) {
  std::size_t n = 0;
  for (std::size_t p = 0; p < std::size_t(image.width) * std::size_t(image.height); ++p)
    n += (*image.rgba)[4 * p] == color[0] && (*image.rgba)[4 * p + 1] == color[1] &&
         (*image.rgba)[4 * p + 2] == color[2];
  return n;
}

// The scene image: the free camera sees the robot, the masks view paints
// each mask in its colour, the point cloud is the D.1 sample the policy
// would get, splatted from the same camera.
TEST(ViewComposer, MasksAndPointsOfTheFreeCameraShowTheRobot) {
  SessionOptions options = makeDrawerTeleop("");
  Session session(getBuildTreeRegistry(), options);
  Environment& env = session.updEnvironment();
  const std::vector<std::string>& masks = env.getTaskDescription().masks;
  const auto robot_mask = std::find(masks.begin(), masks.end(), "robot");
  ASSERT_NE(robot_mask, masks.end());
  const std::array<std::uint8_t, 3> robot_color =
      ViewComposer::getMaskColor(std::size_t(robot_mask - masks.begin()));
  FreeCamera camera;
  const Scene& scene = env.getScene();
  const int robot = scene.findArticulation(env.getTaskDescription().robot_articulation);
  const Pose base = scene.getLinkPose(scene.findLink(robot, "base_link"));
  const Eigen::Vector3d x = base.orientation * Eigen::Vector3d::UnitX();
  camera.aimAtRobot(base.position, std::atan2(x.y(), x.x()));
  ViewComposer composer;
  ViewSettings view;
  const ViewImage& plain = composer.compose(env, session.getEpisodeCount(), view, camera, 320, 180);
  EXPECT_EQ(plain.width, 320);
  EXPECT_EQ(plain.height, 180);
  EXPECT_EQ(countColor(plain, robot_color), 0u);
  view.masks = true;
  const std::size_t robot_pixels =
      countColor(composer.compose(env, session.getEpisodeCount(), view, camera, 320, 180), robot_color);
  EXPECT_GT(robot_pixels, 500u);
  view.points = true;
  const ViewImage& points = composer.compose(env, session.getEpisodeCount(), view, camera, 320, 180);
  EXPECT_EQ(composer.getPointCloud().size(), env.getOptions().observation.pointcloud.total);
  EXPECT_GT(countColor(points, robot_color), 50u);
  EXPECT_LT(countColor(points, robot_color), robot_pixels);
  // The colour alone, as the plain view reads it back, is readBack's.
  SceneRenderer& renderer = env.updObserver().updRenderer();
  const CameraSpec spec = camera.makeSpec(320, 180);
  RawCameraImages all, color;
  renderer.draw(spec, camera.calcPose());
  renderer.readBack(spec, all);
  renderer.readBackColor(spec, color);
  EXPECT_EQ(color.rgba, all.rgba);
  EXPECT_TRUE(color.segment.empty());
  EXPECT_TRUE(color.depth.empty());
  EXPECT_EQ(color.intrinsic, all.intrinsic);
  // A task camera, at its own size.
  view = ViewSettings();
  view.camera = 0;
  const ViewImage& task = composer.compose(env, session.getEpisodeCount(), view, camera, 320, 180);
  EXPECT_EQ(task.camera, env.getObserver().getCameras().getMount(0).spec.name);
  EXPECT_EQ(task.width, env.getObserver().getCameras().getMount(0).spec.width);
}

}  // namespace
}  // namespace manibench::viewer
