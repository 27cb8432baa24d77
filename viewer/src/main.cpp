// manibench-view: the program `manibench view` runs (docs/viewer.md).
// A window on a task (GLFW, Dear ImGui, the core's EGL renderer): look
// around, drive the robot by keyboard and record what you did, or watch a
// policy or a demonstration file. Exit codes as manibench's: 0, 1 (an
// error, or a replay that differed from its recording), 2 (usage).
#include <manibench/plugin_registry.hpp>
#include <manibench/task_name.hpp>

#include <cstdio>
#include <iostream>
#include <string>

#include "cli.hpp"
#include "session.hpp"
#include "viewer_app.hpp"

using namespace manibench;
using namespace manibench::viewer;

namespace {

const std::string kViewUsageText = R"(usage: manibench view TASK [options]                 drive the robot by keyboard
       manibench view TASK --policy NAME|PATH.so|PATH.py    watch a policy
       manibench view --replay FILE.h5 [--trajectory traj_N] watch a demonstration

A window on a task: the scene from a free camera (mouse: drag to orbit,
Shift-drag or right-drag to pan, wheel to zoom) or from the task's cameras,
its segmentation masks, the point cloud a policy gets, and an overlay with
the step, reward, success conditions, object and seed. Physics runs in real
time (the overlay says when the machine is slower). Without --policy or
--replay the keyboard drives the mobile base and each gripper through the
end-effector controller (mobile_panda_ee, chosen unless --controller says
otherwise); the keymap is in the window (H). Needs a display: headless,
use `manibench render` (images, --video).

Options:
  --object ID             object id (default: drawn from the split by the seed)
  --seed S                episode seed (default 0)
  --split train|test      split of the objects (default train); N moves on
  --controller NAME       controller (default: the task's; mobile_panda_ee
                          for the mobile Panda robots when driving by keyboard)
  --obs MODE              observation mode: state, pointcloud or rgbd
  --config FILE, --set KEY=VALUE   configuration layers, as for run
)" + std::string(cli::kPolicyUsage) + R"(                          the policy gets the controller it names, as in run
  --record FILE.h5        every episode driven (or watched) with at least one
                          step into a demonstration file (docs/demonstrations.md;
                          policy `teleop` when driving), replayable with
                          `manibench demos replay FILE.h5 --check`
  --replay FILE.h5        play a demonstration file's trajectories, with a
                          timeline; --trajectory traj_N starts at that one
  --size WxH              window size (default 1280x720)
  --camera NAME           start with task camera NAME (default: the free camera)
  --masks, --points       start with the masks / the point cloud shown
  --paused                start paused
  --screenshot-dir DIR    where F12 writes PNG screenshots (default: .)
  --measure SECONDS       print the frame rate over SECONDS (after one second)
                          and quit; no vsync
  --no-vsync              do not wait for the display's refresh
)";
const char* const kViewUsage = kViewUsageText.c_str();

using cli::UsageError;

void parseSize(const std::string& text, ViewerOptions& options) {
  int w = 0, h = 0;
  char x = 0;
  if (std::sscanf(text.c_str(), "%d%c%d", &w, &x, &h) != 3 || x != 'x' || w < 64 || h < 64 || w > 8192 ||
      h > 8192)
    throw UsageError("--size must be WxH, from 64 to 8192, got '" + text + "'", kViewUsage);
  options.width = w;
  options.height = h;
}

// Driving by keyboard goes through mobile_panda_ee: a mobile Panda task
// gets it unless the user chose a controller.
void chooseTeleopController(const PluginRegistry& registry, const std::string& task, ConfigSources& sources) {
  for (const std::string& set : sources.overrides)
    if (set.rfind("control.controller=", 0) == 0) return;
  const TaskId id = resolveTaskId(registry, task);
  const TaskInstance probe(registry, id.task, "");
  const std::string controller = probe.getDescription().default_controller;
  if (controller == "mobile_panda" || controller == "mobile_panda_ee")
    sources.overrides.insert(sources.overrides.begin(), "control.controller=mobile_panda_ee");
}

// What runs: a replay, or a task driven by keys or watched (its policy is
// resolved once the plugins are loaded: choosePolicy).
SessionOptions parseSessionOptions(const cli::Arguments& args, int argc, char** argv) {
  SessionOptions session;
  session.command = cli::joinCommand(argc, argv);
  if (args.options.count("replay")) {
    if (!args.positional.empty())
      throw UsageError("--replay takes no TASK: the file names its task", kViewUsage);
    for (const char* option : {"policy", "record", "object", "seed", "split", "controller", "obs"})
      if (args.options.count(option))
        throw UsageError(std::string("--replay plays the file as recorded: no --") + option, kViewUsage);
    if (args.repeated.count("config") || args.repeated.count("set"))
      throw UsageError("--replay plays the file as recorded: no --config or --set", kViewUsage);
    session.mode = SessionMode::Replay;
    session.replay_path = args.options.at("replay");
    session.trajectory = cli::valueOr(args, "trajectory", "");
    return session;
  }
  if (args.positional.size() != 1) throw UsageError("view needs one TASK (or --replay FILE.h5)", kViewUsage);
  if (args.options.count("trajectory")) throw UsageError("--trajectory goes with --replay", kViewUsage);
  session.task = args.positional[0];
  session.split = cli::parseSplit(args, "train", kViewUsage);
  session.seed = cli::parseSeed(cli::valueOr(args, "seed", "0"), kViewUsage);
  session.object = cli::valueOr(args, "object", "");
  session.record_path = cli::valueOr(args, "record", "");
  session.sources = cli::getConfigSources(args, cli::parseObservationMode(args, kViewUsage));
  return session;
}

ViewerOptions parseViewerOptions(const cli::Arguments& args, const SessionOptions& session) {
  ViewerOptions options;
  if (args.options.count("size")) parseSize(args.options.at("size"), options);
  options.paused = args.options.count("paused") != 0;
  options.vsync = args.options.count("no-vsync") == 0;
  options.screenshot_dir = cli::valueOr(args, "screenshot-dir", ".");
  if (args.options.count("measure")) {
    char* end = nullptr;
    options.measure_seconds = std::strtod(args.options.at("measure").c_str(), &end);
    if (*end || !(options.measure_seconds > 0))
      throw UsageError("--measure needs a positive number of seconds", kViewUsage);
  }
  options.title = "manibench view: " + (session.mode == SessionMode::Replay ? session.replay_path : session.task);
  return options;
}

// --policy (a name, a library, a Python file; as every command that runs a
// policy: cli::choosePolicy) with the controller it names or, without one,
// the controller teleoperation needs.
void choosePolicy(PluginRegistry& registry, const cli::Arguments& args, SessionOptions& session) {
  if (session.mode == SessionMode::Replay) return;
  if (!args.options.count("policy")) {
    chooseTeleopController(registry, session.task, session.sources);
    return;
  }
  session.mode = SessionMode::Policy;
  const cli::PolicyChoice choice = cli::choosePolicy(registry, args, kViewUsage);
  session.policy = choice.name;
  session.policy_config = choice.config;
  cli::applyPolicyController(registry, session.policy, args, session.sources, kViewUsage);
}

// --camera NAME: its index among the task's cameras.
int findCamera(const Session& session, const std::string& name) {
  const CameraRig& rig = session.getEnvironment().getObserver().getCameras();
  std::string names;
  for (std::size_t i = 0; i < rig.getCount(); ++i) {
    if (rig.getMount(i).spec.name == name) return int(i);
    names += (i ? ", " : "") + rig.getMount(i).spec.name;
  }
  throw UsageError("--camera: the task has no camera '" + name + "' (it has " + names + ")", kViewUsage);
}

int view(int argc, char** argv) {
  // `manibench view ...` runs this program with its own arguments.
  const int first = argc > 1 && std::string(argv[1]) == "view" ? 2 : 1;
  const cli::Arguments args = cli::parseArguments(
      argc, argv, first,
      {"object", "seed", "split", "controller", "obs", "config", "set", "policy", "policy-config", "record",
       "replay", "trajectory", "size", "camera", "screenshot-dir", "measure"},
      {"masks", "points", "paused", "no-vsync"}, kViewUsage);
  if (args.help) {
    std::cout << kViewUsage;
    return 0;
  }
  SessionOptions session = parseSessionOptions(args, argc, argv);
  const ViewerOptions options = parseViewerOptions(args, session);
  ViewSettings first_view;
  first_view.masks = args.options.count("masks") != 0;
  first_view.points = args.options.count("points") != 0;

  // The window first: without a display, say so before loading anything.
  ViewerApp app(options);
  PluginRegistry registry;
  cli::loadPlugins(registry);
  choosePolicy(registry, args, session);
  Session running(registry, session);
  if (args.options.count("camera")) first_view.camera = findCamera(running, args.options.at("camera"));
  const Environment& env = running.getEnvironment();
  std::cout << "view " << env.getEnvironmentId() << ", object " << env.getObjectId() << ", seed " << env.getSeed()
            << ", "
            << (session.mode == SessionMode::Replay ? "replay of " + running.getTrajectoryName()
                                                    : running.getPolicyName())
            << ", controller " << env.getControllerDescription().name << "; Esc quits\n"
            << std::flush;
  return app.run(running, first_view);
}

}  // namespace

int main(int argc, char** argv) {
  return cli::runMain("manibench", [&] { return view(argc, argv); });
}
