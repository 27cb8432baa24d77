// libmanibench_learning_runtime: the half of the torch_policy plugin that
// links libtorch (torch_policy.cpp opens it on first use). Turns the SDK's
// observation into the networks' batch and runs an InferencePolicy.
#include <manibench/learning/inference.hpp>
#include <manibench/learning/runtime_entry.hpp>
#include <manibench/sdk.hpp>

#include <cstring>
#include <map>

namespace manibench::learning {

namespace {

namespace sdk = manibench::sdk;

std::vector<SpecSegment> toSegments(const sdk::Layout& layout) {
  std::vector<SpecSegment> out;
  for (const sdk::Segment& s : layout.segments) out.push_back({s.name, s.offset, s.size, s.description});
  return out;
}

ObservationSpec makeHostSpec(const sdk::PolicyContext& context) {
  ObservationSpec spec;
  spec.task = context.task_name;
  spec.mode = context.observation_mode;
  spec.state_dim = context.observation.dim;
  spec.state_segments = toSegments(context.observation);
  spec.action_dim = context.action.dim;
  spec.action_segments = toSegments(context.action);
  return spec;
}

ObservationBatch makeBatch(const sdk::Observation& o) {
  ObservationBatch b;
  b.state = torch::empty({1, int64_t(o.state.size())}, torch::kFloat32);
  float* state = b.state.data_ptr<float>();
  for (Eigen::Index i = 0; i < o.state.size(); ++i) state[i] = float(o.state[i]);
  if (o.points_xyz.rows() > 0) {
    const int64_t n = o.points_xyz.rows(), k = o.mask_count;
    b.xyz = torch::from_blob(const_cast<float*>(o.points_xyz.data()), {1, n, 3}, torch::kFloat32).clone();
    b.rgb = torch::from_blob(const_cast<float*>(o.points_rgb.data()), {1, n, 3}, torch::kFloat32).clone();
    torch::Tensor seg = torch::zeros({1, n, k}, torch::kUInt8);
    if (k > 0 && o.points_mask.rows() == n)
      std::memcpy(seg.data_ptr<uint8_t>(), o.points_mask.data(), std::size_t(n * k));
    b.valid = calcValidPoints(b.xyz, b.rgb, seg);
    b.seg = seg.to(torch::kFloat32);
  }
  return b;
}

InferenceOptions readInferenceOptions(const sdk::Config& config) {
  InferenceOptions options;
  options.checkpoint = config.get<std::string>("checkpoint", "");
  options.torchscript = config.get<std::string>("torchscript", "");
  options.device = config.get<std::string>("device", "cpu");
  options.threads = config.get<int>("threads", 1);
  return options;
}

// One agent, or a population's (train sac-population's population.yaml:
// `objects: {ID: {policy_config: ID's policy.yaml, ...}}`), each episode
// acted by its object's agent, loaded on its object's first episode.
class TorchPolicy : public sdk::Policy {
 public:
  TorchPolicy(const sdk::Config& config, const sdk::PolicyContext& context) : host_(makeHostSpec(context)) {
    if (!config.has("objects")) {
      config.requireKnownKeys({"checkpoint", "torchscript", "device", "threads"}, "torch_policy");
      own_ = loadInferencePolicy(readInferenceOptions(config), host_);
      policy_ = own_.get();
      return;
    }
    const YAML::Node objects = config.node()["objects"];
    if (!objects.IsMap()) throw sdk::Error("torch_policy: the population's objects are not a map", MB_INVALID_ARGUMENT);
    for (const auto& entry : objects) {
      const std::string id = entry.first.as<std::string>();
      const YAML::Node policy_config = entry.second["policy_config"];
      agent_configs_[id] = policy_config ? policy_config.as<std::string>() : "";
    }
  }
  void reset(uint64_t seed) override {
    if (!policy_ || !agent_configs_.empty())
      throw sdk::Error("torch_policy: a population needs each episode's object, which this host does not pass "
                       "(ABI 1.5's reset_episode)",
                       MB_UNSUPPORTED);
    policy_->reset(seed);
  }
  void resetEpisode(const sdk::EpisodeInfo& episode) override {
    if (!agent_configs_.empty()) policy_ = &findAgent(episode.object_id);
    policy_->reset(episode.seed);
  }
  Eigen::VectorXd act(const sdk::Observation& o) override {
    const torch::Tensor action = policy_->act(makeBatch(o)).contiguous();
    Eigen::VectorXd out(action.size(0));
    const float* a = action.data_ptr<float>();
    for (Eigen::Index i = 0; i < out.size(); ++i) out[i] = double(a[i]);
    return out;
  }

 private:
  InferencePolicy& findAgent(const std::string& object) {
    const auto loaded = agents_.find(object);
    if (loaded != agents_.end()) return *loaded->second;
    const auto config = agent_configs_.find(object);
    if (config == agent_configs_.end())
      throw sdk::Error("torch_policy: object '" + object + "' is not in the population", MB_INVALID_ARGUMENT);
    if (config->second.empty())
      throw sdk::Error("torch_policy: object '" + object + "' has no agent yet (its training is pending)",
                       MB_INVALID_ARGUMENT);
    YAML::Node node;
    try {
      node = YAML::LoadFile(config->second);
    } catch (const YAML::Exception& e) {
      throw sdk::Error("torch_policy: object '" + object + "': cannot read " + config->second + ": " + e.what(),
                       MB_INVALID_ARGUMENT);
    }
    const sdk::Config agent(node);
    agent.requireKnownKeys({"checkpoint", "torchscript", "device", "threads"}, config->second);
    return *(agents_[object] = loadInferencePolicy(readInferenceOptions(agent), host_));
  }

  ObservationSpec host_;
  std::unique_ptr<InferencePolicy> own_;
  std::map<std::string, std::string> agent_configs_;                     // a population's: object -> policy.yaml
  std::map<std::string, std::unique_ptr<InferencePolicy>> agents_;  // those loaded
  InferencePolicy* policy_ = nullptr;                                    // this episode's
};

}  // namespace

}  // namespace manibench::learning

extern "C" manibench::sdk::Policy* manibench_learning_make_policy(const char* config_yaml,
                                                                  const manibench::sdk::PolicyContext* context,
                                                                  char* error, std::size_t error_size) {
  try {
    return new manibench::learning::TorchPolicy(manibench::sdk::Config(config_yaml), *context);
  } catch (const c10::Error& e) {
    std::snprintf(error, error_size, "%s", e.what_without_backtrace());
  } catch (const std::exception& e) {
    std::snprintf(error, error_size, "%s", e.what());
  }
  return nullptr;
}
