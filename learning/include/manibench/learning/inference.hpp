// A trained policy acting one observation at a time: a manibench checkpoint
// (any algorithm: BC and TD3+BC run their actor, BCQ picks the best of its
// sampled actions) or a TorchScript module written by torch.jit.save in
// Python (python3-torch shares Debian's libtorch). What the policy plugin
// (learning/policy) runs, and the tests compare it with.
//
// A TorchScript module's forward takes one argument, a Dict[str, Tensor]
// of the observation with a batch dimension of 1, and returns the action
// ([1, A] or [A]):
//   state mode:      "state" [1, D] float32
//   pointcloud mode: "agent" [1, D] float32, "xyz" [1, N, 3] float32,
//                    "rgb" [1, N, 3] float32, "seg" [1, N, K] uint8
// (the names and types of a demonstration file's datasets).
#pragma once

#include <manibench/learning/networks.hpp>
#include <manibench/learning/spec.hpp>

#include <torch/torch.h>

#include <cstdint>
#include <memory>
#include <string>

namespace manibench::learning {

struct InferenceOptions {
  std::string checkpoint;   // a manibench checkpoint, or
  std::string torchscript;  // a TorchScript file
  std::string device = "cpu";
  int threads = 1;
};

class InferencePolicy {
 public:
  virtual ~InferencePolicy() = default;
  // Seeds the samples of a stochastic policy (BCQ).
  virtual void reset(uint64_t seed) = 0;
  // One observation (batch of 1) -> the action [A] (float32, on the CPU).
  virtual torch::Tensor act(const ObservationBatch& obs) = 0;
  virtual std::string describe() const = 0;
};

// Loads the policy for the environment the host describes (`host`: task,
// mode, layouts; its point count may be 0 = unknown). A checkpoint of
// another task, mode or layout is a LearningError naming both; so is a
// TorchScript module whose output has the wrong size (at the first act).
std::unique_ptr<InferencePolicy> loadInferencePolicy(const InferenceOptions& options,
                                                     const ObservationSpec& host);

}  // namespace manibench::learning
