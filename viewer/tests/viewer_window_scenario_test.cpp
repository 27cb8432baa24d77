// The viewer for real: `manibench view` in a virtual X display (Xvfb), keys
// and mouse from xdotool (XTEST, the server's real input path). What is
// asserted comes from the files the viewer writes (its screenshots, its
// recordings, replayed by `demos replay --check`) and the environment
// states recorded in them, not from what the test sent.
#include <gtest/gtest.h>
#include <png.h>
#include <sys/wait.h>
#include <unistd.h>

#include <manibench/demos.hpp>
#include <manibench/plugin_instances.hpp>

#include <algorithm>
#include <iostream>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "test_registry.hpp"
#include "view_composer.hpp"
#include "virtual_display.hpp"

namespace manibench::viewer {
namespace {

using manibench::testing::contains;
using manibench::testing::getBuildTreeRegistry;
using manibench::testing::runCli;
using testing::runXdotool;
using testing::ViewerProcess;
using testing::VirtualDisplay;

constexpr double kStartSeconds = 120;  // plugins, the scene, the first frame, on a busy machine
const char* kReady = "Esc quits";

class TempDir {
 public:
  TempDir() {
    char path[] = "/tmp/manibench_viewer_test_XXXXXX";
    if (mkdtemp(path) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = path;
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string operator/(const std::string& name) const { return (std::filesystem::path(path_) / name).string(); }
  const std::string& get() const { return path_; }

 private:
  std::string path_;
};

struct Rgb {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  // 3 per pixel, rows top first
};

Rgb readPng(const std::string& path) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) throw std::runtime_error("cannot read " + path);
  image.format = PNG_FORMAT_RGB;
  Rgb rgb;
  rgb.width = int(image.width);
  rgb.height = int(image.height);
  rgb.pixels.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, rgb.pixels.data(), 0, nullptr))
    throw std::runtime_error("cannot decode " + path);
  return rgb;
}

std::size_t countColor(const Rgb& image, const std::array<std::uint8_t, 3>& color) {
  std::size_t n = 0;
  for (std::size_t p = 0; p + 2 < image.pixels.size(); p += 3)
    n += image.pixels[p] == color[0] && image.pixels[p + 1] == color[1] && image.pixels[p + 2] == color[2];
  return n;
}

std::size_t countDifferent(const Rgb& a, const Rgb& b) {
  std::size_t n = 0;
  for (std::size_t p = 0; p + 2 < std::min(a.pixels.size(), b.pixels.size()); p += 3)
    n += a.pixels[p] != b.pixels[p] || a.pixels[p + 1] != b.pixels[p + 1] || a.pixels[p + 2] != b.pixels[p + 2];
  return n;
}

// The last "wrote PATH" line of the viewer's output.
std::string findWritten(const std::string& out) {
  const std::size_t at = out.rfind("wrote ");
  if (at == std::string::npos) return "";
  return out.substr(at + 6, out.find('\n', at) - at - 6);
}

// F12, and the screenshot the viewer says it wrote.
Rgb takeScreenshot(const VirtualDisplay& display, ViewerProcess& viewer, int count) {
  runXdotool(display, {"key", "F12"});
  const std::string marker = "manibench-view-00" + std::to_string(count) + ".png";
  EXPECT_TRUE(viewer.waitForOutput(marker, 60)) << viewer.getOut() << viewer.getErr();
  return readPng(findWritten(viewer.getOut()));
}

std::size_t findMask(const std::string& task, const std::string& mask) {
  const TaskInstance probe(getBuildTreeRegistry(), task, "");
  const std::vector<std::string>& masks = probe.getDescription().masks;
  const auto it = std::find(masks.begin(), masks.end(), mask);
  if (it == masks.end()) throw std::runtime_error(task + " has no mask " + mask);
  return std::size_t(it - masks.begin());
}

// Where the robot's base and right TCP are in a recorded state.
struct RobotAt {
  Eigen::Vector3d base, tcp, heading;
};
RobotAt readRobot(Environment& env, const std::vector<std::uint8_t>& state) {
  env.restoreState(state);
  const Scene& scene = env.getScene();
  const int robot = scene.findArticulation(env.getTaskDescription().robot_articulation);
  const Pose base = scene.getLinkPose(scene.findLink(robot, "base_link"));
  return {base.position, scene.getLinkPose(scene.findLink(robot, "right_panda_tcp")).position,
          base.orientation * Eigen::Vector3d::UnitX()};
}

void hold(const VirtualDisplay& display, const std::string& key, double seconds) {
  runXdotool(display, {"keydown", key});
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  runXdotool(display, {"keyup", key});
}

// `manibench demos replay FILE --check`: every trajectory bit for bit.
void expectReplaysBitForBit(const std::string& path) {
  const manibench::testing::CommandResult replay = runCli({"demos", "replay", path, "--check"});
  EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  EXPECT_TRUE(contains(replay.out, "0 differ")) << replay.out;
}

TEST(ViewerWindow, WithoutADisplayItSaysSoInOneLineAndNamesTheHeadlessWay) {
  for (const char* display : {"", ":987"}) {
    char out_path[] = "/tmp/manibench_view_nodisplay_XXXXXX";
    const int out = mkstemp(out_path);
    const pid_t pid = fork();
    if (pid == 0) {
      dup2(out, 1);
      dup2(out, 2);
      if (*display) setenv("DISPLAY", display, 1); else unsetenv("DISPLAY");
      execl(MANIBENCH_TEST_CLI, MANIBENCH_TEST_CLI, "view", "OpenCabinetDrawer-v0", static_cast<char*>(nullptr));
      _exit(127);
    }
    close(out);
    int status = 0;
    waitpid(pid, &status, 0);
    std::ifstream in(out_path);
    std::stringstream text;
    text << in.rdbuf();
    std::remove(out_path);
    const std::string message = text.str();
    EXPECT_EQ(WEXITSTATUS(status), 1) << message;
    EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 1) << message;
    for (const char* part : {"manibench: error: ", "display", "manibench render", "--video"})
      EXPECT_TRUE(contains(message, part)) << message;
  }
}

// Nothing but the viewer links GLFW or Xlib: every other program runs
// where no display is.
TEST(ViewerWindow, TheManibenchProgramItselfNeedsNoDisplayLibrary) {
  FILE* pipe = popen(("ldd " + std::string(MANIBENCH_TEST_CLI)).c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string libraries;
  char buffer[512];
  while (fgets(buffer, sizeof(buffer), pipe)) libraries += buffer;
  pclose(pipe);
  EXPECT_FALSE(contains(libraries, "libglfw")) << libraries;
  EXPECT_FALSE(contains(libraries, "libX11")) << libraries;
}

// Each family's window opens; a screenshot the viewer takes itself (F12)
// of the masks view shows the robot in its mask colour; a mouse drag turns
// the free camera.
TEST(ViewerWindow, OpensForEveryTaskFamilyAndItsScreenshotShowsTheRobot) {
  VirtualDisplay display;
  for (const char* name : {"OpenCabinetDrawer-v0", "OpenCabinetDoor-v0", "PushChair-v0", "MoveBucket-v0", "Reach-v0"}) {
    const std::string task = name;
    SCOPED_TRACE(task);
    TempDir dir;
    ViewerProcess viewer(display, {task, "--paused", "--masks", "--screenshot-dir", dir.get()});
    ASSERT_TRUE(viewer.waitForOutput(kReady, kStartSeconds)) << viewer.getOut() << viewer.getErr();
    const std::string window = viewer.focusWindow(display);
    const Rgb first = takeScreenshot(display, viewer, 0);
    EXPECT_EQ(first.width, 1280);
    EXPECT_EQ(first.height, 720);
    const std::size_t robot = countColor(first, ViewComposer::getMaskColor(findMask(task, "robot")));
    // Reach's robot is two 4 cm bars: 1958 pixels at its reset here.
    EXPECT_GT(robot, task == "Reach-v0" ? 1000u : 2000u);
    if (task == "OpenCabinetDrawer-v0") {
      runXdotool(display, {"mousemove", "--window", window, "640", "400", "mousedown", "1", "mousemove_relative",
                           "--", "150", "40", "mouseup", "1"});
      const Rgb turned = takeScreenshot(display, viewer, 1);
      EXPECT_GT(countDifferent(first, turned), 20000u);
    }
    runXdotool(display, {"key", "Escape"});
    EXPECT_EQ(viewer.wait(60), 0) << viewer.getErr();
  }
}

// Holding the key for "base forward" drives the base forward, the key for
// "gripper up" raises the gripper: in the environment states the viewer
// recorded, which `demos replay --check` replays bit for bit.
TEST(ViewerWindow, HeldKeysDriveTheBaseForwardAndRaiseTheGripper) {
  VirtualDisplay display;
  TempDir dir;
  const std::string file = dir / "held.h5";
  ViewerProcess viewer(display, {"OpenCabinetDrawer-v0", "--object", "2000_link_0", "--record", file});
  ASSERT_TRUE(viewer.waitForOutput(kReady, kStartSeconds)) << viewer.getOut() << viewer.getErr();
  viewer.focusWindow(display);
  hold(display, "w", 1.5);
  hold(display, "u", 1.0);
  runXdotool(display, {"key", "Escape"});
  ASSERT_EQ(viewer.wait(60), 0) << viewer.getErr();
  EXPECT_TRUE(contains(viewer.getOut(), "recorded 1 episode(s) to " + file)) << viewer.getOut();

  const DemoReader reader(file);
  EXPECT_TRUE(contains(reader.getInfo().policy, "teleop")) << reader.getInfo().policy;
  const Trajectory t = reader.read("traj_0");
  const std::unique_ptr<Environment> env = makeDemoEnvironment(getBuildTreeRegistry(), reader.getInfo());
  const RobotAt start = readRobot(*env, t.getEnvState(0));
  const RobotAt end = readRobot(*env, t.getEnvState(t.steps));
  // 1.5 s at 0.25 m/s is 0.37 m in real time; a machine slower than real
  // time gets fewer steps, so only the direction and a clear distance.
  EXPECT_GT((end.base - start.base).dot(start.heading), 0.05) << t.steps << " steps";
  EXPECT_LT(std::abs((end.base - start.base).cross(start.heading).z()), 0.02);
  EXPECT_GT(end.tcp.z() - start.tcp.z(), 0.03) << t.steps << " steps";
  expectReplaysBitForBit(file);
}

// The recording survives the window: killed (the X connection breaks: the
// episode so far is saved), the viewer terminated (the same, and the file
// closed with its sidecar), or killed outright (what was written before
// stays readable; nothing written leaves no file).
TEST(ViewerWindow, AKilledWindowOrViewerLeavesAReadableFileOrNone) {
  VirtualDisplay display;
  TempDir dir;
  {
    const std::string file = dir / "window_killed.h5";
    ViewerProcess viewer(display, {"OpenCabinetDrawer-v0", "--record", file});
    ASSERT_TRUE(viewer.waitForOutput(kReady, kStartSeconds)) << viewer.getErr();
    const std::string window = viewer.focusWindow(display);
    hold(display, "w", 0.5);
    runXdotool(display, {"windowkill", window});
    EXPECT_EQ(viewer.wait(60), 1);
    EXPECT_TRUE(contains(viewer.getErr(), "connection to the display was lost")) << viewer.getErr();
    EXPECT_TRUE(contains(viewer.getOut(), "recorded 1 episode(s)")) << viewer.getOut();
    EXPECT_EQ(DemoReader(file).getTrajectoryNames().size(), 1u);
    expectReplaysBitForBit(file);
  }
  {
    const std::string file = dir / "killed_after_one.h5";
    ViewerProcess viewer(display, {"OpenCabinetDrawer-v0", "--record", file});
    ASSERT_TRUE(viewer.waitForOutput(kReady, kStartSeconds)) << viewer.getErr();
    viewer.focusWindow(display);
    hold(display, "w", 0.5);
    runXdotool(display, {"key", "n"});  // the next object: the first episode is written
    ASSERT_TRUE([&] {
      for (int i = 0; i < 600 && !std::filesystem::exists(file); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      return std::filesystem::exists(file);
    }());
    hold(display, "w", 0.5);
    viewer.kill(SIGKILL);
    EXPECT_EQ(viewer.wait(60), 128 + SIGKILL);
    const DemoReader reader(file);
    EXPECT_EQ(reader.getTrajectoryNames().size(), 1u);
    expectReplaysBitForBit(file);
  }
  {
    // SIGTERM (or Ctrl-C) mid-episode: recorded, closed, status 130.
    const std::string file = dir / "terminated.h5";
    ViewerProcess viewer(display, {"OpenCabinetDrawer-v0", "--record", file});
    ASSERT_TRUE(viewer.waitForOutput(kReady, kStartSeconds)) << viewer.getErr();
    viewer.focusWindow(display);
    hold(display, "w", 0.5);
    viewer.kill(SIGTERM);
    EXPECT_EQ(viewer.wait(60), 130) << viewer.getErr();
    EXPECT_TRUE(contains(viewer.getOut(), "recorded 1 episode(s)")) << viewer.getOut();
    EXPECT_TRUE(std::filesystem::exists(getDemoJsonPath(file)));
    expectReplaysBitForBit(file);
  }
  {
    const std::string file = dir / "killed_before_any.h5";
    ViewerProcess viewer(display, {"OpenCabinetDrawer-v0", "--record", file});
    ASSERT_TRUE(viewer.waitForOutput(kReady, kStartSeconds)) << viewer.getErr();
    viewer.kill(SIGKILL);
    viewer.wait(60);
    EXPECT_FALSE(std::filesystem::exists(file));
  }
}

// --replay of a generated file plays it in real time to the recorded final
// state, bit for bit at every state.
TEST(ViewerWindow, ReplayOfAGeneratedFileReachesTheRecordedFinalState) {
  TempDir dir;
  const std::string file = dir / "expert.h5";
  const manibench::testing::CommandResult generated =
      runCli({"demos", "generate", "OpenCabinetDrawer-v0", "--policy", "open_cabinet_expert", "--controller",
              "mobile_panda_ee", "--objects", "2000_link_0", "--out", file, "--no-progress"});
  ASSERT_EQ(generated.exit_code, 0) << generated.out << generated.err;
  VirtualDisplay display;
  ViewerProcess viewer(display, {"--replay", file, "--trajectory", "traj_0"});
  ASSERT_TRUE(viewer.waitForOutput(kReady, kStartSeconds)) << viewer.getErr();
  ASSERT_TRUE(viewer.waitForOutput("replayed to its last state", 120)) << viewer.getOut() << viewer.getErr();
  EXPECT_TRUE(contains(viewer.getOut(), "traj_0: replayed to its last state (step " +
                                            std::to_string(DemoReader(file).readSummary("traj_0").steps) +
                                            "), every state bit-identical to the recording"))
      << viewer.getOut();
  viewer.focusWindow(display);
  runXdotool(display, {"key", "Escape"});
  EXPECT_EQ(viewer.wait(60), 0) << viewer.getErr();
}


// What a person at the keyboard does, scripted: a drawer opened by key
// presses alone, paused and stepping with `.` (one step per tap, with the
// keys held at that moment), so that the episode does not depend on how
// fast this machine runs. Each entry: keys held, then taps of `.`; or a
// key tapped once (no steps). The plan was found by trying it in a
// teleoperation session (object 2000_link_0, seed 0).
struct PlanEntry {
  std::vector<std::string> held;  // xdotool key names
  int steps = 0;                  // taps of `.` while they are held
};
const std::vector<PlanEntry> kDrawerPlan = {
    {{"equal"}, 0}, {{"equal"}, 0},        // speed 50 % -> 100 %
    {{"a"}, 24},                           // base left: the arm (on the right) in front of the handle
    {{"w"}, 25},                           // base forward, within the arm's reach
    {{"o"}, 9},                            // gripper down to the handle's height
    {{"minus"}, 0}, {{"minus"}, 0}, {{"minus"}, 0},  // speed 25 %: the last centimetres
    {{"i", "j"}, 5},                       // gripper forward and left
    {{"i"}, 10},                           // forward, around the handle
    {{"u"}, 2},                            // up 1 cm
    {{}, 3},                               // settle
    {{"g"}, 0},                            // close the gripper
    {{}, 5},                               // let it close
    {{"s"}, 45},                           // base back: pull the drawer out
    {{}, 10},                              // hold still: success holds for 10 steps
};

TEST(ViewerWindow, ADrawerOpenedByKeyPressesAloneIsRecordedReplayedAndCountedASuccess) {
  VirtualDisplay display;
  TempDir dir;
  const std::string file = dir / "drawer_by_keys.h5";
  ViewerProcess viewer(display, {"OpenCabinetDrawer-v0", "--object", "2000_link_0", "--seed", "0", "--paused",
                                 "--record", file});
  ASSERT_TRUE(viewer.waitForOutput(kReady, kStartSeconds)) << viewer.getOut() << viewer.getErr();
  viewer.focusWindow(display);
  int presses = 0, steps = 0;
  for (const PlanEntry& entry : kDrawerPlan) {
    if (entry.steps == 0) {
      runXdotool(display, {"key", "--delay", "40", entry.held.front()});
      ++presses;
      continue;
    }
    if (!entry.held.empty()) {
      std::vector<std::string> down = {"keydown"};
      down.insert(down.end(), entry.held.begin(), entry.held.end());
      runXdotool(display, down);
      presses += int(entry.held.size());
    }
    // More than GLFW's 20 ms between taps (closer ones arrive as repeats,
    // which step all the same).
    runXdotool(display, {"key", "--repeat", std::to_string(entry.steps), "--delay", "40", "period"});
    presses += entry.steps;
    steps += entry.steps;
    if (!entry.held.empty()) {
      std::vector<std::string> up = {"keyup"};
      up.insert(up.end(), entry.held.rbegin(), entry.held.rend());
      runXdotool(display, up);
    }
  }
  runXdotool(display, {"key", "Escape"});
  ASSERT_EQ(viewer.wait(120), 0) << viewer.getErr();
  EXPECT_TRUE(contains(viewer.getOut(), "recorded 1 episode(s)")) << viewer.getOut();
  const DemoReader reader(file);
  ASSERT_EQ(reader.getTrajectoryNames().size(), 1u);
  const Trajectory t = reader.read("traj_0");
  EXPECT_TRUE(t.success) << t.steps << " steps";
  EXPECT_LE(t.steps, uint32_t(steps));
  EXPECT_TRUE(contains(reader.getInfo().policy, "teleop"));
  expectReplaysBitForBit(file);
  std::cout << "drawer opened in " << t.steps << " steps by " << presses << " key presses (" << steps
            << " taps of '.', " << presses - steps << " other keys)\n";
}

}  // namespace
}  // namespace manibench::viewer
