#include "test_env.hpp"

namespace manibench::testing {

std::unique_ptr<Environment> makeEnvironment(const std::string& task, const std::vector<std::string>& overrides) {
  ConfigSources sources;
  sources.overrides = overrides;
  const ConfigNode config = loadTaskConfig(getBuildTreeRegistry(), task, sources);
  return std::make_unique<Environment>(getBuildTreeRegistry(), task, calcEnvironmentOptions(config));
}

void expectSameStartAfterAnotherObject(Environment& env, const std::string& object, const std::string& other) {
  env.reset(object, 5);
  const Eigen::VectorXd start = env.getObservation();
  env.reset(other, 1);
  env.reset(object, 5);
  EXPECT_EQ(start, env.getObservation()) << object << " after " << other;
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
