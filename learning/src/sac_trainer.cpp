#include <manibench/learning/checkpoint.hpp>
#include <manibench/learning/compute.hpp>
#include <manibench/learning/dataset.hpp>
#include <manibench/learning/env_workers.hpp>
#include <manibench/learning/sac_trainer.hpp>
#include <manibench/learning/trainer.hpp>

#include "replay_buffer.hpp"
#include "training_files.hpp"

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/stopwatch.hpp>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <fstream>
#include <map>

namespace manibench::learning {

namespace fs = std::filesystem;

namespace {

// --- the loop -----------------------------------------------------------------------------

constexpr std::size_t kRecentEpisodes = 20;

// One worker's episode in progress.
struct Slot {
  Eigen::VectorXd obs;
  std::string object;
  uint64_t seed = 0;
  double episode_return = 0;
  bool success = false;
  bool needs_reset = true;
};

// What a log row sums since the previous one (and checkpoints carry, so a
// resumed run's rows equal an uninterrupted one's): episodes, their return
// and successes, update count, then each loss.
enum Row { kRowEpisodes, kRowReturn, kRowSuccesses, kRowUpdates, kRowLosses };

// Seconds of this run, for the log's speeds and time shares.
struct Times {
  double physics = 0;  // the workers' reset and step calls (summed over workers)
  double acting = 0;   // the actor choosing the workers' actions
  double updates = 0;  // gradient steps
  double waiting = 0;  // the learner waiting for the workers after its updates
};

class SacTrainer {
 public:
  SacTrainer(const PluginRegistry& registry, const SacOptions& options, const SacHooks& hooks)
      : options_(options), hooks_(hooks), dir_(options.out_dir) {
    checkOptions();
    EnvironmentOptions env_options = makeEnvironmentOptions(registry);
    {
      const Environment probe(registry, options_.environment_id, env_options);
      spec_.task = probe.getTaskDescription().name;
      spec_.mode = "state";
      spec_.controller = probe.getControllerDescription().name;
      setSpecLayout(probe, spec_);
      objects_ = selectObjects(probe);
    }
    // The workers first: libtorch (a CUDA query included) has started no
    // thread pool in this process yet.
    const std::string id = options_.environment_id;
    workers_ = std::make_unique<EnvironmentWorkers>(
        [&registry, id, env_options] { return std::make_unique<Environment>(registry, id, env_options); },
        options_.workers);
    workers_->setReplyTimeout(options_.worker_timeout);
    device_ = parseDevice(options_.device);
    setUpTrainingCompute(options_.threads);
    say(describeCompute(calcComputeInfo(), device_));
    say(spec_.describe() + "; " + std::to_string(objects_.size()) + " object(s), " +
        std::to_string(options_.workers) + " worker(s), " + (options_.early_done ? "early" : "no early") +
        " done at success");
    slots_.resize(options_.workers);
    replay_ = std::make_unique<ReplayBuffer>(options_.replay_size, spec_.state_dim, spec_.action_dim);
    row_ = torch::zeros({kRowLosses + 5}, torch::kFloat64);
  }

  SacResult start() {
    if (fs::exists(dir_ / "train.yaml"))
      throw LearningError("'" + dir_.string() + "' holds a training already: continue it with --resume " +
                          dir_.string() + ", or choose another --out");
    fs::create_directories(dir_ / "checkpoints");
    writeOptions();
    torch::manual_seed(options_.seed);
    algorithm_ = makeAlgorithm(options_.algorithm, options_.network, spec_, device_);
    for (const auto& [name, network] : algorithm_->getNetworks())
      say("network " + name + ": " + std::to_string(countParameters(*network)) + " parameters");
    writeLogHeader();
    for (unsigned w = 0; w < workers_->size(); ++w) startEpisode(w);
    collectResets();
    return run();
  }

  SacResult resume(int64_t steps) {
    const std::string newest = findNewestCheckpoint(dir_.string());
    if (newest.empty()) throw LearningError("'" + dir_.string() + "' has no checkpoint to resume from");
    std::vector<std::string> extras = {kCpuGeneratorExtra, kCudaGeneratorExtra, "counters", "log_row", "recent", "slots"};
    for (unsigned w = 0; w < options_.workers; ++w) extras.push_back("worker_state_" + std::to_string(w));
    LoadedCheckpoint loaded = loadCheckpoint(newest, device_, true, extras);
    loaded.info.spec.checkSame(spec_, "the checkpoint '" + newest + "'", "the environment");
    algorithm_ = std::move(loaded.algorithm);
    if (steps > 0) options_.steps = steps;
    writeOptions();
    restoreGeneratorStates(loaded.extras, device_);
    const torch::Tensor counters = loaded.extras.at("counters");
    env_steps_ = counters[0].item<int64_t>();
    updates_ = counters[1].item<int64_t>();
    next_episode_ = counters[2].item<int64_t>();
    episodes_ = counters[3].item<int64_t>();
    row_ = loaded.extras.at("log_row").clone();
    const torch::Tensor recent = loaded.extras.at("recent");
    for (int64_t i = 0; i < recent.size(0); ++i)
      recent_.emplace_back(recent[i][0].item<double>(), recent[i][1].item<double>() != 0);
    replay_->load(dir_ / "checkpoints" / replayName(env_steps_));
    restoreWorkers(loaded);
    truncateCsv(dir_ / "log.csv", env_steps_);
    // The evaluation this checkpoint was in when the run stopped or was
    // killed runs again (its row, if the kill came after it, goes first).
    const bool pending = hooks_.evaluate && findPendingEvaluation(dir_) == env_steps_;
    if (fs::exists(dir_ / "eval.csv")) truncateCsv(dir_ / "eval.csv", env_steps_ - (pending ? 1 : 0));
    say("resuming from " + newest + " (" + std::to_string(env_steps_) + " env steps)");
    if (pending && !evaluateNewest()) {
      SacResult result;
      result.env_steps = env_steps_;
      result.updates = updates_;
      result.episodes = episodes_;
      result.interrupted = true;
      result.checkpoint = newest;
      return result;
    }
    return run();
  }

 private:
  void say(const std::string& line) {
    if (hooks_.on_message) hooks_.on_message(line);
  }

  void checkOptions() const {
    options_.check();
    if (options_.eval_every > 0 && !hooks_.evaluate) throw LearningError("--eval-every: this program cannot evaluate");
  }

  EnvironmentOptions makeEnvironmentOptions(const PluginRegistry& registry) const {
    ConfigSources sources;
    sources.files = options_.config_files;
    sources.overrides = options_.config_sets;
    sources.overrides.push_back("observation.mode=state");
    EnvironmentOptions o = calcEnvironmentOptions(loadTaskConfig(registry, options_.environment_id, sources));
    o.stop_on_success = options_.early_done;
    return o;
  }

  std::vector<std::string> selectObjects(const Environment& probe) const {
    const std::vector<std::string> all =
        probe.getFixedObjects().empty() ? probe.listObjects(options_.split) : probe.getFixedObjects();
    if (options_.objects.empty()) return all;
    for (const std::string& id : options_.objects)
      if (std::find(all.begin(), all.end(), id) == all.end())
        throw LearningError("'" + id + "' is not an object of " + options_.environment_id +
                            (probe.getFixedObjects().empty() ? " (" + options_.split + " split)" : ""));
    return options_.objects;
  }

  void writeOptions() {
    YAML::Node node;
    options_.writeYaml(node);
    writeText(dir_ / "train.yaml", yamlText(node));
  }

  void writeLogHeader() {
    std::ofstream log(dir_ / "log.csv");
    log << "env_steps,updates,seconds,episodes,return,success_rate";
    for (const std::string& name : algorithm_->getLossNames()) log << "," << name;
    log << ",env_steps_per_second,updates_per_second,physics_share,acting_share,updates_share,waiting_share\n";
  }

  static std::string replayName(int64_t env_steps) {
    const std::string name = checkpointName(env_steps);
    return "replay_" + name.substr(5);
  }

  // --- episodes --------------------------------------------------------------------------

  // Episode number next_episode_ on worker `w`: the objects in turn, the
  // evaluation kit's seed of (seed, object, episode).
  void startEpisode(unsigned w) {
    Slot& s = slots_[w];
    const int64_t episode = next_episode_++;
    s.object = objects_[std::size_t(episode) % objects_.size()];
    s.seed = calcEpisodeSeed(options_.seed, s.object, uint64_t(episode));
    s.episode_return = 0;
    s.success = false;
    s.needs_reset = true;
    workers_->sendReset(w, s.object, s.seed);
  }

  // Receives every reset sent; a worker that fails or dies gets the next
  // episode (three failures in a row end the training).
  void collectResets() {
    for (unsigned w = 0; w < workers_->size(); ++w) {
      Slot& s = slots_[w];
      for (int attempt = 0; s.needs_reset; ++attempt) {
        std::string error;
        try {
          const WorkerReply r = workers_->receive(w);
          times_.physics += r.physics_seconds;
          if (r.ok) {
            s.obs = r.observation;
            s.needs_reset = false;
            break;
          }
          error = r.error;
        } catch (const WorkerDied& e) {
          error = e.what();
        }
        say("worker " + std::to_string(w) + ": reset of object " + s.object + ", seed " + std::to_string(s.seed) +
            " failed: " + error);
        if (attempt == 2) throw LearningError("worker " + std::to_string(w) + " failed three resets in a row");
        startEpisode(w);
      }
    }
  }

  void finishEpisode(const Slot& s) {
    ++episodes_;
    double* row = row_.data_ptr<double>();
    row[kRowEpisodes] += 1;
    row[kRowReturn] += s.episode_return;
    row[kRowSuccesses] += s.success ? 1 : 0;
    recent_.emplace_back(s.episode_return, s.success);
    if (recent_.size() > kRecentEpisodes) recent_.pop_front();
  }

  // --- one round: act, step the workers while updating, store --------------------------------

  torch::Tensor chooseActions() {
    const Clock::time_point started = Clock::now();
    const int64_t w = workers_->size();
    torch::Tensor actions;
    if (env_steps_ < options_.random_steps) {
      actions = torch::rand({w, int64_t(spec_.action_dim)}) * 2 - 1;
    } else {
      ObservationBatch obs;
      obs.state = torch::empty({w, int64_t(spec_.state_dim)});
      float* state = obs.state.data_ptr<float>();
      for (int64_t i = 0; i < w; ++i)
        for (uint32_t d = 0; d < spec_.state_dim; ++d) *state++ = float(slots_[std::size_t(i)].obs[d]);
      actions = algorithm_->explore(obs.to(device_)).to(torch::kCPU).contiguous();
    }
    times_.acting += secondsSince(started);
    return actions;
  }

  void update(int64_t count) {
    const Clock::time_point started = Clock::now();
    double* row = row_.data_ptr<double>();
    const std::vector<std::string> names = algorithm_->getLossNames();
    for (int64_t k = 0; k < count; ++k) {
      const std::vector<double> losses = algorithm_->update(replay_->sample(options_.algorithm.batch_size).to(device_), updates_);
      for (std::size_t i = 0; i < losses.size(); ++i) {
        if (!std::isfinite(losses[i]))
          throw LearningError("update " + std::to_string(updates_ + 1) + ": the " + names[i] + " is " +
                              formatNumber(losses[i]) + "; training stopped (the newest checkpoint is intact)");
        row[kRowLosses + i] += losses[i];
      }
      row[kRowUpdates] += 1;
      ++updates_;
    }
    times_.updates += secondsSince(started);
  }

  // Gradient steps due for this round's env steps, once the buffer holds enough.
  int64_t calcUpdatesDue(int64_t stepped) const {
    const int64_t ready = std::max(options_.learning_starts, options_.algorithm.batch_size);
    if (replay_->size() < ready) return 0;
    return int64_t(std::floor(double(env_steps_ + stepped) * options_.updates_per_step)) -
           int64_t(std::floor(double(env_steps_) * options_.updates_per_step));
  }

  void runRound() {
    const torch::Tensor actions = chooseActions();
    const unsigned w_count = workers_->size();
    const float* action = actions.data_ptr<float>();
    const int64_t a_dim = spec_.action_dim;
    // What the replay stores: the action as the environment applies it.
    std::vector<float> clipped(std::size_t(w_count * a_dim));
    for (unsigned w = 0; w < w_count; ++w) {
      Eigen::VectorXd sent(a_dim);
      for (int64_t d = 0; d < a_dim; ++d) {
        sent[d] = double(action[w * a_dim + d]);
        clipped[std::size_t(w * a_dim + d)] = std::clamp(action[w * a_dim + d], -1.0f, 1.0f);
      }
      workers_->sendStep(w, sent);
    }
    update(calcUpdatesDue(w_count));
    const Clock::time_point waiting = Clock::now();
    int64_t stepped = 0;
    for (unsigned w = 0; w < w_count; ++w) {
      Slot& s = slots_[w];
      WorkerReply r;
      try {
        r = workers_->receive(w);
      } catch (const WorkerDied& e) {
        dropEpisode(w, e.what());
        continue;
      }
      times_.physics += r.physics_seconds;
      if (!r.ok) {
        dropEpisode(w, "worker " + std::to_string(w) + ": " + r.error);
        continue;
      }
      replay_->add(s.obs, clipped.data() + w * a_dim, r.reward, r.observation, r.terminated);
      ++stepped;
      s.episode_return += r.reward;
      s.success = s.success || r.success;
      s.obs = r.observation;
      if (r.terminated || r.truncated) {
        finishEpisode(s);
        startEpisode(w);
      }
    }
    times_.waiting += secondsSince(waiting);
    env_steps_ += stepped;
    const Clock::time_point resetting = Clock::now();
    collectResets();
    times_.waiting += secondsSince(resetting);
  }

  // --- files -----------------------------------------------------------------------------

  void writeLogRow(double elapsed) {
    double* row = row_.data_ptr<double>();
    const std::size_t losses = algorithm_->getLossNames().size();
    std::ofstream log(dir_ / "log.csv", std::ios::app);
    const double episodes = row[kRowEpisodes], updates = std::max(row[kRowUpdates], 1.0);
    log << env_steps_ << "," << updates_ << "," << formatNumber(elapsed) << "," << int64_t(episodes) << ",";
    if (episodes > 0)
      log << formatNumber(row[kRowReturn] / episodes) << "," << formatNumber(row[kRowSuccesses] / episodes);
    else
      log << ",";
    for (std::size_t i = 0; i < losses; ++i) log << "," << (row[kRowUpdates] > 0 ? formatNumber(row[kRowLosses + i] / updates) : "");
    const double seconds = std::max(secondsSince(row_started_), 1e-9);
    const double total = times_.acting + times_.updates + times_.waiting + times_.physics;
    auto share = [&](double t) { return formatNumber(total > 0 ? t / total : 0); };
    log << "," << formatNumber(double(env_steps_ - row_env_steps_) / seconds) << ","
        << formatNumber(double(updates_ - row_updates_) / seconds) << "," << share(times_.physics) << ","
        << share(times_.acting) << "," << share(times_.updates) << "," << share(times_.waiting) << "\n";
    row_.zero_();
    row_started_ = Clock::now();
    row_env_steps_ = env_steps_;
    row_updates_ = updates_;
  }

  // The answer to sendSaveState; a worker that died meanwhile is replaced,
  // its episode dropped, and the replacement's new episode saved instead.
  WorkerReply receiveState(unsigned w) {
    for (;;) {
      try {
        return workers_->receive(w);
      } catch (const WorkerDied& e) {
        dropEpisode(w, e.what());
        collectResets();
        workers_->sendSaveState(w);
      }
    }
  }

  void dropEpisode(unsigned w, const std::string& why) {
    const Slot& s = slots_[w];
    say(why + "; its episode (object " + s.object + ", seed " + std::to_string(s.seed) + ") is dropped");
    startEpisode(w);
  }

  void saveAll() {
    // Each worker's environment as it stands (restoreState continues it bit for bit).
    std::map<std::string, torch::Tensor> extras;
    for (unsigned w = 0; w < workers_->size(); ++w) workers_->sendSaveState(w);
    for (unsigned w = 0; w < workers_->size(); ++w) {
      const WorkerReply r = receiveState(w);
      if (!r.ok) throw LearningError("worker " + std::to_string(w) + " cannot save its state: " + r.error);
      extras["worker_state_" + std::to_string(w)] =
          torch::from_blob(const_cast<uint8_t*>(r.state.data()), {int64_t(r.state.size())}, torch::kUInt8).clone();
    }
    torch::Tensor slots = torch::zeros({int64_t(slots_.size()), 2}, torch::kFloat64);
    for (std::size_t w = 0; w < slots_.size(); ++w) {
      slots[int64_t(w)][0] = slots_[w].episode_return;
      slots[int64_t(w)][1] = slots_[w].success ? 1.0 : 0.0;
    }
    torch::Tensor recent = torch::zeros({int64_t(recent_.size()), 2}, torch::kFloat64);
    for (std::size_t i = 0; i < recent_.size(); ++i) {
      recent[int64_t(i)][0] = recent_[i].first;
      recent[int64_t(i)][1] = recent_[i].second ? 1.0 : 0.0;
    }
    extras["slots"] = slots;
    extras["recent"] = recent;
    extras["counters"] = torch::tensor({env_steps_, updates_, next_episode_, episodes_}, torch::kInt64);
    extras["log_row"] = row_.clone();
    addGeneratorStates(extras, device_);

    // The buffer first, then the checkpoint that names it, then the older buffers.
    const fs::path folder = dir_ / "checkpoints";
    replay_->save(folder / replayName(env_steps_));
    YAML::Node node;
    options_.writeYaml(node);
    const CheckpointInfo info = describeCheckpoint(updates_, options_, spec_, node);
    const fs::path path = fs::absolute(folder / checkpointName(env_steps_));
    saveCheckpoint(path.string(), info, *algorithm_, extras);
    writePolicyConfig(dir_, options_.environment_id, path.string(), "cpu");
    for (const auto& entry : fs::directory_iterator(folder)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("replay_", 0) == 0 && name != replayName(env_steps_)) fs::remove(entry.path());
    }
    last_checkpoint_ = path.string();
  }

  // The newest checkpoint's deterministic actor (the workers wait
  // meanwhile); false if the evaluation was interrupted (nothing recorded;
  // the pending mark stays for --resume).
  bool evaluateNewest() {
    const fs::path out = dir_ / "eval" / fs::path(checkpointName(env_steps_)).stem();
    markEvaluationPending(dir_, env_steps_);
    const EvaluationOutcome outcome = hooks_.evaluate(options_, (dir_ / "policy.yaml").string(), out.string());
    if (outcome.interrupted) {
      say("the evaluation at " + std::to_string(env_steps_) + " env steps was interrupted; --resume " +
          dir_.string() + " evaluates this checkpoint again");
      return false;
    }
    {
      const bool fresh = !fs::exists(dir_ / "eval.csv");
      std::ofstream csv(dir_ / "eval.csv", std::ios::app);
      if (fresh) csv << "env_steps,episodes,successes,success_rate\n";
      csv << env_steps_ << "," << outcome.episodes << "," << outcome.successes << ","
          << formatNumber(outcome.success_rate) << "\n";
    }
    clearEvaluationPending(dir_);
    say("evaluation at " + std::to_string(env_steps_) + " env steps: success " + formatNumber(outcome.success_rate) +
        " (" + std::to_string(outcome.successes) + "/" + std::to_string(outcome.episodes) + ")" +
        describeFailures(outcome, out.string()));
    return true;
  }

  void restoreWorkers(const LoadedCheckpoint& loaded) {
    const torch::Tensor slots = loaded.extras.at("slots");
    if (slots.size(0) != int64_t(workers_->size()))
      throw LearningError("the checkpoint was written with " + std::to_string(slots.size(0)) + " workers");
    for (unsigned w = 0; w < workers_->size(); ++w) {
      const torch::Tensor blob = loaded.extras.at("worker_state_" + std::to_string(w)).contiguous();
      const uint8_t* p = blob.data_ptr<uint8_t>();
      workers_->sendRestoreState(w, std::vector<uint8_t>(p, p + blob.numel()));
    }
    for (unsigned w = 0; w < workers_->size(); ++w) {
      const WorkerReply r = workers_->receive(w);
      if (!r.ok) throw LearningError("worker " + std::to_string(w) + " cannot restore its state: " + r.error);
      Slot& s = slots_[w];
      const torch::Tensor blob = loaded.extras.at("worker_state_" + std::to_string(w)).contiguous();
      const Environment::StateHeader header = Environment::readStateHeader(
          std::vector<uint8_t>(blob.data_ptr<uint8_t>(), blob.data_ptr<uint8_t>() + blob.numel()));
      s.obs = r.observation;
      s.object = header.object_id;
      s.seed = header.seed;
      s.episode_return = slots[w][0].item<double>();
      s.success = slots[w][1].item<double>() != 0;
      s.needs_reset = false;
    }
  }

  SacResult run() {
    const Clock::time_point started = Clock::now();
    row_started_ = started;
    row_env_steps_ = env_steps_;
    row_updates_ = updates_;
    const int64_t first_steps = env_steps_, first_updates = updates_;
    SacResult result;
    while (env_steps_ < options_.steps) {
      if (hooks_.should_stop && hooks_.should_stop()) {
        result.interrupted = true;
        break;
      }
      const int64_t before = env_steps_;
      runRound();
      const double elapsed = secondsSince(started);
      if (hooks_.on_progress) hooks_.on_progress(makeProgress(elapsed, first_steps, first_updates));
      const bool last = env_steps_ >= options_.steps;
      if (env_steps_ / options_.log_every > before / options_.log_every || last) writeLogRow(elapsed);
      const bool saved = env_steps_ / options_.checkpoint_every > before / options_.checkpoint_every || last;
      if (saved) saveAll();
      if (options_.eval_every > 0 && (env_steps_ / options_.eval_every > before / options_.eval_every || last)) {
        if (!saved) saveAll();
        if (!evaluateNewest()) {
          result.interrupted = true;
          break;
        }
      }
    }
    if (result.interrupted && env_steps_ > first_steps &&
        !fs::exists(dir_ / "checkpoints" / checkpointName(env_steps_)))
      saveAll();
    result.env_steps = env_steps_;
    result.updates = updates_;
    result.episodes = episodes_;
    result.checkpoint = last_checkpoint_.empty() ? findNewestCheckpoint(dir_.string()) : last_checkpoint_;
    result.seconds = secondsSince(started);
    const double total = times_.acting + times_.updates + times_.waiting + times_.physics;
    if (total > 0)
      say("time: physics " + formatNumber(times_.physics) + " s (summed over workers), acting " +
          formatNumber(times_.acting) + " s, gradient steps " + formatNumber(times_.updates) + " s, waiting for " +
          "the workers " + formatNumber(times_.waiting) + " s");
    return result;
  }

  SacProgress makeProgress(double elapsed, int64_t first_steps, int64_t first_updates) const {
    SacProgress p;
    p.env_steps = env_steps_;
    p.total = options_.steps;
    p.updates = updates_;
    p.episodes = episodes_;
    p.env_steps_per_second = double(env_steps_ - first_steps) / std::max(elapsed, 1e-9);
    p.updates_per_second = double(updates_ - first_updates) / std::max(elapsed, 1e-9);
    for (const auto& [episode_return, success] : recent_) {
      p.mean_return += episode_return / double(recent_.size());
      p.success_rate += (success ? 1.0 : 0.0) / double(recent_.size());
    }
    for (unsigned w = 0; w < workers_->size(); ++w) p.worker_pids.push_back(workers_->getPid(w));
    return p;
  }

  SacOptions options_;
  SacHooks hooks_;
  fs::path dir_;
  torch::Device device_ = torch::Device(torch::kCPU);  // parsed once the workers run
  ObservationSpec spec_;
  std::vector<std::string> objects_;
  std::unique_ptr<EnvironmentWorkers> workers_;
  std::unique_ptr<Algorithm> algorithm_;
  std::unique_ptr<ReplayBuffer> replay_;
  std::vector<Slot> slots_;
  std::deque<std::pair<double, bool>> recent_;
  int64_t env_steps_ = 0, updates_ = 0, next_episode_ = 0, episodes_ = 0;
  torch::Tensor row_;
  Clock::time_point row_started_;
  int64_t row_env_steps_ = 0, row_updates_ = 0;
  Times times_;
  std::string last_checkpoint_;
};

}  // namespace

SacResult trainSac(const PluginRegistry& registry, const SacOptions& options, const SacHooks& hooks) {
  SacTrainer trainer(registry, options, hooks);
  return trainer.start();
}

SacResult resumeSac(const PluginRegistry& registry, const std::string& dir, int64_t steps, const SacHooks& hooks) {
  SacTrainer trainer(registry, readRunDirectory<SacOptions>(dir), hooks);
  return trainer.resume(steps);
}

}  // namespace manibench::learning
