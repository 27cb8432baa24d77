// Deterministic mutation fuzzing of the two loaders that read what users
// write: URDF (Scene::addUrdfString + finalize) and the YAML configuration
// (parseConfig, merge, validate, EnvironmentOptions). Seeds are real files
// of this repository; each input is a seed with a few mutations (bit flips,
// deletions, duplicated spans, hostile tokens). A loader may refuse an
// input with an exception; it must not crash, hang or leave the process
// unable to go on.
//
// `make test` runs a short smoke (a few seconds). For a long run:
//   MANIBENCH_FUZZ_SECONDS=600 build/bin/fuzz_test
// runs each target for that many seconds and prints the executions, the
// refusals and the slowest input (docs/robustness.md has the numbers).
#include <manibench/config.hpp>
#include <manibench/scene.hpp>
#include <manibench/sdk/random.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace manibench {
namespace {

const std::string kSourceDir = MANIBENCH_TEST_SOURCE_DIR;

using manibench::testing::readFile;

// The SDK's splitmix64: the same inputs on every run and machine (below()
// by the remainder, as the fuzz inputs were first drawn).
struct Random : manibench::sdk::Random {
  using manibench::sdk::Random::Random;
  std::size_t below(std::size_t n) { return n ? std::size_t(next() % n) : 0; }
};

std::string mutate(std::string text, Random& rng, const std::vector<std::string>& tokens) {
  const int count = 1 + int(rng.below(4));
  for (int m = 0; m < count && !text.empty(); ++m) {
    const std::size_t at = rng.below(text.size());
    switch (rng.below(6)) {
      case 0:  // flip a bit
        text[at] = char(text[at] ^ (1 << rng.below(8)));
        break;
      case 1:  // delete a span
        text.erase(at, 1 + rng.below(16));
        break;
      case 2: {  // duplicate a span somewhere else
        const std::string span = text.substr(at, 1 + rng.below(64));
        text.insert(rng.below(text.size()), span);
        break;
      }
      case 3:  // a hostile token
        text.insert(at, tokens[rng.below(tokens.size())]);
        break;
      case 4:  // replace a number's digit run with another number
        text.replace(at, 1 + rng.below(4), tokens[rng.below(tokens.size())]);
        break;
      default:  // cut short
        text.resize(at);
        break;
    }
  }
  return text;
}

struct FuzzStats {
  uint64_t executions = 0, refusals = 0;
  double slowest = 0;
};

// Runs `target` on mutations of `seeds` for `seconds` (or `minimum`
// executions, whichever is more): every input must return or throw a
// std::exception.
FuzzStats fuzz(const char* name, const std::vector<std::string>& seeds, const std::vector<std::string>& tokens,
               const std::function<void(const std::string&)>& target, uint64_t minimum) {
  double seconds = 0;
  if (const char* s = std::getenv("MANIBENCH_FUZZ_SECONDS")) seconds = std::atof(s);
  Random rng(0x5eed ^ std::hash<std::string>()(name));
  FuzzStats stats;
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  while (stats.executions < minimum || elapsed() < seconds) {
    const std::string input = mutate(seeds[rng.below(seeds.size())], rng, tokens);
    if (const char* last = std::getenv("MANIBENCH_FUZZ_LAST_INPUT")) {
      // Where to find the input a hang or a crash stopped at.
      std::ofstream(last, std::ios::binary) << input;
    }
    const auto t0 = std::chrono::steady_clock::now();
    try {
      target(input);
    } catch (const std::exception&) {
      ++stats.refusals;
    }
    stats.slowest =
        std::max(stats.slowest, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    ++stats.executions;
  }
  std::cout << name << ": " << stats.executions << " executions in " << elapsed() << " s, " << stats.refusals
            << " refused, slowest input " << stats.slowest << " s\n";
  return stats;
}

TEST(Fuzz, UrdfLoaderNeverCrashes) {
  const std::vector<std::string> seeds = {
      readFile(kSourceDir + "/tests/fixtures/partnet_mini/100001/mobility.urdf"),
      readFile(kSourceDir + "/assets/robots/mobile_panda_single.urdf"),
      R"(<?xml version="1.0"?><robot name="r"><link name="a"><inertial><mass value="1"/>
<inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial>
<collision><origin xyz="0 0 0.1" rpy="0 0 0"/><geometry><box size="0.1 0.2 0.3"/></geometry></collision>
<visual><geometry><cylinder radius="0.05" length="0.2"/></geometry></visual></link>
<link name="b"><inertial><mass value="0.5"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial>
<collision><geometry><sphere radius="0.05"/></geometry></collision></link>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.3"/>
<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="2"/><dynamics damping="0.1" friction="0.01"/></joint>
</robot>)"};
  const std::vector<std::string> tokens = {"nan", "inf", "-1e308", "1e308", "0", "-1", "<", ">", "&amp;", "\"",
                                           "<link name=\"a\"/>", "<joint name=\"j\" type=\"floating\">",
                                           "</robot>", "package://", "type=\"planar\"", "<mimic joint=\"j\"/>",
                                           std::string(1, '\0')};
  // Meshes resolve against either seed's folder (the robot's package://
  // paths through its ancestor folder).
  const std::string base_dirs[] = {kSourceDir + "/tests/fixtures/partnet_mini/100001",
                                   kSourceDir + "/assets/robots"};
  std::size_t round = 0;
  const FuzzStats stats = fuzz(
      "urdf", seeds, tokens,
      [&](const std::string& urdf) {
        Scene scene;
        scene.addGround(0);
        scene.addUrdfString(urdf, base_dirs[round++ % 2], "fuzzed", Pose(), true);
        scene.finalize();
      },
      300);
  EXPECT_GT(stats.refusals, 0u);  // the mutations do reach the checks
  EXPECT_LT(stats.refusals, stats.executions);
}

TEST(Fuzz, ConfigurationNeverCrashes) {
  const std::vector<std::string> seeds = {
      getBuiltinConfigText(),
      "physics:\n  integrator: implicit_euler\n  implicit_step: 2.0e-3\ncameras:\n  - name: top\n    far: 30\n"
      "task: {hold_steps: 3}\nobservation:\n  mode: pointcloud\n",
      "a: &x [1, 2, 3]\nb: *x\nc: {d: *x}\n"};
  const std::vector<std::string> tokens = {"nan", ".inf", "-1e308", "&a ", "*a", "[", "{", "]", "}", ": ",
                                           "\n  ", "- ", "!!binary ", "'", "\"", "<<: ", "~", "\t",
                                           std::string(1, '\0')};
  const FuzzStats stats = fuzz(
      "yaml", seeds, tokens,
      [](const std::string& yaml) {
        // What calcConfig does with a --config file.
        const ConfigNode layer = parseConfig(yaml, "fuzzed.yaml");
        validateConfig(layer);
        ConfigNode config = calcBuiltinConfig();
        if (!layer.isNull()) mergeConfig(config, layer);
        completeConfig(config);
        validateConfig(config);
        calcEnvironmentOptions(config);
      },
      500);
  EXPECT_GT(stats.refusals, 0u);
}

}  // namespace
}  // namespace manibench
