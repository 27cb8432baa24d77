#include <manibench/learning/checkpoint.hpp>
#include <manibench/learning/compute.hpp>
#include <manibench/learning/trainer.hpp>

#include "training_files.hpp"

#include <manibench/evaluation.hpp>

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <future>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace manibench::learning {

namespace fs = std::filesystem;

// --- options ------------------------------------------------------------------------------

void TrainOptions::check() const {
  checkRun();
  if (iterations <= 0) throw LearningError("--iterations must be positive");
}

void TrainOptions::writeYaml(YAML::Node& node) const {
  writeRun(node);
  YAML::Node d;
  d["paths"] = data.paths;
  d["objects"] = data.objects;
  d["per_object"] = data.per_object;
  d["cache_bytes"] = data.cache_bytes;
  d["executed_actions"] = data.executed_actions;
  node["data"] = d;
  node["iterations"] = iterations;
  node["prefetch"] = prefetch;
  node["normalize_state"] = normalize_state;
  YAML::Node e = node["evaluation"];
  e["task"] = eval_task;
  e["split"] = eval_split;
  e["objects"] = eval_objects;
  e["workers"] = eval_workers;
  e["device"] = eval_device;
}

TrainOptions TrainOptions::readYaml(const YAML::Node& node) {
  TrainOptions o;
  o.readRun(node);
  const YAML::Node d = node["data"];
  o.data.paths = d["paths"].as<std::vector<std::string>>();
  o.data.objects = d["objects"].as<std::vector<std::string>>(std::vector<std::string>());
  o.data.per_object = d["per_object"].as<uint32_t>();
  o.data.cache_bytes = d["cache_bytes"].as<uint64_t>();
  o.data.executed_actions = d["executed_actions"].as<bool>(false);
  o.iterations = node["iterations"].as<int64_t>();
  o.prefetch = node["prefetch"].as<bool>(false);
  o.normalize_state = node["normalize_state"].as<bool>();
  const YAML::Node e = node["evaluation"];
  o.eval_task = e["task"].as<std::string>();
  o.eval_split = e["split"].as<std::string>();
  o.eval_objects = e["objects"].as<std::vector<std::string>>(std::vector<std::string>());
  o.eval_workers = e["workers"].as<unsigned>();
  // Top level before RunOptions (and absent before it was an option).
  o.eval_device = e["device"].as<std::string>(node["eval_device"].as<std::string>("cpu"));
  return o;
}

// --- the loop -----------------------------------------------------------------------------

namespace {

// The training's batches, on its device. Without prefetching each is
// gathered when the step asks for it. With it (always on CUDA; --prefetch
// on the CPU, where it competes with the step for the cores) the next batch
// is gathered in another thread while the current one trains, into pinned
// memory on CUDA, and copied without blocking the host, so a GPU does not
// wait for the CPU's gather between steps. The batches are the same either
// way: the sampler is only ever called by one thread at a time, in order.
class BatchFeed {
 public:
  BatchFeed(BatchSampler& sampler, const torch::Device& device, bool prefetch)
      : sampler_(sampler), device_(device), prefetch_(prefetch || device.is_cuda()),
        consumed_(sampler.getPosition()) {}
  ~BatchFeed() {
    if (ahead_.valid()) ahead_.wait();
  }
  BatchFeed(const BatchFeed&) = delete;
  BatchFeed& operator=(const BatchFeed&) = delete;

  TransitionBatch next() {
    if (!prefetch_) {
      TransitionBatch batch = sampler_.next();
      consumed_ = sampler_.getPosition();
      return batch.to(device_);
    }
    if (!ahead_.valid()) ahead_ = gatherAhead();
    auto [batch, position] = ahead_.get();
    consumed_ = position;
    ahead_ = gatherAhead();
    return batch.to(device_, /*non_blocking=*/device_.is_cuda());
  }
  // The sampler's position after the batches next() returned (what a
  // checkpoint records: the one gathered ahead is gathered again on resume).
  BatchSampler::Position getPosition() const { return consumed_; }

 private:
  std::future<std::pair<TransitionBatch, BatchSampler::Position>> gatherAhead() {
    return std::async(std::launch::async, [this] {
      TransitionBatch batch = sampler_.next();
      if (device_.is_cuda()) batch = batch.map([](const torch::Tensor& t) { return t.pin_memory(); });
      return std::make_pair(std::move(batch), sampler_.getPosition());
    });
  }

  BatchSampler& sampler_;
  torch::Device device_;
  bool prefetch_;
  BatchSampler::Position consumed_;
  std::future<std::pair<TransitionBatch, BatchSampler::Position>> ahead_;
};

class Trainer {
 public:
  Trainer(const PluginRegistry& registry, const TrainOptions& options, const TrainHooks& hooks)
      : options_(options), hooks_(hooks), dir_(options.out_dir), device_(parseDevice(options.device)) {
    setUpTrainingCompute(options.threads);
    say(describeCompute(calcComputeInfo(), device_));
    dataset_ = std::make_unique<DemoDataset>(options.data);
    spec_ = calcDemoSpec(registry, *dataset_);
    if (options_.pick_network) {
      options_.network.kind = spec_.isPointCloud() ? NetKind::PnTransformer : NetKind::Mlp;
      options_.pick_network = false;
    }
    const AlgorithmOptions for_mode = AlgorithmOptions::makeDefaults(options_.algorithm.name, spec_.mode);
    if (options_.pick_lr) options_.algorithm.lr = for_mode.lr;
    if (options_.pick_weight_decay) options_.algorithm.weight_decay = for_mode.weight_decay;
    options_.pick_lr = options_.pick_weight_decay = false;
    if (options_.robot_frame) {
      options_.network.robot_frame = planRobotFrameInputs(spec_);
      options_.robot_frame = false;  // from now on the network's options carry it
    }
    if (options_.network.robot_frame.isEnabled())
      say("robot-frame inputs: " + options_.network.robot_frame.describe());
    say("demonstrations: " + std::to_string(dataset_->getTrajectories().size()) + " trajectories, " +
        std::to_string(dataset_->getTransitionCount()) + " transitions, " +
        std::to_string(dataset_->calcTotalBytes() >> 20) + " MiB as tensors (" +
        (dataset_->isStreamed() ? "streamed: more than the cache of " : "cached in memory; cache ") +
        std::to_string(options.data.cache_bytes >> 20) + " MiB); " + spec_.describe());
  }

  TrainResult start() {
    if (fs::exists(dir_ / "train.yaml"))
      throw LearningError("'" + dir_.string() + "' holds a training already: continue it with --resume " +
                          dir_.string() + ", or choose another --out");
    fs::create_directories(dir_ / "checkpoints");
    YAML::Node node;
    options_.writeYaml(node);
    writeText(dir_ / "train.yaml", yamlText(node));
    writeText(dir_ / "environment.yaml", dataset_->getInfo().config);
    torch::manual_seed(options_.seed);
    algorithm_ = makeAlgorithm(options_.algorithm, options_.network, spec_, device_);
    if (options_.normalize_state) setStateNormalization();
    sampler_ = std::make_unique<BatchSampler>(*dataset_, options_.algorithm.batch_size, options_.seed,
                                              algorithm_->needsNextObservations(), options_.network);
    for (const auto& [name, network] : algorithm_->getNetworks())
      say("network " + name + ": " + toString(options_.network.kind) + ", " +
          std::to_string(countParameters(*network)) + " parameters");
    writeCsvHeaders();
    return run(0);
  }

  // (s - mean) / std per feature of the state and of its robot-frame
  // features, every stacked observation alike; actions and the step as they are.
  void setStateNormalization() {
    const RobotFrameInputs& frame = options_.network.robot_frame;
    auto [mean, std] = dataset_->calcStateStatistics([&](const torch::Tensor& states) {
      return frame.isEnabled() ? torch::cat({states, calcRobotFrameFeatures(frame, states)}, 1) : states;
    });
    const int64_t state_dim = spec_.state_dim, frame_dim = frame.calcDim();
    torch::Tensor scale = torch::where(std > 1e-6, 1.0 / std, torch::ones_like(std));
    const int64_t history = options_.network.history;
    const int64_t rest = calcInputStateDim(options_.network, spec_) - history * state_dim - frame_dim;
    auto arrange = [&](const torch::Tensor& v, double other) {
      return torch::cat({v.slice(0, 0, state_dim).repeat({history}), torch::full({rest}, other),
                         v.slice(0, state_dim)});
    };
    algorithm_->setStateNormalization(arrange(mean, 0.0).to(device_), arrange(scale, 1.0).to(device_));
  }

  TrainResult resume(int64_t iterations) {
    const std::string newest = findNewestCheckpoint(dir_.string());
    if (newest.empty()) throw LearningError("'" + dir_.string() + "' has no checkpoint to resume from");
    LoadedCheckpoint loaded =
        loadCheckpoint(newest, device_, true, {kCpuGeneratorExtra, kCudaGeneratorExtra, "sampler", "log_row"});
    loaded.info.spec.checkSame(spec_, "the checkpoint '" + newest + "'", "the demonstrations");
    algorithm_ = std::move(loaded.algorithm);
    if (iterations > 0) options_.iterations = iterations;
    YAML::Node node;
    options_.writeYaml(node);
    writeText(dir_ / "train.yaml", yamlText(node));
    restoreGeneratorStates(loaded.extras, device_);
    sampler_ = std::make_unique<BatchSampler>(*dataset_, options_.algorithm.batch_size, options_.seed,
                                              algorithm_->needsNextObservations(), options_.network);
    const torch::Tensor s = loaded.extras.at("sampler");
    sampler_->setPosition({uint64_t(s[0].item<int64_t>()), s[1].item<int64_t>(), s[2].item<int64_t>()});
    log_row_ = loaded.extras.at("log_row");
    truncateCsv(dir_ / "log.csv", loaded.info.iteration);
    // The evaluation this checkpoint was in when the run stopped or was
    // killed runs again (its row, if the kill came after it, goes first).
    const bool pending = hooks_.evaluate && findPendingEvaluation(dir_) == loaded.info.iteration;
    truncateCsv(dir_ / "eval.csv", loaded.info.iteration - (pending ? 1 : 0));
    say("resuming from " + newest + " (iteration " + std::to_string(loaded.info.iteration) + ")");
    if (pending && !evaluate(loaded.info.iteration)) {
      TrainResult result;
      result.iteration = loaded.info.iteration;
      result.interrupted = true;
      result.checkpoint = newest;
      return result;
    }
    return run(loaded.info.iteration);
  }

 private:
  void say(const std::string& line) {
    if (hooks_.on_message) hooks_.on_message(line);
  }

  void writeCsvHeaders() {
    std::ofstream log(dir_ / "log.csv");
    log << "iteration,seconds";
    for (const std::string& name : algorithm_->getLossNames()) log << "," << name;
    log << ",iterations_per_second\n";
    std::ofstream eval(dir_ / "eval.csv");
    eval << "iteration,split,episodes,successes,success_rate\n";
  }

  std::string saveCheckpointAt(int64_t iteration) {
    YAML::Node node;
    options_.writeYaml(node);
    const CheckpointInfo info = describeCheckpoint(iteration, options_, spec_, node);
    const BatchSampler::Position p = feed_ ? feed_->getPosition() : sampler_->getPosition();
    const torch::Tensor sampler = torch::tensor({int64_t(p.epoch_seed), p.epoch, p.batch}, torch::kInt64);
    const fs::path path = fs::absolute(dir_ / "checkpoints" / checkpointName(iteration));
    std::map<std::string, torch::Tensor> extras{{"sampler", sampler}, {"log_row", log_row_}};
    addGeneratorStates(extras, device_);
    saveCheckpoint(path.string(), info, *algorithm_, extras);
    writePolicyConfig(dir_, "TASK", path.string(), options_.eval_device);
    last_checkpoint_ = path.string();
    return last_checkpoint_;
  }

  // False if the evaluation was interrupted (nothing recorded; the pending
  // mark stays for --resume).
  bool evaluate(int64_t iteration) {
    if (!hooks_.evaluate) return true;
    EvaluationRequest request;
    request.options = &options_;
    request.environment_id = dataset_->getInfo().environment_id;
    request.environment_config = fs::absolute(dir_ / "environment.yaml").string();
    request.policy_config = fs::absolute(dir_ / "policy.yaml").string();
    request.out_dir = fs::absolute(dir_ / "eval" / ("iter_" + std::to_string(iteration))).string();
    request.iteration = iteration;
    markEvaluationPending(dir_, iteration);
    const EvaluationOutcome outcome = hooks_.evaluate(request);
    if (outcome.interrupted) {
      say("iteration " + std::to_string(iteration) + ": the evaluation was interrupted; --resume " + dir_.string() +
          " evaluates this checkpoint again");
      return false;
    }
    {
      std::ofstream eval(dir_ / "eval.csv", std::ios::app);
      eval << iteration << "," << options_.eval_split << "," << outcome.episodes << "," << outcome.successes << ","
           << formatNumber(outcome.success_rate) << "\n";
    }
    clearEvaluationPending(dir_);
    say("iteration " + std::to_string(iteration) + ": success " + std::to_string(outcome.successes) + "/" +
        std::to_string(outcome.episodes) + " on the " + options_.eval_split + " objects" +
        describeFailures(outcome, request.out_dir));
    return true;
  }

  TrainResult run(int64_t first) {
    using clock = std::chrono::steady_clock;
    const auto started = clock::now();
    const std::vector<std::string> names = algorithm_->getLossNames();
    // The log row in progress: its iteration count, then each loss's sum
    // (in checkpoints, so a resumed run's rows equal an uninterrupted one's).
    if (!log_row_.defined()) log_row_ = torch::zeros({int64_t(names.size()) + 1}, torch::kFloat64);
    double* row = log_row_.data_ptr<double>();
    auto row_started = clock::now();
    std::ofstream log(dir_ / "log.csv", std::ios::app);
    TrainResult result;
    int64_t iteration = first;
    feed_ = std::make_unique<BatchFeed>(*sampler_, device_, options_.prefetch);
    while (iteration < options_.iterations) {
      if (hooks_.should_stop && hooks_.should_stop()) {
        result.interrupted = true;
        break;
      }
      const TransitionBatch batch = feed_->next();
      const std::vector<double> losses = algorithm_->update(batch, iteration);
      for (std::size_t i = 0; i < losses.size(); ++i) {
        if (!std::isfinite(losses[i]))
          throw LearningError("iteration " + std::to_string(iteration + 1) + ": the " + names[i] + " is " +
                              formatNumber(losses[i]) + "; training stopped (" +
                              (last_checkpoint_.empty() ? std::string("no checkpoint was written")
                                                        : "the newest checkpoint, " + last_checkpoint_ + ", is intact") +
                              "): try a lower --lr, --normalize-state, or check the demonstrations");
        row[i + 1] += losses[i];
      }
      ++iteration;
      row[0] += 1;
      const double elapsed = std::chrono::duration<double>(clock::now() - started).count();
      if (hooks_.on_progress)
        hooks_.on_progress({iteration, options_.iterations, names, losses, elapsed,
                            double(iteration - first) / std::max(elapsed, 1e-9)});
      if (iteration % options_.log_every == 0 || iteration == options_.iterations) {
        const double row_seconds = std::chrono::duration<double>(clock::now() - row_started).count();
        log << iteration << "," << formatNumber(elapsed);
        for (std::size_t i = 0; i < names.size(); ++i) log << "," << formatNumber(row[i + 1] / row[0]);
        log << "," << formatNumber(row[0] / std::max(row_seconds, 1e-9)) << "\n" << std::flush;
        log_row_.zero_();
        row_started = clock::now();
      }
      const bool checkpoint = iteration % options_.checkpoint_every == 0 || iteration == options_.iterations;
      const bool evaluation = options_.eval_every > 0 &&
                              (iteration % options_.eval_every == 0 || iteration == options_.iterations);
      if (checkpoint || evaluation) saveCheckpointAt(iteration);
      if (evaluation && !evaluate(iteration)) {
        result.interrupted = true;
        break;
      }
    }
    if (result.interrupted && iteration > first && !fs::exists(dir_ / "checkpoints" / checkpointName(iteration)))
      saveCheckpointAt(iteration);
    result.iteration = iteration;
    result.checkpoint = last_checkpoint_.empty() ? findNewestCheckpoint(dir_.string()) : last_checkpoint_;
    result.seconds = std::chrono::duration<double>(clock::now() - started).count();
    return result;
  }

  TrainOptions options_;
  TrainHooks hooks_;
  fs::path dir_;
  torch::Device device_;
  std::unique_ptr<DemoDataset> dataset_;
  ObservationSpec spec_;
  std::unique_ptr<Algorithm> algorithm_;
  std::unique_ptr<BatchSampler> sampler_;
  std::unique_ptr<BatchFeed> feed_;  // over sampler_, while the loop runs
  torch::Tensor log_row_;
  std::string last_checkpoint_;
};

}  // namespace

std::string describeFailures(const EvaluationOutcome& outcome, const std::string& out_dir) {
  if (outcome.failures == 0) return "";
  return "; " + std::to_string(outcome.failures) + " of them failed (why: " +
         (fs::path(out_dir) / "episodes.csv").string() + ")";
}

std::string findNewestCheckpoint(const std::string& dir) {
  const fs::path folder = fs::path(dir) / "checkpoints";
  std::string newest;
  if (!fs::is_directory(folder)) return newest;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("iter_", 0) == 0 && entry.path().extension() == ".pt" &&
        (newest.empty() || name > fs::path(newest).filename().string()))
      newest = entry.path().string();
  }
  return newest;
}

TrainResult train(const PluginRegistry& registry, const TrainOptions& options, const TrainHooks& hooks) {
  options.check();
  Trainer trainer(registry, options, hooks);
  return trainer.start();
}

TrainResult resumeTraining(const PluginRegistry& registry, const std::string& dir, int64_t iterations,
                           const TrainHooks& hooks) {
  Trainer trainer(registry, readRunDirectory<TrainOptions>(dir), hooks);
  return trainer.resume(iterations);
}

}  // namespace manibench::learning
