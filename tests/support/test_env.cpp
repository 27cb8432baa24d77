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

StepResult runRandomEpisode(Environment& env, std::mt19937_64& rng,
                            const std::function<void(const StepResult&)>& each) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd action(env.getControllerDescription().action_dim);
  StepResult r;
  do {
    for (Eigen::Index i = 0; i < action.size(); ++i) action[i] = u(rng);
    r = env.step(action);
    if (each) each(r);
  } while (!r.isDone());
  return r;
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
