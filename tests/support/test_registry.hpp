// The build tree's plugins as a registry, for the tests of the runtime and
// the layers above it (links manibench::runtime).
#pragma once

#include <manibench/plugin_registry.hpp>

#include "test_support.hpp"

namespace manibench::testing {

// A registry holding the plugins of this build tree (and nothing else).
PluginRegistry& getBuildTreeRegistry();
// The build tree's plugins plus the fixture task RobotTestbed-v0 (which
// lives outside the default search path).
const PluginRegistry& getRobotTestbedRegistry();

}  // namespace manibench::testing
