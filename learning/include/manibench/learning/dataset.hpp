// Demonstration files (docs/demonstrations.md) as training data: one or
// more files of one task, observation mode and controller, read through
// core's DemoReader into float32 tensors, and minibatches of transitions
// (obs, action, reward, next obs, done) shuffled with a fixed seed.
//
// What is cached: the observations, actions, rewards and dones of the
// selected trajectories (not their environment states), as float32 (masks
// as bytes): 4 S bytes per observation in the state mode, 4 S_agent +
// N (24 + K) in the pointcloud mode. When that exceeds the cache budget
// the set streams: every epoch shuffles the trajectory order, cuts it into
// windows of whole trajectories that fit the budget and shuffles within
// each window, so memory stays bounded by the budget (plus one window
// being read) whatever the files' size.
#pragma once

#include <manibench/demos.hpp>
#include <manibench/learning/algorithms.hpp>
#include <manibench/learning/spec.hpp>

#include <torch/torch.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace manibench {
class PluginRegistry;
}

namespace manibench::learning {

struct DatasetOptions {
  std::vector<std::string> paths;
  // Only these objects' trajectories (empty: every object's).
  std::vector<std::string> objects;
  // At most this many trajectories of each object, the first in file
  // order (0: all).
  uint32_t per_object = 0;
  uint64_t cache_bytes = uint64_t(8) << 30;
  // Files made with `demos generate --action-noise` hold the executed
  // (noisy) actions and the policy's own: the labels are the policy's
  // unless this asks for the executed ones.
  bool executed_actions = false;
};

struct TrajectoryRef {
  std::size_t file = 0;  // index into the paths
  std::string name;      // traj_N
  std::string object_id;
  uint32_t steps = 0;
};

// The observations and transitions of some trajectories, as tensors.
struct DataChunk {
  torch::Tensor state;          // [O, S] float32: every observation (T + 1 per trajectory)
  torch::Tensor xyz, rgb, seg;  // pointcloud: [O, N, 3], [O, N, 3] float32, [O, N, K] uint8
  torch::Tensor actions;        // [M, A] float32, clipped to [-1, 1]
  torch::Tensor rewards, dones;  // [M] float32
  torch::Tensor obs_index;      // [M] int64: transition i starts at observation obs_index[i]
  torch::Tensor obs_first;      // [O] int64: the first observation of each observation's trajectory
  torch::Tensor obs_transition; // [O] int64: the transition starting at each observation (-1: the last)
  int64_t getTransitionCount() const { return actions.size(0); }
  // The transitions `index` ([B] int64), with next observations if asked;
  // the state inputs as `inputs` asks (NetOptions::history, action_history, step_input).
  TransitionBatch gather(const torch::Tensor& index, bool with_next, const NetOptions& inputs) const;
  ObservationBatch gatherObservations(const torch::Tensor& obs_rows, const NetOptions& inputs) const;
};

class DemoDataset {
 public:
  // Opens the files and reads their descriptions and trajectory lists;
  // loads nothing yet. Throws LearningError for a file that cannot be
  // read, files that disagree (task, observation mode, controller; naming
  // both), an unsupported mode (rgbd), or a selection without trajectories.
  explicit DemoDataset(const DatasetOptions& options);
  ~DemoDataset();

  const DatasetOptions& getOptions() const { return options_; }
  const DemoFileInfo& getInfo() const;  // the first file's
  const std::vector<TrajectoryRef>& getTrajectories() const { return trajectories_; }
  uint64_t getTransitionCount() const { return transitions_; }
  uint64_t getObservationCount() const { return transitions_ + trajectories_.size(); }
  // The cached size of trajectory i.
  uint64_t calcBytes(std::size_t trajectory) const;
  uint64_t calcTotalBytes() const;
  bool isStreamed() const { return calcTotalBytes() > options_.cache_bytes; }
  uint32_t getStateDim() const { return state_dim_; }
  uint32_t getActionDim() const { return action_dim_; }
  uint32_t getPointCount() const { return point_count_; }
  uint32_t getMaskCount() const { return mask_count_; }

  // The trajectories `indices` (into getTrajectories()), in that order.
  DataChunk load(const std::vector<std::size_t>& indices) const;
  // Mean and standard deviation of each state feature over every
  // observation (reads the whole set once when it streams); of
  // `features(states)` ([O, S] -> [O, F]) when given.
  using StateFeatures = std::function<torch::Tensor(const torch::Tensor&)>;
  std::pair<torch::Tensor, torch::Tensor> calcStateStatistics(const StateFeatures& features = {}) const;

 private:
  DatasetOptions options_;
  std::vector<std::unique_ptr<DemoReader>> readers_;
  std::vector<TrajectoryRef> trajectories_;
  uint64_t transitions_ = 0;
  uint32_t state_dim_ = 0, action_dim_ = 0, point_count_ = 0, mask_count_ = 0;
};

// The set's ObservationSpec: its task, mode, controller and dimensions, and
// the layouts of the environment its configuration makes (which needs the
// task's plugin).
ObservationSpec calcDemoSpec(const PluginRegistry& registry, const DemoDataset& dataset);
// The state and action layouts of `env` (its own observation mode) into `spec`.
void setSpecLayout(const Environment& env, ObservationSpec& spec);

// Minibatches without replacement within an epoch (the last partial batch
// of each window is dropped), from a fully specified generator: the same
// seed gives the same batches everywhere. Its position is a small state
// that a checkpoint saves and restores.
class BatchSampler {
 public:
  BatchSampler(const DemoDataset& dataset, int64_t batch_size, uint64_t seed, bool with_next,
               const NetOptions& inputs = NetOptions());
  TransitionBatch next();

  struct Position {
    uint64_t epoch_seed = 0;  // the generator's state when the epoch began
    int64_t epoch = 0;
    int64_t batch = 0;        // batches taken in this epoch
  };
  Position getPosition() const { return position_; }
  void setPosition(const Position& position);
  int64_t getBatchesPerEpoch() const { return batches_per_epoch_; }

 private:
  void planEpoch();
  void loadWindow(std::size_t window);

  const DemoDataset& dataset_;
  int64_t batch_size_;
  bool with_next_;
  NetOptions inputs_;
  Position position_;
  uint64_t next_epoch_seed_ = 0;
  // This epoch: windows of trajectories, each window's transition order.
  std::vector<std::vector<std::size_t>> windows_;
  std::vector<int64_t> window_first_batch_;
  std::vector<uint64_t> window_seeds_;
  int64_t batches_per_epoch_ = 0;
  std::size_t loaded_window_ = SIZE_MAX;
  bool whole_set_loaded_ = false;
  DataChunk chunk_;
  std::vector<int64_t> order_;  // the loaded window's transitions, shuffled
};

}  // namespace manibench::learning
