// The build tree's plugins as a registry, for the tests of the runtime and
// the layers above it (links manibench::runtime).
#pragma once

#include <manibench/environment.hpp>
#include <manibench/plugin_registry.hpp>

#include <string>

#include "test_support.hpp"

namespace manibench::testing {

// A registry holding the plugins of this build tree (and nothing else).
PluginRegistry& getBuildTreeRegistry();
// The build tree's plugins plus the fixture task RobotTestbed-v0 (which
// lives outside the default search path).
const PluginRegistry& getRobotTestbedRegistry();

// Where segment `name` of `env`'s state observation starts; throws when it
// has none (the robot's segments of the mobile Panda tasks are found by name).
uint32_t getObservationOffset(const Environment& env, const std::string& name);

}  // namespace manibench::testing
