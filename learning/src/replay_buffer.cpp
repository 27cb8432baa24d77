#include "replay_buffer.hpp"

#include <manibench/learning/spec.hpp>

#include <algorithm>

namespace manibench::learning {

namespace fs = std::filesystem;

ReplayBuffer::ReplayBuffer(int64_t capacity, int64_t state_dim, int64_t action_dim)
    : capacity_(capacity),
      obs_(torch::empty({capacity, state_dim})),
      next_obs_(torch::empty({capacity, state_dim})),
      actions_(torch::empty({capacity, action_dim})),
      rewards_(torch::empty({capacity})),
      dones_(torch::empty({capacity})) {}

void ReplayBuffer::add(const Eigen::VectorXd& obs, const float* action, double reward, const Eigen::VectorXd& next,
                       bool done) {
  float* o = obs_[position_].data_ptr<float>();
  float* n = next_obs_[position_].data_ptr<float>();
  for (Eigen::Index i = 0; i < obs.size(); ++i) {
    o[i] = float(obs[i]);
    n[i] = float(next[i]);
  }
  std::copy(action, action + actions_.size(1), actions_[position_].data_ptr<float>());
  rewards_[position_] = float(reward);
  dones_[position_] = done ? 1.0f : 0.0f;
  position_ = (position_ + 1) % capacity_;
  size_ = std::min(size_ + 1, capacity_);
}

TransitionBatch ReplayBuffer::sample(int64_t batch) const {
  const torch::Tensor index = torch::randint(size_, {batch}, torch::kInt64);
  TransitionBatch b;
  b.obs.state = obs_.index_select(0, index);
  b.next_obs.state = next_obs_.index_select(0, index);
  b.actions = actions_.index_select(0, index);
  b.rewards = rewards_.index_select(0, index);
  b.dones = dones_.index_select(0, index);
  return b;
}

void ReplayBuffer::save(const fs::path& path) const {
  torch::serialize::OutputArchive archive;
  // Copies of the filled part: a slice would write the whole storage.
  archive.write("obs", obs_.slice(0, 0, size_).clone());
  archive.write("next_obs", next_obs_.slice(0, 0, size_).clone());
  archive.write("actions", actions_.slice(0, 0, size_).clone());
  archive.write("rewards", rewards_.slice(0, 0, size_).clone());
  archive.write("dones", dones_.slice(0, 0, size_).clone());
  archive.write("position", torch::tensor({position_}, torch::kInt64));
  const std::string temporary = path.string() + ".tmp";
  archive.save_to(temporary);
  fs::rename(temporary, path);
}

void ReplayBuffer::load(const fs::path& path) {
  if (!fs::exists(path)) throw LearningError("the replay buffer '" + path.string() + "' is missing");
  torch::serialize::InputArchive archive;
  archive.load_from(path.string());
  // A fresh tensor per read: reading into a defined tensor re-points it
  // (Tensor::set_), whatever its type.
  auto read = [&](const char* key) {
    torch::Tensor t;
    archive.read(key, t);
    return t;
  };
  const torch::Tensor obs = read("obs");
  size_ = obs.size(0);
  if (size_ > capacity_ || obs.size(1) != obs_.size(1))
    throw LearningError("the replay buffer '" + path.string() + "' does not fit this training's");
  obs_.slice(0, 0, size_).copy_(obs);
  next_obs_.slice(0, 0, size_).copy_(read("next_obs"));
  actions_.slice(0, 0, size_).copy_(read("actions"));
  rewards_.slice(0, 0, size_).copy_(read("rewards"));
  dones_.slice(0, 0, size_).copy_(read("dones"));
  position_ = read("position")[0].item<int64_t>();
}

}  // namespace manibench::learning
