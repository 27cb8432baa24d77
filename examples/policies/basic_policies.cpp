// Baseline policies for any task: `random` (uniform actions in [-1, 1],
// reproducible from the episode seed) and `zero` (always the zero action).
// The random actions come from sdk::Random, not a std:: distribution, whose
// output the standard leaves to each library: the same seed gives the same
// actions with every compiler.
#include <manibench/sdk.hpp>

namespace {

using manibench::sdk::Observation;
using manibench::sdk::PolicyContext;

class RandomPolicy : public manibench::sdk::Policy {
 public:
  explicit RandomPolicy(const PolicyContext& context) : action_dim_(context.action.dim) {}
  void reset(uint64_t seed) override { random_ = manibench::sdk::Random(seed); }
  Eigen::VectorXd act(const Observation&) override {
    Eigen::VectorXd action(action_dim_);
    for (Eigen::Index i = 0; i < action.size(); ++i) action[i] = random_.uniform(-1.0, 1.0);
    return action;
  }

 private:
  Eigen::Index action_dim_;
  manibench::sdk::Random random_{0};
};

class ZeroPolicy : public manibench::sdk::Policy {
 public:
  explicit ZeroPolicy(const PolicyContext& context) : action_dim_(context.action.dim) {}
  Eigen::VectorXd act(const Observation&) override { return Eigen::VectorXd::Zero(action_dim_); }

 private:
  Eigen::Index action_dim_;
};

}  // namespace

MANIBENCH_REGISTER_POLICY(RandomPolicy, "random", "uniform random actions in [-1, 1], seeded per episode");
MANIBENCH_REGISTER_POLICY(ZeroPolicy, "zero", "the zero action at every step");
MANIBENCH_PLUGIN_LIBRARY("manibench_example_policies", "0.1.0");
