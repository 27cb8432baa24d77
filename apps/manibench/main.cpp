// manibench: the host program. Loads plugins by name and runs them.
//   manibench list | info | run | bench | config | render | objects | eval | demo
// Exit codes: 0 success, 1 failure (reported on stderr), 2 usage error.
#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/task_name.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"

namespace manibench::cli {
int commandEval(int argc, char** argv);  // command_eval.cpp
}  // namespace manibench::cli

namespace mb = manibench;
using namespace manibench::cli;

namespace manibench::cli {
int commandRender(int argc, char** argv);  // command_render.cpp
}

namespace manibench::cli {
int commandObjects(int argc, char** argv);  // command_objects.cpp
}

namespace {


const char* kMainUsage = R"(usage: manibench <command> [options]

Commands:
  list                      every loaded plugin: kind, name, version, library
  info TASK                 observation and action layout, success conditions,
                            masks and objects of a task
  run TASK --policy NAME    run one episode and print steps, return, success
  bench TASK                environment steps per second of a task
  render TASK --out DIR     camera images, masks and point clouds as PNG/PLY
  eval TASK --policy NAME   evaluate a policy on a split's objects: success
                            rates per object, CSV and JSON (docs/evaluation.md)
  objects TASK              object ids of a split (--split train|test)
  config [TASK]             print the merged YAML configuration
  demo                      list the plugins, then evaluate the cabinet expert
                            on the OpenCabinetDrawer-v0 test split

TASK is a task name (a random object of the split each episode) or a
fixed-object id <Task>_<object>-v<N>, e.g. OpenCabinetDrawer_1000-v0.
Run `manibench <command> --help` for a command's options. info, run, bench,
render, eval, objects and config take --config FILE and --set KEY=VALUE
(docs/configuration.md).
Plugins are searched in $MANIBENCH_PLUGIN_PATH, ~/.local/lib/manibench/plugins,
the install prefix and the build tree, in that order.
)";

const char* kListUsage = R"(usage: manibench list

Lists every plugin library found on the search path with what it registered
(kind, name, library version, file), then any library that was refused and why.
)";

const char* kInfoUsage = R"(usage: manibench info TASK [--controller NAME] [--config FILE]... [--set KEY=VALUE]...

Prints the task's timing, observation layout, the controller's action layout,
the success conditions, segmentation masks and the objects of each split, as
configured. TASK may be a fixed-object id such as OpenCabinetDrawer_1000-v0
(<Task>_<object>-v<N>): then the objects are that environment's.

Options:
  --controller NAME       override the task's default controller
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key, e.g. --set control.frequency=50; repeatable
)";

const char* kRunUsage = R"(usage: manibench run TASK --policy NAME|PATH.so [options]

TASK is a task name or a fixed-object id <Task>_<object>-v<N> such as
Reach_3-v0 or OpenCabinetDrawer_1000-v0 (the object is drawn from its own).

Options:
  --policy NAME|PATH.so   policy plugin by name, or a library file to load
  --seed S                episode seed (default 0)
  --object ID             object id (default: drawn from the split by the seed)
  --split train|test      split to draw the object from (default train)
  --controller NAME       override the task's default controller
  --obs MODE              observation mode: state (default), pointcloud or rgbd
  --no-early-stop         run to the time limit even after success
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key, e.g. --set physics.accuracy=0.001; repeatable
)";

const char* kConfigUsage = R"(usage: manibench config [TASK] [--config FILE]... [--set KEY=VALUE]... [--explain]

Prints the merged configuration as YAML. Layers, lowest first: the built-in
defaults, the task's description and its own YAML (when TASK is given), each
--config FILE in the order given, each --set in the order given. Maps merge
key by key; scalars and lists replace. Keys are checked against the schema
in docs/configuration.md.

Options:
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key; VALUE is YAML: 0.001, cpodes, [0, 0, -9.81],
                          {reach_tolerance: 0.05}; empty means null; repeatable
  --explain               name each value's origin (file:line, --set, task, ...)
)";

const char* kBenchUsage = R"(usage: manibench bench TASK [options]

Measures environment steps per second: episodes of TASK on the split's
objects (in turn, seeds 0, 1, ...) until --steps environment steps have run.
Each env step is frame_skip control steps of physics plus the task's reward,
success and observation; resets are timed separately. A second line gives
the integrator's work per env step (steps, failed steps, Newton iterations,
Jacobians, evaluations of the equations of motion), which does not depend
on the load of the machine.

Options:
  --policy NAME|PATH.so   policy acting (default random)
  --obs MODE              observation mode: state (default), pointcloud or rgbd
                          (the visual modes render every camera at every step)
  --steps N               environment steps to time (default 2000)
  --split train|test      objects to cycle through (default train)
  --controller NAME       override the task's default controller
  --config FILE, --set KEY=VALUE   configuration layers, as for run
)";

const char* kDemoUsage = R"(usage: manibench demo [--out DIR]

Lists the plugins, then evaluates the scripted expert (open_cabinet_expert on
the mobile_panda_ee controller) on the test split of OpenCabinetDrawer-v0 in
state mode, one episode per object with two workers, and prints the table:
the same as

  manibench eval OpenCabinetDrawer-v0 --policy open_cabinet_expert \
      --controller mobile_panda_ee --obs state --split test \
      --episodes-per-object 1 --workers 2 --seed 0 --out DIR

Options:
  --out DIR   where the CSV and JSON files go (default demo-results)
)";

int commandList(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {}, {}, kListUsage);
  if (args.help) {
    std::cout << kListUsage;
    return 0;
  }
  if (!args.positional.empty()) throw UsageError("list takes no arguments", kListUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  std::cout << "search path:\n";
  for (const std::string& dir : mb::PluginRegistry::calcDefaultSearchPath())
    std::cout << "  " << dir << "\n";
  std::cout << "\n" << std::left << std::setw(12) << "KIND" << std::setw(26) << "NAME"
            << std::setw(10) << "VERSION" << "LIBRARY\n";
  for (const mb::PluginEntry& e : registry.getEntries()) {
    const mb::LoadedLibrary& lib = registry.getLibraries()[e.library];
    std::cout << std::left << std::setw(12) << mb::toString(e.kind) << std::setw(26) << e.name
              << std::setw(10) << lib.version << lib.path << "\n";
  }
  for (const std::string& task : registry.getNames(mb::PluginKind::Task)) {
    const std::string form = mb::makeFixedObjectId(task, "<object>");
    if (form.empty()) continue;
    std::cout << "\nevery task <Task>-v<N> is also one environment per object (or object group):\n"
              << "<Task>_<object>-v<N>, e.g. " << form
              << " (`manibench objects TASK` lists the objects)\n";
    break;
  }
  if (!registry.getFailures().empty()) {
    std::cout << "\nrefused libraries:\n";
    for (const mb::LoadFailure& f : registry.getFailures()) std::cout << "  " << f.message << "\n";
  }
  return 0;
}


int commandInfo(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {"controller", "config", "set"}, {}, kInfoUsage);
  if (args.help) {
    std::cout << kInfoUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("info needs exactly one TASK", kInfoUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  const std::unique_ptr<mb::Environment> env_owner =
      makeEnvironment(registry, args.positional[0], getConfigSources(args), true);
  mb::Environment& env = *env_owner;
  const mb::TaskDescription& task = env.getTaskDescription();
  const std::vector<std::string> train = env.listObjects("train");
  const std::vector<std::string> test = env.listObjects("test");
  if (train.empty()) throw std::runtime_error("task '" + task.name + "' has no train objects");
  env.reset(train.front(), 0);  // the action layout needs the robot's joints
  const mb::ControllerDescription& controller = env.getControllerDescription();

  if (!env.getFixedObjects().empty()) std::cout << "environment " << env.getEnvironmentId() << ": ";
  std::cout << "task " << task.name << " ("
            << registry.getLibraries()[registry.getEntry(mb::PluginKind::Task, task.name).library].path
            << ")\n";
  std::cout << "control " << task.control_frequency << " Hz, frame skip " << task.frame_skip
            << ", " << task.max_episode_steps << " steps per episode\n\n";
  std::cout << "observation (state), " << task.observation_dim << " values:\n";
  printSegments(task.observation_segments);
  std::cout << "pointcloud and rgbd modes: the first " << task.agent_state_dim
            << " values (the robot's own state) with the visual data\n";
  std::cout << "\naction, " << controller.action_dim << " values in [-1, 1], controller '"
            << controller.name << "'"
            << ((controller.flags & MB_CONTROLLER_BALANCE_PASSIVE_FORCES) ? " (balances gravity)" : "")
            << ":\n";
  printSegments(controller.action_segments);
  std::cout << "\nsuccess conditions:";
  for (const std::string& c : task.success_conditions) std::cout << " " << c;
  std::cout << "\nmasks:";
  if (task.masks.empty()) std::cout << " (none)";
  for (const std::string& m : task.masks) std::cout << " " << m;
  if (env.getFixedObjects().empty()) {
    std::cout << "\nobjects: " << train.size() << " train, " << test.size() << " test\n";
  } else {
    std::cout << "\nfixed objects (" << env.getFixedObjects().size() << "):";
    for (const std::string& o : env.getFixedObjects()) std::cout << " " << o;
    std::cout << "\n";
  }
  std::cout << "scene: " << env.getScene().getVisualShapes().size() << " visuals, "
            << env.getScene().calcVisualTriangleCount()
            << " mesh triangles (the renderer adds tessellated primitives)\n";
  std::cout << "cameras:";
  const std::vector<mb::CameraMount>& cameras = env.getOptions().observation.cameras;
  if (cameras.empty()) std::cout << " (none)";
  for (const mb::CameraMount& c : cameras)
    std::cout << " " << c.spec.name << " (" << c.spec.width << "x" << c.spec.height << ", "
              << (c.articulation.empty() ? std::string("world")
                                         : c.articulation + (c.link.empty() ? "" : ":" + c.link))
              << ")";
  std::cout << "\n";
  return 0;
}

int runOne(mb::PluginRegistry& registry, const std::string& task_name, const std::string& policy_arg,
           uint64_t seed, const std::string& object_arg, const std::string& split,
           const mb::ConfigSources& sources, bool stop_on_success) {
  const std::string policy_name = resolvePolicy(registry, policy_arg);
  registry.getEntry(mb::PluginKind::Policy, policy_name);  // fail before building anything
  const std::unique_ptr<mb::Environment> env_owner =
      makeEnvironment(registry, task_name, sources, stop_on_success);
  mb::Environment& env = *env_owner;
  const std::string object =
      object_arg.empty() ? chooseObject(env.listObjects(split), seed, split) : object_arg;
  env.reset(object, seed);
  mb::PolicyInstance policy(registry, policy_name, "", env.calcPolicyLayout());
  std::cout << "task " << task_name << ", policy " << policy_name << ", controller "
            << env.getControllerDescription().name << "\n";
  // A policy's failure is named by where it happened, as the environment's
  // own errors are.
  mb::EpisodeHooks hooks;
  bool acting = false;
  hooks.on_phase = [&acting](mb::EpisodePhase phase, uint32_t) {
    acting = phase == mb::EpisodePhase::PolicyAct;
  };
  try {
    printEpisode(mb::runEpisode(env, policy, object, seed, hooks));
  } catch (const mb::PluginCallError& e) {
    if (!acting) throw;
    throw mb::PluginCallError("task '" + env.getTaskDescription().name + "', object '" + object +
                                  "', seed " + std::to_string(seed) + ", step " +
                                  std::to_string(env.getElapsedSteps()) + ": " + e.what(),
                              e.status());
  }
  return 0;
}

// The configuration sources, with --obs MODE as the last --set observation.mode.
mb::ConfigSources withObservationMode(const Arguments& args, const char* usage) {
  mb::ConfigSources sources = getConfigSources(args);
  if (args.options.count("obs")) {
    const std::string obs = args.options.at("obs");
    if (obs != "state" && obs != "pointcloud" && obs != "rgbd")
      throw UsageError("--obs must be state, pointcloud or rgbd, got '" + obs + "'", usage);
    sources.overrides.push_back("observation.mode=" + obs);
  }
  return sources;
}

int commandRun(int argc, char** argv) {
  const Arguments args =
      parseArguments(argc, argv, 2,
                     {"policy", "seed", "object", "split", "controller", "obs", "config", "set"},
                     {"no-early-stop"}, kRunUsage);
  if (args.help) {
    std::cout << kRunUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("run needs exactly one TASK", kRunUsage);
  if (!args.options.count("policy")) throw UsageError("run needs --policy NAME", kRunUsage);
  const std::string split = valueOr(args, "split", "train");
  if (split != "train" && split != "test")
    throw UsageError("--split must be train or test", kRunUsage);
  const uint64_t seed = parseSeed(valueOr(args, "seed", "0"), kRunUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  return runOne(registry, args.positional[0], args.options.at("policy"), seed,
                valueOr(args, "object", ""), split, withObservationMode(args, kRunUsage),
                !args.options.count("no-early-stop"));
}

int commandConfig(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {"config", "set"}, {"explain"}, kConfigUsage);
  if (args.help) {
    std::cout << kConfigUsage;
    return 0;
  }
  if (args.positional.size() > 1) throw UsageError("config takes at most one TASK", kConfigUsage);
  const mb::ConfigSources sources = getConfigSources(args);
  mb::ConfigNode config;
  if (args.positional.empty()) {
    config = mb::calcConfig(nullptr, sources);
  } else {
    mb::PluginRegistry registry;
    loadPlugins(registry);
    config = mb::loadTaskConfig(registry, args.positional[0], sources);
  }
  // What an environment would refuse (e.g. sideways gravity), refuse here too.
  mb::calcEnvironmentOptions(config);
  std::cout << mb::formatConfig(config, args.options.count("explain") != 0);
  return 0;
}

int commandBench(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2,
                                        {"policy", "obs", "steps", "split", "controller", "config", "set"}, {},
                                        kBenchUsage);
  if (args.help) {
    std::cout << kBenchUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("bench needs exactly one TASK", kBenchUsage);
  const std::string obs = valueOr(args, "obs", "state");
  if (obs != "state" && obs != "pointcloud" && obs != "rgbd")
    throw UsageError("--obs must be state, pointcloud or rgbd, got '" + obs + "'", kBenchUsage);
  mb::ConfigSources sources = getConfigSources(args);
  if (args.options.count("obs")) sources.overrides.push_back("observation.mode=" + obs);
  const std::string split = valueOr(args, "split", "train");
  if (split != "train" && split != "test")
    throw UsageError("--split must be train or test", kBenchUsage);
  const uint64_t target_steps = parseSeed(valueOr(args, "steps", "2000"), kBenchUsage, "--steps");
  if (target_steps == 0) throw UsageError("--steps must be positive", kBenchUsage);

  mb::PluginRegistry registry;
  loadPlugins(registry);
  const std::string policy_name = resolvePolicy(registry, valueOr(args, "policy", "random"));
  registry.getEntry(mb::PluginKind::Policy, policy_name);
  const std::unique_ptr<mb::Environment> env =
      makeEnvironment(registry, args.positional[0], sources, true);
  const std::vector<std::string> objects = env->listObjects(split);
  if (objects.empty()) throw std::runtime_error("the " + split + " split has no objects");
  mb::PolicyInstance policy(registry, policy_name, "", env->calcPolicyLayout());

  using Clock = std::chrono::steady_clock;
  std::chrono::duration<double> step_time{0}, reset_time{0};
  uint64_t steps = 0, episodes = 0, successes = 0;
  // Integrator work during env steps only (resets rebuild scenes).
  mb::IntegratorStatistics physics, before;
  Clock::time_point start;
  // Resets (environment and policy) from entering the first to the first
  // act; env steps from each act to the end of its step.
  mb::EpisodeHooks hooks;
  hooks.on_phase = [&](mb::EpisodePhase phase, uint32_t step) {
    if (phase == mb::EpisodePhase::EnvReset) start = Clock::now();
    if (phase != mb::EpisodePhase::PolicyAct) return;
    if (step == 0) reset_time += Clock::now() - start;
    before = env->getScene().getIntegratorStatistics();
    start = Clock::now();
  };
  hooks.on_step = [&](const mb::StepResult& result, const mb::EpisodeResult&) {
    step_time += Clock::now() - start;
    physics += env->getScene().getIntegratorStatistics();
    physics -= before;
    ++steps;
    if (result.done && result.success) ++successes;
    return steps < target_steps;
  };
  while (steps < target_steps) {
    mb::runEpisode(*env, policy, objects[episodes % objects.size()], episodes, hooks);
    ++episodes;
  }
  std::cout << "task " << args.positional[0] << ", obs " << mb::toString(env->getObservationMode()) << ", policy " << policy_name
            << ", controller " << env->getControllerDescription().name << "\n"
            << steps << " env steps in " << episodes << " episodes (" << successes
            << " successful), " << std::fixed << std::setprecision(1)
            << steps / step_time.count() << " env steps/s (policy + physics + task), "
            << std::setprecision(2) << 1e3 * reset_time.count() / double(episodes)
            << " ms per reset\n"
            << "physics per env step: " << std::setprecision(1)
            << double(physics.steps) / double(steps) << " integrator steps ("
            << double(physics.error_test_failures) / double(steps) << " error-test and "
            << double(physics.convergence_test_failures) / double(steps) << " convergence failures), "
            << double(physics.iterations) / double(steps) << " Newton iterations, "
            << double(physics.jacobians) / double(steps) << " Jacobians, "
            << double(physics.realizations) / double(steps) << " evaluations of the dynamics\n";
  std::cout.unsetf(std::ios::fixed);
  return 0;
}

int commandDemo(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {"out"}, {}, kDemoUsage);
  if (args.help) {
    std::cout << kDemoUsage;
    return 0;
  }
  if (!args.positional.empty()) throw UsageError("demo takes no arguments", kDemoUsage);
  commandList(2, argv);
  std::cout << "\n" << std::flush;
  std::vector<std::string> words = {argv[0], "eval", "OpenCabinetDrawer-v0",
                                    "--policy", "open_cabinet_expert",
                                    "--controller", "mobile_panda_ee",
                                    "--obs", "state", "--split", "test",
                                    "--episodes-per-object", "1", "--workers", "2",
                                    "--seed", "0", "--out", valueOr(args, "out", "demo-results")};
  std::vector<char*> eval_argv;
  for (std::string& w : words) eval_argv.push_back(w.data());
  eval_argv.push_back(nullptr);
  return manibench::cli::commandEval(int(words.size()), eval_argv.data());
}

}  // namespace

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  try {
    if (command == "--help" || command == "-h" || command == "help") {
      std::cout << kMainUsage;
      return 0;
    }
    if (command == "list") return commandList(argc, argv);
    if (command == "info") return commandInfo(argc, argv);
    if (command == "run") return commandRun(argc, argv);
    if (command == "config") return commandConfig(argc, argv);
    if (command == "demo") return commandDemo(argc, argv);
    if (command == "bench") return commandBench(argc, argv);
    if (command == "render") return commandRender(argc, argv);
    if (command == "eval") return manibench::cli::commandEval(argc, argv);
    if (command == "objects") return manibench::cli::commandObjects(argc, argv);
    throw UsageError(command.empty() ? "no command given" : "unknown command '" + command + "'",
                     kMainUsage);
  } catch (const UsageError& e) {
    std::cerr << "manibench: " << e.what() << "\n\n" << e.usage();
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "manibench: error: " << e.what() << "\n";
    return 1;
  }
}
