// The torch_policy plugin: a policy that runs a `manibench train` checkpoint
// or a TorchScript file (docs/learning.md):
//   manibench eval TASK --policy torch_policy --policy-config run/policy.yaml
// with policy.yaml holding `checkpoint: PATH` or `torchscript: PATH`, and
// optionally `device: cpu|cuda` and `threads: N` (default 1: the
// evaluation kit runs one worker per core); or a population's
// population.yaml (train sac-population): each episode's object's agent.
//
// Why two libraries: every manibench command loads every plugin of the
// search path, and loading libtorch takes about a second (1.8 s measured on
// the 2-core development VM). This library links only the SDK; the half
// that links libtorch (runtime.cpp) is opened when a policy is created, in
// the process that runs it: in an evaluation, the forked worker, after the
// fork, so libtorch's OpenMP pool never starts in a process that forks.
#include <manibench/learning/runtime_entry.hpp>
#include <manibench/sdk.hpp>

#include <dlfcn.h>

#include <memory>
#include <string>

namespace sdk = manibench::sdk;

namespace {

// lib/manibench/libmanibench_learning_runtime.so, beside the plugin folder
// this library sits in (the build tree and an install share the layout).
std::string findRuntime() {
  Dl_info self;
  if (!dladdr(reinterpret_cast<void*>(&findRuntime), &self) || !self.dli_fname)
    throw sdk::Error("torch_policy: cannot find its own library", MB_ERROR);
  std::string dir = self.dli_fname;
  dir = dir.substr(0, dir.find_last_of('/'));  // .../lib/manibench/plugins
  dir = dir.substr(0, dir.find_last_of('/'));  // .../lib/manibench
  return dir + "/" + kManibenchLearningRuntimeFile;
}

ManibenchLearningMakePolicy openRuntime() {
  static ManibenchLearningMakePolicy make = [] {
    const std::string path = findRuntime();
    void* library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!library)
      throw sdk::Error(std::string("torch_policy: cannot load the learning runtime: ") + dlerror(), MB_ERROR);
    auto function = reinterpret_cast<ManibenchLearningMakePolicy>(dlsym(library, kManibenchLearningMakePolicy));
    if (!function)
      throw sdk::Error("torch_policy: " + path + " has no " + kManibenchLearningMakePolicy, MB_ERROR);
    return function;
  }();
  return make;
}

class TorchPolicy : public sdk::Policy {
 public:
  TorchPolicy(const sdk::Config& config, const sdk::PolicyContext& context) {
    YAML::Emitter text;
    text << config.node();
    char error[2048] = "";
    impl_.reset(openRuntime()(text.c_str(), &context, error, sizeof error));
    if (!impl_) throw sdk::Error(std::string("torch_policy: ") + error, MB_INVALID_ARGUMENT);
  }
  void reset(uint64_t seed) override { impl_->reset(seed); }
  void resetEpisode(const sdk::EpisodeInfo& episode) override { impl_->resetEpisode(episode); }
  Eigen::VectorXd act(const sdk::Observation& observation) override { return impl_->act(observation); }

 private:
  std::unique_ptr<sdk::Policy> impl_;
};

}  // namespace

MANIBENCH_REGISTER_POLICY(TorchPolicy, "torch_policy",
                          "runs a `manibench train` checkpoint or a TorchScript file (--policy-config)");
MANIBENCH_PLUGIN_LIBRARY("manibench_torch_policy", "1.0.0");
