#include "session.hpp"

#include <manibench/evaluation.hpp>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <utility>

#include "cli.hpp"

namespace manibench::viewer {

const char* toString(EpisodeStatus status) {
  switch (status) {
    case EpisodeStatus::Running: return "running";
    case EpisodeStatus::Success: return "success";
    case EpisodeStatus::TimeLimit: return "time limit";
    case EpisodeStatus::Failed: return "failed";
  }
  return "?";
}

// The demonstration file of --record: made at the first episode to keep
// (so that a session that records nothing leaves no file), one trajectory
// appended and flushed per episode (a killed viewer keeps every episode
// before), closed with its JSON sidecar at the end.
class Session::Recording {
 public:
  Recording(std::string path, DemoFileInfo info, Environment& env)
      : path_(std::move(path)), info_(std::move(info)), recorder_(env) {}

  void onReset(const std::string& object, uint64_t seed) {
    recorder_.onReset(object, levels_[object]++, seed);
    kept_ = false;
  }
  void onStep(const Eigen::VectorXd& action, const StepResult& result) {
    recorder_.onStep(action, result);
  }
  // Appends the episode so far, once, if it has a step.
  void keep() {
    if (kept_ || recorder_.get().steps == 0) return;
    if (!writer_) writer_ = std::make_unique<DemoWriter>(path_, info_);
    writer_->append(recorder_.get());
    kept_ = true;
  }
  // A failed episode is not kept (its last step never finished).
  void drop() { kept_ = true; }
  void close() {
    if (writer_) writer_->close();
  }
  std::size_t getCount() const { return writer_ ? writer_->getCount() : 0; }

 private:
  std::string path_;
  DemoFileInfo info_;
  TrajectoryRecorder recorder_;
  std::unique_ptr<DemoWriter> writer_;
  std::map<std::string, uint64_t> levels_;  // episodes so far per object
  bool kept_ = true;
};

namespace {

// DemoFileInfo of what this session records, as `demos generate` writes it.
DemoFileInfo describeRecording(const PluginRegistry& registry, const SessionOptions& options,
                               const Environment& env, const std::string& policy) {
  DemoFileInfo info;
  info.manibench_version = getManibenchVersion();
  info.task = env.getTaskDescription().name;
  info.environment_id = options.task;
  info.controller = env.getControllerDescription().name;
  info.observation_mode = env.getObservationMode();
  info.condition_names = env.getTaskDescription().success_conditions;
  info.config = formatConfig(loadTaskConfig(registry, options.task, options.sources));
  info.plugins = cli::describePlugins(registry);
  info.policy = policy;
  info.created = cli::formatUtcNow();
  info.command = options.command;
  return info;
}

}  // namespace

Session::Session(PluginRegistry& registry, SessionOptions options)
    : registry_(registry), options_(std::move(options)) {
  if (options_.mode == SessionMode::Replay) {
    reader_ = std::make_unique<DemoReader>(options_.replay_path);
    trajectory_names_ = reader_->getTrajectoryNames();
    if (trajectory_names_.empty())
      throw DemoError("'" + options_.replay_path + "' holds no trajectory");
    env_ = makeDemoEnvironment(registry_, reader_->getInfo());
    const std::string first = options_.trajectory.empty() ? trajectory_names_.front() : options_.trajectory;
    if (std::find(trajectory_names_.begin(), trajectory_names_.end(), first) == trajectory_names_.end())
      throw DemoError("'" + options_.replay_path + "' has no trajectory '" + first + "' (it has traj_0 to " +
                      trajectory_names_.back() + ")");
    loadTrajectory(first);
    return;
  }
  env_ = cli::makeEnvironment(registry_, options_.task, options_.sources, /*stop_on_success=*/true);
  objects_ = env_->listObjects(options_.split);
  if (objects_.empty()) throw std::runtime_error("the " + options_.split + " split has no objects");
  const std::string first = options_.object.empty()
                                ? cli::chooseObject(objects_, options_.seed, options_.split)
                                : options_.object;
  const auto found = std::find(objects_.begin(), objects_.end(), first);
  if (found == objects_.end())
    objects_.insert(objects_.begin(), first);  // another split's: the reset judges it
  else
    object_index_ = std::size_t(found - objects_.begin());

  std::string policy_description;
  if (options_.mode == SessionMode::Policy) {
    policy_ = std::make_unique<PolicyInstance>(registry_, options_.policy, options_.policy_config,
                                               env_->calcPolicyLayout());
    const PluginEntry& entry = registry_.getEntry(PluginKind::Policy, options_.policy);
    const LoadedLibrary& library = registry_.getLibraries()[entry.library];
    policy_description = options_.policy + " (" + library.path + ", version " + library.version + ")";
  } else {
    policy_description = std::string("teleop (manibench-view, version ") + getManibenchVersion() + ")";
  }
  if (!options_.record_path.empty())
    recording_ = std::make_unique<Recording>(
        options_.record_path, describeRecording(registry_, options_, *env_, policy_description), *env_);
  startEpisode();
}

Session::~Session() {
  try {
    close();
  } catch (...) {
    // close() explicitly to see errors.
  }
}

const std::string& Session::getPolicyName() const {
  static const std::string teleop = "teleop", replay = "replay";
  if (policy_) return policy_->getName();
  return options_.mode == SessionMode::Replay ? replay : teleop;
}

void Session::startEpisode() {
  const std::string& object = objects_[object_index_];
  ++episode_count_;
  status_ = EpisodeStatus::Running;
  failure_.clear();
  last_ = StepResult();
  return_ = 0;
  last_action_.resize(0);
  try {
    env_->reset(object, options_.seed);
    if (recording_) recording_->onReset(object, options_.seed);
    if (policy_) policy_->reset(PolicyEpisode{env_->getTaskDescription().name, object, options_.seed});
  } catch (const EpisodeFailure& e) {
    status_ = EpisodeStatus::Failed;
    failure_ = e.what();
    if (recording_) recording_->drop();
  } catch (const PluginCallError& e) {
    status_ = EpisodeStatus::Failed;
    failure_ = e.what();
    if (recording_) recording_->drop();
  }
}

void Session::setStatusFrom(const StepResult& result) {
  last_ = result;
  return_ += result.reward;
  if (result.isDone()) status_ = result.success ? EpisodeStatus::Success : EpisodeStatus::TimeLimit;
}

void Session::step(const Eigen::VectorXd& teleop_action) {
  if (isOver() || closed_) return;
  Eigen::VectorXd action;
  const uint32_t t = env_->getElapsedSteps();
  try {
    switch (options_.mode) {
      case SessionMode::Teleop: action = teleop_action; break;
      case SessionMode::Policy:
        policy_->act(env_->getObservation(), t, action, env_->getVisualObservation());
        break;
      case SessionMode::Replay: action = trajectory_->getAction(t); break;
    }
    const StepResult result = env_->step(action);
    last_action_ = action;
    if (recording_) recording_->onStep(action, result);
    setStatusFrom(result);
  } catch (const EpisodeFailure& e) {
    status_ = EpisodeStatus::Failed;
    failure_ = e.what();
  } catch (const PluginCallError& e) {
    status_ = EpisodeStatus::Failed;
    failure_ = "policy " + getPolicyName() + ", step " + std::to_string(t) + ": " + e.what();
  } catch (const InvalidAction& e) {
    status_ = EpisodeStatus::Failed;
    failure_ = e.what();
  }
  if (status_ == EpisodeStatus::Failed) {
    if (recording_) recording_->drop();
    return;
  }
  if (options_.mode == SessionMode::Replay) {
    if (replay_divergence_.empty()) {
      const std::string difference =
          env_->findStateDifference(env_->saveState(), trajectory_->getEnvState(t + 1));
      if (!difference.empty()) replay_divergence_ = "step " + std::to_string(t + 1) + ": " + difference;
    }
    // The recording's end is the episode's, whatever the replay says.
    if (t + 1 >= trajectory_->steps && status_ == EpisodeStatus::Running)
      status_ = trajectory_->success ? EpisodeStatus::Success : EpisodeStatus::TimeLimit;
  }
  if (isOver() && recording_) recording_->keep();
}

void Session::restart(bool discard) {
  if (options_.mode == SessionMode::Replay) {
    seek(0);
    return;
  }
  if (recording_) {
    if (discard)
      recording_->drop();
    else
      recording_->keep();
  }
  startEpisode();
}

void Session::nextObject() {
  if (options_.mode == SessionMode::Replay) {
    const auto it = std::find(trajectory_names_.begin(), trajectory_names_.end(), trajectory_name_);
    const std::size_t next = (std::size_t(it - trajectory_names_.begin()) + 1) % trajectory_names_.size();
    loadTrajectory(trajectory_names_[next]);
    return;
  }
  if (recording_) recording_->keep();
  object_index_ = (object_index_ + 1) % objects_.size();
  startEpisode();
}

void Session::loadTrajectory(const std::string& name) {
  trajectory_ = reader_->read(name);
  trajectory_name_ = name;
  if (trajectory_->getStateCount() != trajectory_->steps + 1)
    throw DemoError("'" + options_.replay_path + "', " + name + ": " +
                    std::to_string(trajectory_->getStateCount()) + " states for " +
                    std::to_string(trajectory_->steps) + " steps");
  seek(0);
}

uint32_t Session::getReplayLength() const { return trajectory_ ? trajectory_->steps : 0; }

void Session::seek(uint32_t t) {
  if (!trajectory_) return;
  t = std::min(t, trajectory_->steps);
  ++episode_count_;
  env_->restoreState(trajectory_->getEnvState(t));
  replay_divergence_.clear();
  failure_.clear();
  return_ = 0;
  for (uint32_t k = 0; k < t; ++k) return_ += trajectory_->rewards[k];
  last_ = StepResult();
  if (t > 0) {
    const uint32_t c = trajectory_->condition_count;
    last_.reward = trajectory_->rewards[t - 1];
    last_.flags.assign(trajectory_->conditions.begin() + std::ptrdiff_t((t - 1) * c),
                       trajectory_->conditions.begin() + std::ptrdiff_t(t * c));
    last_.success = trajectory_->success_flags[t - 1] != 0;
    last_action_ = trajectory_->getAction(t - 1);
  } else {
    last_action_.resize(0);
  }
  status_ = t < trajectory_->steps ? EpisodeStatus::Running
            : trajectory_->success ? EpisodeStatus::Success
                                   : EpisodeStatus::TimeLimit;
}

std::size_t Session::getRecordedCount() const { return recording_ ? recording_->getCount() : 0; }

void Session::close() {
  if (closed_) return;
  closed_ = true;
  if (!recording_) return;
  if (status_ != EpisodeStatus::Failed) recording_->keep();
  recording_->close();
}

}  // namespace manibench::viewer
