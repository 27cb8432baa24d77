// Checkpoints: one file (libtorch's archive format) holding what a network
// was trained on and how (a YAML description: algorithm, network,
// ObservationSpec, iteration, training options), every network's
// parameters and buffers, and for resuming the optimizers' state and the
// random generators' (libtorch's and the batch sampler's), so that a
// resumed training continues bit for bit (tested).
#pragma once

#include <manibench/learning/algorithms.hpp>
#include <manibench/learning/spec.hpp>

#include <torch/torch.h>

#include <map>
#include <memory>
#include <string>

namespace manibench::learning {

inline constexpr int kCheckpointFormatVersion = 1;

struct CheckpointInfo {
  std::string path;
  int64_t iteration = 0;  // gradient steps taken
  AlgorithmOptions algorithm;
  NetOptions network;
  ObservationSpec spec;
  std::string training_yaml;  // the training's options, as `manibench train` wrote them
  std::string manibench_version;
};

// Writes `algorithm` (with its optimizers) and `extras` (named tensors:
// generator states) to `path`, through a temporary file renamed into place,
// so a run killed while saving leaves the previous checkpoint intact.
void saveCheckpoint(const std::string& path, const CheckpointInfo& info, const Algorithm& algorithm,
                    const std::map<std::string, torch::Tensor>& extras);

// The description alone. Throws LearningError naming the file when it is
// not a manibench checkpoint (a TorchScript file, say) or of another format.
CheckpointInfo readCheckpointInfo(const std::string& path);

struct LoadedCheckpoint {
  CheckpointInfo info;
  std::unique_ptr<Algorithm> algorithm;
  std::map<std::string, torch::Tensor> extras;  // those asked for
};
// The algorithm rebuilt from the description, its networks loaded (and the
// optimizers and `extras` when resuming).
LoadedCheckpoint loadCheckpoint(const std::string& path, const torch::Device& device, bool with_optimizers,
                                const std::vector<std::string>& extras = {});

}  // namespace manibench::learning
