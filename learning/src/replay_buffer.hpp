// SAC's replay buffer (sac_trainer.cpp): a ring of transitions as float32
// tensors, saved beside each checkpoint so that a resumed run samples what an
// uninterrupted one would.
#pragma once

#include <manibench/learning/algorithms.hpp>

#include <Eigen/Core>
#include <torch/torch.h>

#include <cstdint>
#include <filesystem>

namespace manibench::learning {

// Allocated at full capacity; the pages are touched only as it fills.
class ReplayBuffer {
 public:
  ReplayBuffer(int64_t capacity, int64_t state_dim, int64_t action_dim);

  int64_t size() const { return size_; }

  void add(const Eigen::VectorXd& obs, const float* action, double reward, const Eigen::VectorXd& next, bool done);
  // Uniform over what it holds, from libtorch's default generator.
  TransitionBatch sample(int64_t batch) const;

  // The filled part and the ring's position; written to a temporary file
  // renamed into place.
  void save(const std::filesystem::path& path) const;
  // A missing file, or one of another state width or larger than the
  // capacity, is a LearningError naming it.
  void load(const std::filesystem::path& path);

 private:
  int64_t capacity_, size_ = 0, position_ = 0;
  torch::Tensor obs_, next_obs_, actions_, rewards_, dones_;
};

}  // namespace manibench::learning
