#include "test_env.hpp"

namespace manibench::testing {

std::unique_ptr<Environment> makeEnvironment(const std::string& task, const std::vector<std::string>& overrides) {
  ConfigSources sources;
  sources.overrides = overrides;
  const ConfigNode config = loadTaskConfig(getBuildTreeRegistry(), task, sources);
  return std::make_unique<Environment>(getBuildTreeRegistry(), task, calcEnvironmentOptions(config));
}

ExpertSetup makeExpertSetup(const std::string& task, const std::string& policy,
                            const std::vector<std::string>& overrides) {
  std::vector<std::string> all = {"control.controller=mobile_panda_ee"};
  all.insert(all.end(), overrides.begin(), overrides.end());
  ExpertSetup s;
  s.env = makeEnvironment(task, all);
  s.expert = std::make_unique<PolicyInstance>(getBuildTreeRegistry(), policy, "",
                                              s.env->calcPolicyLayout(ObservationMode::State));
  return s;
}

}  // namespace manibench::testing
