// What the demonstration tests share: generating a file the way
// `manibench demos generate` does, on the build tree's plugins.
#pragma once

#include <manibench/config.hpp>
#include <manibench/demos.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

#include "test_registry.hpp"

namespace manibench::testing {

struct DemoSetup {
  std::string task;
  std::string policy;
  std::string controller;  // empty: the task's default
};

inline ConfigSources makeDemoSources(const DemoSetup& setup) {
  ConfigSources sources;
  if (!setup.controller.empty()) sources.overrides.push_back("control.controller=" + setup.controller);
  return sources;
}

inline DemoFileInfo makeDemoInfo(const PluginRegistry& registry, const DemoSetup& setup) {
  DemoFileInfo info;
  info.manibench_version = getManibenchVersion();
  info.task = setup.task;
  info.environment_id = setup.task;
  info.config = formatConfig(loadTaskConfig(registry, setup.task, makeDemoSources(setup)));
  info.policy = setup.policy;
  info.command = "test";
  return info;
}

// `per_object` successful episodes of the first `objects` train objects
// (every one when empty) into `path`.
inline GenerationResult generateDemoFile(const DemoSetup& setup, const std::string& path,
                                         uint32_t per_object, unsigned workers,
                                         const std::vector<std::string>& objects = {},
                                         const GenerationHooks& hooks = {}) {
  PluginRegistry& registry = getBuildTreeRegistry();
  GenerationOptions options;
  options.evaluation.task = setup.task;
  options.evaluation.policy = setup.policy;
  options.evaluation.split = "train";
  options.evaluation.objects = objects;
  options.evaluation.workers = workers;
  options.per_object = per_object;
  const ConfigSources sources = makeDemoSources(setup);
  const EnvironmentFactory factory = [&registry, setup, sources] {
    EnvironmentOptions environment = calcEnvironmentOptions(loadTaskConfig(registry, setup.task, sources));
    environment.stop_on_success = true;
    return std::make_unique<Environment>(registry, setup.task, environment);
  };
  return generateDemonstrations(registry, options, factory, path, makeDemoInfo(registry, setup), hooks);
}

// A parameterized test's name: the task's letters and digits.
inline std::string nameDemoSetup(const ::testing::TestParamInfo<DemoSetup>& info) {
  std::string name = info.param.task;
  name.erase(std::remove_if(name.begin(), name.end(), [](char c) { return !std::isalnum(c); }), name.end());
  return name;
}

// A fresh folder for one test's files.
inline std::filesystem::path makeDemoDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("manibench_demos_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace manibench::testing
