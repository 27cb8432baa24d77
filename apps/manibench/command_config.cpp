// manibench config: the merged YAML configuration, with --explain the origin
// of every value.
#include <iostream>

#include "cli.hpp"

namespace manibench::cli {

namespace {

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

}  // namespace

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

}  // namespace manibench::cli
