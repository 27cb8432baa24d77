#include <manibench/learning/dataset.hpp>

#include <manibench/environment.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/sdk/random.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

namespace manibench::learning {

namespace {

std::string quoted(const std::string& path) { return "'" + path + "'"; }

// The dimensions of one trajectory's data; the set's must all agree.
struct Shape {
  uint32_t state_dim = 0, action_dim = 0, point_count = 0, mask_count = 0;
};

Shape getShape(const Trajectory& t, const std::string& where) {
  Shape s;
  s.state_dim = t.state_dim;
  s.action_dim = t.action_dim;
  s.mask_count = t.mask_count;
  if (t.mode == ObservationMode::PointCloud) {
    s.point_count = t.point_counts.empty() ? 0 : t.point_counts.front();
    for (uint32_t c : t.point_counts)
      if (c != s.point_count)
        throw LearningError(where + ": point clouds of different sizes (" + std::to_string(c) + " and " +
                            std::to_string(s.point_count) +
                            " points): the networks take clouds padded to one size (the default "
                            "D.1 sampling, observation.pointcloud.pad: true)");
  }
  return s;
}

std::string describeShape(const Shape& s) {
  std::string out = "state " + std::to_string(s.state_dim) + ", action " + std::to_string(s.action_dim);
  if (s.point_count) out += ", " + std::to_string(s.point_count) + " points x " + std::to_string(s.mask_count) + " masks";
  return out;
}

void checkShape(const Shape& expected, const Shape& got, const std::string& where, const std::string& first) {
  if (expected.state_dim == got.state_dim && expected.action_dim == got.action_dim &&
      expected.point_count == got.point_count && expected.mask_count == got.mask_count)
    return;
  throw LearningError("the layouts of " + first + " and " + where + " differ:\n  " + first + ": " +
                      describeShape(expected) + "\n  " + where + ": " + describeShape(got));
}

}  // namespace

// --- DataChunk -----------------------------------------------------------------------------

ObservationBatch DataChunk::gatherObservations(const torch::Tensor& rows, const NetOptions& inputs) const {
  ObservationBatch b;
  b.state = state.index_select(0, rows);
  if (inputs.hasExtraStateInputs()) {
    // As InputHistory builds them while acting.
    const torch::Tensor first = obs_first.index_select(0, rows);
    std::vector<torch::Tensor> parts{b.state};
    for (int64_t k = 1; k < inputs.history; ++k)
      parts.push_back(state.index_select(0, torch::max(rows - k, first)));
    for (int64_t k = 1; k <= inputs.action_history; ++k) {
      const torch::Tensor exists = rows - k >= first;
      const torch::Tensor transition = obs_transition.index_select(0, torch::max(rows - k, first));
      parts.push_back(actions.index_select(0, transition.clamp_min(0)) * exists.unsqueeze(1).to(torch::kFloat32));
    }
    if (inputs.step_input) parts.push_back(calcStepFeature((rows - first).to(torch::kFloat32)).unsqueeze(1));
    if (inputs.robot_frame.isEnabled()) parts.push_back(calcRobotFrameFeatures(inputs.robot_frame, b.state));
    b.state = torch::cat(parts, 1);
  }
  if (xyz.defined()) {
    b.xyz = xyz.index_select(0, rows);
    b.rgb = rgb.index_select(0, rows);
    const torch::Tensor masks = seg.index_select(0, rows);
    b.valid = calcValidPoints(b.xyz, b.rgb, masks);
    b.seg = masks.to(torch::kFloat32);
  }
  return b;
}

TransitionBatch DataChunk::gather(const torch::Tensor& index, bool with_next, const NetOptions& inputs) const {
  TransitionBatch b;
  const torch::Tensor rows = obs_index.index_select(0, index);
  b.obs = gatherObservations(rows, inputs);
  if (with_next) b.next_obs = gatherObservations(rows + 1, inputs);
  b.actions = actions.index_select(0, index);
  b.rewards = rewards.index_select(0, index);
  b.dones = dones.index_select(0, index);
  return b;
}

// --- DemoDataset ---------------------------------------------------------------------------

DemoDataset::DemoDataset(const DatasetOptions& options) : options_(options) {
  if (options.paths.empty()) throw LearningError("no demonstration file given (--demos FILE.h5)");
  std::map<std::string, uint32_t> per_object;
  for (std::size_t f = 0; f < options.paths.size(); ++f) {
    const std::string& path = options.paths[f];
    if (!std::filesystem::exists(path)) throw LearningError("no such demonstration file " + quoted(path));
    try {
      readers_.push_back(std::make_unique<DemoReader>(path));
    } catch (const std::exception& e) {
      throw LearningError("cannot read the demonstrations " + quoted(path) + ": " + e.what());
    }
    const DemoFileInfo& info = readers_.back()->getInfo();
    const DemoFileInfo& first = readers_.front()->getInfo();
    if (info.observation_mode == ObservationMode::Rgbd)
      throw LearningError(quoted(path) + " holds rgbd observations; the learning module trains on "
                          "state and pointcloud demonstrations (`manibench demos convert " + path +
                          " --obs pointcloud`)");
    auto differ = [&](const std::string& what, const std::string& a, const std::string& b) {
      throw LearningError("the demonstration files disagree on the " + what + ": " +
                          quoted(options.paths.front()) + " has " + a + ", " + quoted(path) + " has " + b);
    };
    if (info.task != first.task) differ("task", first.task, info.task);
    if (info.observation_mode != first.observation_mode)
      differ("observation mode", toString(first.observation_mode), toString(info.observation_mode));
    if (info.controller != first.controller) differ("controller", first.controller, info.controller);

    for (const std::string& name : readers_.back()->getTrajectoryNames()) {
      Trajectory summary;
      try {
        summary = readers_.back()->readSummary(name);
      } catch (const std::exception& e) {
        throw LearningError(e.what());
      }
      if (summary.steps == 0) continue;
      if (!options.objects.empty() &&
          std::find(options.objects.begin(), options.objects.end(), summary.object_id) == options.objects.end())
        continue;
      if (options.per_object && per_object[summary.object_id] >= options.per_object) continue;
      ++per_object[summary.object_id];
      trajectories_.push_back({f, name, summary.object_id, summary.steps});
      transitions_ += summary.steps;
    }
  }
  if (trajectories_.empty()) {
    std::string why = "no trajectory with steps in";
    for (const std::string& p : options.paths) why += " " + quoted(p);
    if (!options.objects.empty()) why += " for the objects asked for";
    throw LearningError(why);
  }
  // Every file's first selected trajectory fixes (and checks) the dimensions.
  Shape shape;
  std::string shape_source;
  std::vector<bool> seen(readers_.size(), false);
  for (const TrajectoryRef& ref : trajectories_) {
    if (seen[ref.file]) continue;
    seen[ref.file] = true;
    const std::string where = quoted(options.paths[ref.file]) + " (" + ref.name + ")";
    Shape s;
    try {
      s = getShape(readers_[ref.file]->read(ref.name, false), where);
    } catch (const LearningError&) {
      throw;
    } catch (const std::exception& e) {
      throw LearningError(e.what());
    }
    if (shape_source.empty()) {
      shape = s;
      shape_source = where;
    } else {
      checkShape(shape, s, where, shape_source);
    }
  }
  state_dim_ = shape.state_dim;
  action_dim_ = shape.action_dim;
  point_count_ = shape.point_count;
  mask_count_ = shape.mask_count;
}

DemoDataset::~DemoDataset() = default;

const DemoFileInfo& DemoDataset::getInfo() const { return readers_.front()->getInfo(); }

uint64_t DemoDataset::calcBytes(std::size_t i) const {
  const uint64_t steps = trajectories_[i].steps;
  const uint64_t per_obs = 4 * uint64_t(state_dim_) + uint64_t(point_count_) * (24 + mask_count_);
  return (steps + 1) * per_obs + steps * (4 * uint64_t(action_dim_) + 4 + 4 + 8);
}

uint64_t DemoDataset::calcTotalBytes() const {
  uint64_t total = 0;
  for (std::size_t i = 0; i < trajectories_.size(); ++i) total += calcBytes(i);
  return total;
}

DataChunk DemoDataset::load(const std::vector<std::size_t>& indices) const {
  int64_t observations = 0, transitions = 0;
  for (std::size_t i : indices) {
    observations += trajectories_[i].steps + 1;
    transitions += trajectories_[i].steps;
  }
  const bool points = point_count_ > 0;
  const int64_t n = point_count_, k = mask_count_;
  DataChunk c;
  c.state = torch::empty({observations, int64_t(state_dim_)}, torch::kFloat32);
  if (points) {
    c.xyz = torch::empty({observations, n, 3}, torch::kFloat32);
    c.rgb = torch::empty({observations, n, 3}, torch::kFloat32);
    c.seg = torch::empty({observations, n, k}, torch::kUInt8);
  }
  c.actions = torch::empty({transitions, int64_t(action_dim_)}, torch::kFloat32);
  c.rewards = torch::empty({transitions}, torch::kFloat32);
  c.dones = torch::empty({transitions}, torch::kFloat32);
  c.obs_index = torch::empty({transitions}, torch::kInt64);
  c.obs_first = torch::empty({observations}, torch::kInt64);
  c.obs_transition = torch::full({observations}, int64_t(-1), torch::kInt64);
  float* state = c.state.data_ptr<float>();
  float* actions = c.actions.data_ptr<float>();
  float* rewards = c.rewards.data_ptr<float>();
  float* dones = c.dones.data_ptr<float>();
  int64_t* obs_index = c.obs_index.data_ptr<int64_t>();
  int64_t* obs_first = c.obs_first.data_ptr<int64_t>();
  int64_t* obs_transition = c.obs_transition.data_ptr<int64_t>();
  int64_t o = 0, m = 0;
  for (std::size_t i : indices) {
    const TrajectoryRef& ref = trajectories_[i];
    const std::string where = quoted(options_.paths[ref.file]) + " (" + ref.name + ")";
    Trajectory t;
    try {
      t = readers_[ref.file]->read(ref.name, false);
    } catch (const std::exception& e) {
      throw LearningError(e.what());
    }
    checkShape({state_dim_, action_dim_, point_count_, mask_count_}, getShape(t, where), where,
               "the set");
    const int64_t obs = int64_t(t.steps) + 1;
    for (std::size_t j = 0; j < t.state.size(); ++j) state[o * state_dim_ + int64_t(j)] = float(t.state[j]);
    if (points) {
      std::memcpy(c.xyz.data_ptr<float>() + o * n * 3, t.xyz.data(), t.xyz.size() * sizeof(float));
      std::memcpy(c.rgb.data_ptr<float>() + o * n * 3, t.point_rgb.data(), t.point_rgb.size() * sizeof(float));
      std::memcpy(c.seg.data_ptr<uint8_t>() + o * n * k, t.point_masks.data(), t.point_masks.size());
    }
    const std::vector<double>& labels =
        t.policy_actions.empty() || options_.executed_actions ? t.actions : t.policy_actions;
    for (uint32_t s = 0; s < t.steps; ++s) {
      for (uint32_t a = 0; a < action_dim_; ++a)
        actions[(m + s) * action_dim_ + a] = float(std::clamp(labels[s * action_dim_ + a], -1.0, 1.0));
      rewards[m + s] = float(t.rewards[s]);
      dones[m + s] = t.terminated[s] ? 1.0f : 0.0f;
      obs_index[m + s] = o + s;
      obs_transition[o + s] = m + s;
    }
    for (int64_t s = 0; s < obs; ++s) obs_first[o + s] = o;
    o += obs;
    m += t.steps;
  }
  return c;
}

std::pair<torch::Tensor, torch::Tensor> DemoDataset::calcStateStatistics(const StateFeatures& features) const {
  torch::Tensor sum, squares;  // float64, over every observation
  uint64_t count = 0;
  std::vector<std::size_t> window;
  uint64_t bytes = 0;
  auto flush = [&] {
    if (window.empty()) return;
    const DataChunk c = load(window);
    const torch::Tensor s = (features ? features(c.state) : c.state).to(torch::kFloat64);
    sum = sum.defined() ? sum + s.sum(0) : s.sum(0);
    squares = squares.defined() ? squares + (s * s).sum(0) : (s * s).sum(0);
    count += uint64_t(s.size(0));
    window.clear();
    bytes = 0;
  };
  for (std::size_t i = 0; i < trajectories_.size(); ++i) {
    if (bytes + calcBytes(i) > options_.cache_bytes) flush();
    window.push_back(i);
    bytes += calcBytes(i);
  }
  flush();
  const torch::Tensor mean = sum / double(count);
  const torch::Tensor std = (squares / double(count) - mean * mean).clamp_min(0.0).sqrt();
  return {mean.to(torch::kFloat32), std.to(torch::kFloat32)};
}

void setSpecLayout(const Environment& env, ObservationSpec& spec) {
  const PolicyLayout layout = env.calcPolicyLayout();
  spec.state_dim = layout.observation_dim;
  spec.state_segments.clear();
  for (const sdk::Segment& s : layout.observation_segments)
    spec.state_segments.push_back({s.name, s.offset, s.size, s.description});
  spec.action_dim = layout.action_dim;
  spec.action_segments.clear();
  for (const sdk::Segment& s : layout.action_segments)
    spec.action_segments.push_back({s.name, s.offset, s.size});
}

ObservationSpec calcDemoSpec(const PluginRegistry& registry, const DemoDataset& dataset) {
  const DemoFileInfo& info = dataset.getInfo();
  ObservationSpec spec;
  spec.task = info.task;
  spec.mode = toString(info.observation_mode);
  spec.controller = info.controller;
  std::unique_ptr<Environment> env;
  try {
    env = makeDemoEnvironment(registry, info);
  } catch (const std::exception& e) {
    throw LearningError("cannot make the environment of " + quoted(dataset.getOptions().paths.front()) +
                        " (" + info.task + "): " + e.what());
  }
  setSpecLayout(*env, spec);
  spec.point_count = dataset.getPointCount();
  spec.mask_count = dataset.getMaskCount();
  if (spec.isPointCloud()) spec.mask_names = env->getTaskDescription().masks;
  if (spec.state_dim != dataset.getStateDim() || spec.action_dim != dataset.getActionDim())
    throw LearningError(quoted(dataset.getOptions().paths.front()) + " holds observations of " +
                        std::to_string(dataset.getStateDim()) + " values and actions of " +
                        std::to_string(dataset.getActionDim()) + ", but its environment's layout is " +
                        spec.describe());
  return spec;
}

// --- BatchSampler --------------------------------------------------------------------------

BatchSampler::BatchSampler(const DemoDataset& dataset, int64_t batch_size, uint64_t seed, bool with_next,
                           const NetOptions& inputs)
    : dataset_(dataset), batch_size_(batch_size), with_next_(with_next), inputs_(inputs) {
  if (batch_size <= 0) throw LearningError("the batch size must be positive");
  if (dataset.getTransitionCount() < uint64_t(batch_size))
    throw LearningError("the demonstrations hold " + std::to_string(dataset.getTransitionCount()) +
                        " transitions, fewer than a batch of " + std::to_string(batch_size));
  position_.epoch_seed = sdk::Random(seed ^ 0x6c6561726e696e67ULL).next();
  planEpoch();
}

void BatchSampler::planEpoch() {
  sdk::Random rng(position_.epoch_seed);
  const std::size_t count = dataset_.getTrajectories().size();
  std::vector<std::size_t> order(count);
  for (std::size_t i = 0; i < count; ++i) order[i] = i;
  windows_.clear();
  if (!dataset_.isStreamed()) {
    windows_.push_back(order);
  } else {
    for (std::size_t i = count; i > 1; --i) std::swap(order[i - 1], order[std::size_t(rng.next() % i)]);
    uint64_t bytes = 0, transitions = 0;
    for (std::size_t i : order) {
      const uint64_t b = dataset_.calcBytes(i);
      if (!windows_.empty() && bytes + b > dataset_.getOptions().cache_bytes &&
          transitions >= uint64_t(batch_size_)) {
        windows_.emplace_back();
        bytes = transitions = 0;
      }
      if (windows_.empty()) windows_.emplace_back();
      windows_.back().push_back(i);
      bytes += b;
      transitions += dataset_.getTrajectories()[i].steps;
    }
    // A last window too small for one batch joins the one before.
    if (windows_.size() > 1 && transitions < uint64_t(batch_size_)) {
      auto last = windows_.back();
      windows_.pop_back();
      windows_.back().insert(windows_.back().end(), last.begin(), last.end());
    }
  }
  window_first_batch_.assign(1, 0);
  for (const auto& w : windows_) {
    uint64_t transitions = 0;
    for (std::size_t i : w) transitions += dataset_.getTrajectories()[i].steps;
    window_first_batch_.push_back(window_first_batch_.back() + int64_t(transitions) / batch_size_);
  }
  batches_per_epoch_ = window_first_batch_.back();
  window_seeds_.clear();
  for (std::size_t w = 0; w < windows_.size(); ++w) window_seeds_.push_back(rng.next());
  next_epoch_seed_ = rng.next();
  loaded_window_ = SIZE_MAX;
}

void BatchSampler::loadWindow(std::size_t w) {
  if (!whole_set_loaded_) {
    chunk_ = DataChunk();  // release the previous window first
    chunk_ = dataset_.load(windows_[w]);
    whole_set_loaded_ = !dataset_.isStreamed();
  }
  const int64_t m = chunk_.getTransitionCount();
  order_.resize(std::size_t(m));
  for (int64_t i = 0; i < m; ++i) order_[std::size_t(i)] = i;
  sdk::Random rng(window_seeds_[w]);
  for (int64_t i = m; i > 1; --i) std::swap(order_[std::size_t(i - 1)], order_[rng.next() % uint64_t(i)]);
  loaded_window_ = w;
}

TransitionBatch BatchSampler::next() {
  if (position_.batch >= batches_per_epoch_) {
    position_.epoch_seed = next_epoch_seed_;
    ++position_.epoch;
    position_.batch = 0;
    planEpoch();
  }
  std::size_t w = 0;
  while (position_.batch >= window_first_batch_[w + 1]) ++w;
  if (loaded_window_ != w) loadWindow(w);
  const int64_t first = (position_.batch - window_first_batch_[w]) * batch_size_;
  const torch::Tensor index =
      torch::from_blob(order_.data() + first, {batch_size_}, torch::kInt64).clone();
  ++position_.batch;
  return chunk_.gather(index, with_next_, inputs_);
}

void BatchSampler::setPosition(const Position& position) {
  position_ = position;
  planEpoch();
}

}  // namespace manibench::learning
