// Environments of the build tree's plugins as the configuration makes them,
// for the tests of the families and the layers above config (links
// manibench::config and the registries).
#pragma once

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/plugin_instances.hpp>

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "test_registry.hpp"

namespace manibench::testing {

// `task` (or a fixed-object id) with its configuration layers and
// `overrides` (KEY=VALUE, as --set) on top.
std::unique_ptr<Environment> makeEnvironment(const std::string& task, const std::vector<std::string>& overrides = {});

// Resetting `object` with a seed after an episode of `other` gives the
// start that seed gave before (the episode does not depend on what ran).
void expectSameStartAfterAnotherObject(Environment& env, const std::string& object, const std::string& other);

// Steps `env` (reset already) with actions uniform in [-1, 1] drawn from
// `rng` until the episode ends; `each` sees every step's result. Returns
// the last one. (The families' "random flailing never succeeds" tests.)
StepResult runRandomEpisode(Environment& env, std::mt19937_64& rng,
                            const std::function<void(const StepResult&)>& each = {});

// A scripted expert and its environment: `task` with the mobile_panda_ee
// controller (`overrides` after it), `policy` on the state observation.
struct ExpertSetup {
  std::unique_ptr<Environment> env;
  std::unique_ptr<PolicyInstance> expert;
};
ExpertSetup makeExpertSetup(const std::string& task, const std::string& policy,
                            const std::vector<std::string>& overrides = {});

}  // namespace manibench::testing
