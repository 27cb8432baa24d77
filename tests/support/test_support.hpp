// Shared helpers for the test programs.
#pragma once

#include <manibench/plugin_registry.hpp>

#include <string>
#include <vector>

namespace manibench::testing {

// A registry holding the plugins of this build tree (and nothing else).
PluginRegistry& getBuildTreeRegistry();
// The build tree's plugins plus the fixture task RobotTestbed-v0 (which
// lives outside the default search path).
const PluginRegistry& getRobotTestbedRegistry();

// This process's resident memory (VmRSS), kB; -1 if unknown.
long readRssKb();

struct CommandResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs the built `manibench` CLI with `arguments` (each passed as one word),
// with extra environment assignments "NAME=value" in `environment`.
CommandResult runCli(const std::vector<std::string>& arguments,
                     const std::vector<std::string>& environment = {});

}  // namespace manibench::testing
