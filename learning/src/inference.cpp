#include <manibench/learning/checkpoint.hpp>
#include <manibench/learning/compute.hpp>
#include <manibench/learning/inference.hpp>

#include <torch/script.h>

#include <filesystem>

namespace manibench::learning {

namespace {

void checkPoints(const ObservationSpec& expected, const ObservationBatch& obs, const std::string& what) {
  if (!expected.isPointCloud()) return;
  if (!obs.hasPoints()) throw LearningError(what + " takes point clouds; the observation has none");
  if (expected.point_count && (obs.xyz.size(1) != expected.point_count || obs.seg.size(2) != expected.mask_count))
    throw LearningError(what + " was trained on clouds of " + std::to_string(expected.point_count) +
                        " points and " + std::to_string(expected.mask_count) + " masks; the observation has " +
                        std::to_string(obs.xyz.size(1)) + " points and " + std::to_string(obs.seg.size(2)) +
                        " masks");
}

class CheckpointPolicy : public InferencePolicy {
 public:
  CheckpointPolicy(const InferenceOptions& options, const ObservationSpec& host)
      : device_(parseDevice(options.device)), generator_(at::detail::createCPUGenerator(0)) {
    loaded_ = loadCheckpoint(options.checkpoint, device_, false);
    loaded_.info.spec.checkSame(host, "the checkpoint '" + options.checkpoint + "'", "the environment");
    history_ = std::make_unique<InputHistory>(loaded_.info.network, loaded_.info.spec);
    name_ = "checkpoint '" + options.checkpoint + "' (" + loaded_.info.algorithm.name + ", " +
            toString(loaded_.info.network.kind) + ", iteration " + std::to_string(loaded_.info.iteration) + ")";
  }
  void reset(uint64_t seed) override {
    generator_.set_current_seed(seed);
    c10::InferenceMode inference;  // the history holds act()'s tensors, which only it may change in place
    history_->reset();
    step_ = 0;
  }
  torch::Tensor act(const ObservationBatch& obs) override {
    checkPoints(loaded_.info.spec, obs, "the " + name_);
    if (obs.state.size(1) != loaded_.info.spec.state_dim)
      throw LearningError("the " + name_ + " takes a state of " + std::to_string(loaded_.info.spec.state_dim) +
                          " values; the observation has " + std::to_string(obs.state.size(1)));
    // No autograd state at all (not even the version counters NoGradGuard
    // keeps): the tensors made here never meet a gradient.
    c10::InferenceMode inference;
    ObservationBatch input = obs;
    input.state = history_->makeInput(obs.state, step_);
    ++step_;
    const torch::Tensor action = loaded_.algorithm->act(input.to(device_), generator_).to(torch::kCPU).squeeze(0);
    history_->setAction(action);
    return action;
  }
  std::string describe() const override { return name_; }

 private:
  torch::Device device_;
  LoadedCheckpoint loaded_;
  std::unique_ptr<InputHistory> history_;
  int64_t step_ = 0;  // of the episode (reset() starts one; act() is called once per step)
  at::Generator generator_;
  std::string name_;
};

class TorchScriptPolicy : public InferencePolicy {
 public:
  TorchScriptPolicy(const InferenceOptions& options, const ObservationSpec& host)
      : device_(parseDevice(options.device)), host_(host), path_(options.torchscript) {
    if (!std::filesystem::exists(path_)) throw LearningError("no such TorchScript file '" + path_ + "'");
    if (host.mode != "state" && host.mode != "pointcloud")
      throw LearningError("a TorchScript policy takes the state or pointcloud mode, not " + host.mode);
    try {
      module_ = torch::jit::load(path_, device_);
    } catch (const c10::Error& e) {
      throw LearningError("'" + path_ + "' is not a TorchScript file libtorch can load (" +
                          e.what_without_backtrace() + ")");
    }
    module_.eval();
  }
  void reset(uint64_t seed) override { torch::manual_seed(seed); }
  torch::Tensor act(const ObservationBatch& obs) override {
    torch::NoGradGuard no_grad;
    c10::Dict<std::string, torch::Tensor> input;
    if (obs.hasPoints()) {
      input.insert("agent", obs.state.to(device_));
      input.insert("xyz", obs.xyz.to(device_));
      input.insert("rgb", obs.rgb.to(device_));
      input.insert("seg", obs.seg.to(torch::kUInt8).to(device_));
    } else {
      input.insert("state", obs.state.to(device_));
    }
    torch::Tensor action;
    try {
      const c10::IValue out = module_.forward({input});
      if (!out.isTensor()) throw LearningError("'" + path_ + "': forward() returned no tensor");
      action = out.toTensor();
    } catch (const c10::Error& e) {
      throw LearningError("'" + path_ + "': forward() failed: " + e.what_without_backtrace());
    }
    action = action.to(torch::kCPU).to(torch::kFloat32).reshape({-1});
    if (action.size(0) != host_.action_dim)
      throw LearningError("'" + path_ + "': forward() returned " + std::to_string(action.size(0)) +
                          " values; the action has " + std::to_string(host_.action_dim));
    return action;
  }
  std::string describe() const override { return "TorchScript '" + path_ + "'"; }

 private:
  torch::Device device_;
  ObservationSpec host_;
  std::string path_;
  torch::jit::Module module_;  // not jit::script::Module: an alias kept only for compatibility
};

}  // namespace

std::unique_ptr<InferencePolicy> loadInferencePolicy(const InferenceOptions& options, const ObservationSpec& host) {
  if (options.checkpoint.empty() == options.torchscript.empty())
    throw LearningError("the policy configuration names one of `checkpoint:` (a manibench checkpoint) "
                        "and `torchscript:` (a file written by torch.jit.save)");
  setComputeThreads(options.threads);
  // A point-cloud network's activations are megabytes (BCQ's 100 sampled
  // clouds: about 90 MB per layer), which glibc maps fresh and unmaps on
  // every call: page faults and zeroing, not arithmetic, were most of an
  // act (bench/learning_speed.cpp --act; docs/learning-results.md). Kept
  // freed, the next call reuses them. Only the allocator's behaviour
  // changes, not one computed value (the environment's physics included).
  setKeepFreedMemory();
  if (!options.checkpoint.empty()) return std::make_unique<CheckpointPolicy>(options, host);
  return std::make_unique<TorchScriptPolicy>(options, host);
}

}  // namespace manibench::learning
