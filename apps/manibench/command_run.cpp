// manibench run: one episode of a policy, printed step count, return and
// success conditions.
#include <iostream>
#include <manibench/episode.hpp>
#include <memory>

#include "cli.hpp"

namespace manibench::cli {

namespace {

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


}  // namespace

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
  const std::string split = parseSplit(args, "train", kRunUsage);
  const mb::ConfigSources sources = getConfigSources(args, parseObservationMode(args, kRunUsage));
  const uint64_t seed = parseSeed(valueOr(args, "seed", "0"), kRunUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  return runOne(registry, args.positional[0], args.options.at("policy"), seed,
                valueOr(args, "object", ""), split, sources,
                !args.options.count("no-early-stop"));
}

}  // namespace manibench::cli
