#include "test_registry.hpp"

#include <stdexcept>
#include <string>

namespace manibench::testing {

PluginRegistry& getBuildTreeRegistry() {
  static PluginRegistry* registry = [] {
    auto* r = new PluginRegistry();
    r->loadDirectories({MANIBENCH_TEST_BUILD_PLUGIN_DIR});
    return r;
  }();
  return *registry;
}

const PluginRegistry& getRobotTestbedRegistry() {
  static PluginRegistry* registry = [] {
    auto* r = new PluginRegistry();
    r->loadDirectories({MANIBENCH_TEST_BUILD_PLUGIN_DIR});
    r->loadLibrary(std::string(MANIBENCH_TEST_FIXTURE_DIR) + "/libfixture_robot_testbed.so");
    return r;
  }();
  return *registry;
}

uint32_t getObservationOffset(const Environment& env, const std::string& name) {
  for (const sdk::Segment& s : env.getTaskDescription().observation_segments)
    if (s.name == name) return s.offset;
  throw std::invalid_argument("no observation segment '" + name + "'");
}

}  // namespace manibench::testing
