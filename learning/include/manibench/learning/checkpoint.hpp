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

// The extras that hold libtorch's random states: the CPU generator's
// always, the CUDA device's when training ran on one (absent otherwise;
// loadCheckpoint skips it when asked for and missing).
inline constexpr const char* kCpuGeneratorExtra = "torch_generator";
inline constexpr const char* kCudaGeneratorExtra = "cuda_generator";
// Adds the default generators' states of the devices in use (the CPU and
// `device`) to `extras`, for a resume that continues bit for bit.
void addGeneratorStates(std::map<std::string, torch::Tensor>& extras, const torch::Device& device);
// Sets the default generators from what addGeneratorStates saved (the
// CUDA state only when `device` is CUDA and the checkpoint has one).
void restoreGeneratorStates(const std::map<std::string, torch::Tensor>& extras, const torch::Device& device);

// The description alone. Throws LearningError naming the file when it is
// not a manibench checkpoint (a TorchScript file, say) or of another format.
CheckpointInfo readCheckpointInfo(const std::string& path);

struct LoadedCheckpoint {
  CheckpointInfo info;
  std::unique_ptr<Algorithm> algorithm;
  std::map<std::string, torch::Tensor> extras;  // those asked for
};
// The algorithm rebuilt from the description on `device`, its networks
// loaded onto it whichever device they were saved from (and the optimizers
// and `extras`, on the CPU, when resuming). A missing extra is a
// LearningError, except kCudaGeneratorExtra.
LoadedCheckpoint loadCheckpoint(const std::string& path, const torch::Device& device, bool with_optimizers,
                                const std::vector<std::string>& extras = {});

}  // namespace manibench::learning
