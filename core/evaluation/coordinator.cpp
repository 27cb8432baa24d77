// The evaluation's coordinator: forks the workers (worker.hpp), hands out
// the episode list one episode at a time, collects the records, and turns a
// worker's death or a call past its time limit into a failed episode and a
// fresh worker, so that the evaluation goes on.
#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <manibench/evaluation.hpp>
#include <manibench/worker_pool.hpp>
#include <sstream>

#include "journal_writer.hpp"
#include "messages.hpp"
#include "worker.hpp"

namespace manibench {
namespace {

using namespace evaluation_detail;

// The coordinator's view of one worker process (the process itself and its
// channel are the WorkerPool's).
struct Worker {
  int64_t episode = -1;  // index of the episode it runs, -1 when idle
  bool ready = false;
  bool leaving = false;  // said it leaves after its episode: gets no other
  const char* kill_reason = nullptr;  // set when the coordinator killed it
  std::string kill_message;
};

// The worker processes, their state here and their shared-memory slots.
class Pool {
 public:
  Pool(const WorkerContext& context, unsigned count)
      : context_(context),
        processes_(count, [this](std::size_t i, int fd) { return runWorker(fd, slots_[i], context_); }),
        workers_(count) {
    void* memory = mmap(nullptr, sizeof(Slot) * count, PROT_READ | PROT_WRITE,
                        MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (memory == MAP_FAILED)
      throw EvaluationError(std::string("cannot map the workers' shared memory: ") +
                            std::strerror(errno));
    slots_ = static_cast<Slot*>(memory);
    for (unsigned i = 0; i < count; ++i) new (&slots_[i]) Slot();
  }
  ~Pool() {
    // The workers go before the slots they write.
    processes_.stopAll();
    munmap(slots_, sizeof(Slot) * workers_.size());
  }
  Pool(const Pool&) = delete;
  Pool& operator=(const Pool&) = delete;

  std::vector<Worker>& workers() { return workers_; }
  WorkerPool& processes() { return processes_; }
  Slot& slot(std::size_t i) { return slots_[i]; }

  void start(std::size_t i) {
    Slot& s = slots_[i];
    s.step.store(0);
    s.total_reward.store(0);
    enterPhase(s, kSetup);
    try {
      processes_.start(i);
    } catch (const std::runtime_error& e) {
      throw EvaluationError(e.what());
    }
    workers_[i] = Worker();
  }

  // Ends worker i (killing it when `kill`) and waits for it; the exit status.
  int stop(std::size_t i, bool kill) { return processes_.stop(i, kill); }

 private:
  WorkerContext context_;
  Slot* slots_ = nullptr;
  WorkerPool processes_;
  std::vector<Worker> workers_;
};

// The run's temporary folder, for the sandboxed policies' private folders
// (none with --trusted-policy); removed after the workers are gone, also
// what a killed worker's policy left.
struct ScratchDir {
  std::string path;
  explicit ScratchDir(const EvaluationOptions& options) {
    if (!options.sandbox_policy) return;
    const char* base = std::getenv("TMPDIR");
    path = std::string(base && *base ? base : "/tmp") + "/manibench-eval-XXXXXX";
    if (!mkdtemp(path.data()))
      throw EvaluationError("cannot create the run's temporary folder: " +
                            std::string(std::strerror(errno)));
  }
  ~ScratchDir() {
    std::error_code ignored;
    if (!path.empty()) std::filesystem::remove_all(path, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
};

// One evaluation run: the event loop over the workers' sockets and slots.
class Coordinator {
 public:
  Coordinator(const PluginRegistry& registry, const EvaluationOptions& options,
              const EnvironmentFactory& make_environment, const EvaluationHooks& hooks,
              EvaluationResult& result)
      : options_(options),
        hooks_(hooks),
        result_(result),
        scratch_(options),
        context_{&registry, &options, &make_environment, scratch_.path},
        pool_(context_, options.workers) {}

  // Runs every planned episode (or until stopped); leaves the records,
  // sorted by index, in the result.
  void run();

 private:
  // Progress to the hook: after each episode, else a few times a second.
  void report(bool force);
  void record(EpisodeRecord r);
  // The first worker to report sets the episode list up.
  void plan(EvaluationTaskInfo info);
  // Sends idle worker i the next episode, if any.
  void dispatch(std::size_t i);
  // Ends the run for `reason`; with nothing done there is nothing to keep.
  void stopRun(const std::string& reason);
  // Handles one message of worker i, then gives it its next episode.
  void handleMessage(std::size_t i, const std::string& payload);
  // Worker i's socket ended: record the episode it was running, restart it.
  void handleExit(std::size_t i, int status);
  // Kills workers whose call is past its time limit; their end of stream
  // records the episode.
  void killOverdue();

  // Records the other ranks finished (MPI); whether they are all done.
  void takeRemote();
  bool isRemoteDone() const { return !hooks_.remote_done || hooks_.remote_done(); }
  // Whether every episode of this process's own list is done.
  bool isLocalDone() const { return planned_ && local_done_ == local_.size(); }

  const EvaluationOptions& options_;
  const EvaluationHooks& hooks_;
  EvaluationResult& result_;
  const ScratchDir scratch_;  // outlives the pool
  const WorkerContext context_;
  Pool pool_;
  std::vector<EpisodeRecord> records_;
  // The episodes this process runs: indices into result_.planned (its rank's
  // part of the share, without those resumed).
  std::vector<std::size_t> local_;
  std::size_t next_ = 0;        // next of local_ to hand out
  std::size_t local_done_ = 0;  // of local_, finished
  std::map<std::size_t, std::size_t> position_;  // episode index -> position in planned
  evaluation_detail::JournalWriter journal_;
  bool planned_ = false;
  std::size_t successes_ = 0, failures_ = 0;
  int64_t start_ns_ = getMonotonicNs();
  int64_t last_progress_ns_ = 0;
};

void Coordinator::report(bool force) {
  if (!hooks_.on_progress) return;
  const int64_t now = getMonotonicNs();
  if (!force && now - last_progress_ns_ < 200000000) return;
  last_progress_ns_ = now;
  hooks_.on_progress({records_.size(), result_.planned.size(), successes_, failures_,
                      double(now - start_ns_) * 1e-9});
}

void Coordinator::record(EpisodeRecord r) {
  if (hooks_.on_episode) hooks_.on_episode(r);
  journal_.write(formatJournalEpisode(r));
  if (r.success) ++successes_;
  if (r.failed()) ++failures_;
  records_.push_back(std::move(r));
  report(true);
}

void Coordinator::plan(EvaluationTaskInfo info) {
  result_.task = std::move(info);
  const std::vector<std::string>& split = result_.task.split_objects;
  std::vector<std::string> objects = options_.objects;
  if (objects.empty()) objects = split;
  for (const std::string& id : objects)
    if (std::find(split.begin(), split.end(), id) == split.end()) {
      std::string available;
      for (const std::string& o : split) available += (available.empty() ? "" : ", ") + o;
      throw EvaluationError("object '" + id + "' is not in the " + options_.split + " split of " +
                            options_.task + " (its objects: " + available + ")");
    }
  if (objects.empty())
    throw EvaluationError("the " + options_.split + " split of " + options_.task +
                          " has no objects");
  // The share of the whole list (--shard); its seeds are the whole list's.
  for (const EpisodeSpec& spec : makeEpisodeList(objects, options_.levels, options_.seed))
    if (spec.index % options_.shards == options_.shard) {
      position_[spec.index] = result_.planned.size();
      result_.planned.push_back(spec);
    }
  // The libraries and the policy's files as they are now, before any
  // episode: the certificate's, and the journal header's (a resume or a
  // merge with a rebuilt plugin is then refused).
  result_.inputs = calcInputDigests(*context_.registry, options_, result_.task.controller);
  const std::string header = formatJournalHeader(result_);
  if (!options_.resumed_header.empty()) {
    const std::string difference = findJournalDifference(options_.resumed_header, header, true);
    if (!difference.empty())
      throw EvaluationError("--resume: the journal is of another evaluation (" + difference +
                            " here)");
  }
  std::set<std::size_t> done;
  for (const EpisodeRecord& r : options_.resumed)
    if (position_.count(r.spec.index) && done.insert(r.spec.index).second) {
      records_.push_back(r);
      if (r.success) ++successes_;
      if (r.failed()) ++failures_;
    }
  for (std::size_t p = 0; p < result_.planned.size(); ++p)
    if (p % options_.ranks == options_.rank && !done.count(result_.planned[p].index)) local_.push_back(p);
  if (!options_.journal_path.empty())
    journal_.open(options_.journal_path, header, !options_.resumed_header.empty());
  planned_ = true;
  if (hooks_.on_ready) hooks_.on_ready(result_.task);
}

void Coordinator::dispatch(std::size_t i) {
  Worker& w = pool_.workers()[i];
  if (!planned_ || !pool_.processes().isRunning(i) || !w.ready || w.leaving || w.episode >= 0 ||
      next_ >= local_.size())
    return;
  const EpisodeSpec& spec = result_.planned[local_[next_++]];
  w.episode = static_cast<int64_t>(spec.index);
  Writer m;
  transferRun(m.u8(kRun), spec);
  pool_.processes().send(i, m);  // a dead worker is noticed by poll
}

void Coordinator::stopRun(const std::string& reason) {
  if (records_.empty() && !result_.interrupted) throw EvaluationError(reason);
  result_.interrupted = true;
  result_.stop_reason = reason;
}

void Coordinator::handleMessage(std::size_t i, const std::string& payload) {
  // A stopped run reads no more: what is left is killed with its workers.
  if (result_.interrupted) return;
  Worker& w = pool_.workers()[i];
  Reader in(payload);
  const uint8_t type = in.u8();
  if (type == kReady) {
    EvaluationTaskInfo info;
    transferReady(in, info);
    w.ready = true;
    if (!planned_) plan(std::move(info));
  } else if (type == kSetupError) {
    const std::string message = in.str();
    pool_.stop(i, true);
    stopRun("a worker could not set up: " + message);
    return;
  } else if (type == kResult) {
    EpisodeRecord r;
    transferResult(in, r);
    if (in.u8() != 0) {
      auto trajectory = std::make_shared<Trajectory>();
      transferTrajectory(in, *trajectory);
      r.trajectory = std::move(trajectory);
    }
    w.leaving = in.u8() != 0;
    const std::size_t index = r.spec.index;
    if (w.episode < 0 || uint64_t(w.episode) != index)
      throw EvaluationError("worker reported episode " + std::to_string(index) +
                            " it was not running");
    r.spec = result_.planned[position_.at(index)];
    w.episode = -1;
    ++local_done_;
    record(std::move(r));
  }
  dispatch(i);
}

void Coordinator::handleExit(std::size_t i, int status) {
  if (result_.interrupted) return;
  Worker& w = pool_.workers()[i];
  const bool was_ready = w.ready;
  const int64_t episode = w.episode;
  const char* kill_reason = w.kill_reason;
  const std::string kill_message = w.kill_message;
  const uint32_t phase = pool_.slot(i).phase.load();
  const uint32_t step = pool_.slot(i).step.load();
  if (!was_ready) {
    stopRun("a worker died while building the environment and policy (" +
            (kill_message.empty() ? describeExit(status) : kill_message) + ")");
    return;
  }
  if (episode >= 0) {
    EpisodeRecord r;
    r.spec = result_.planned[position_.at(std::size_t(episode))];
    r.flags.assign(result_.task.condition_names.size(), 0);
    r.failure_step = step;
    r.steps = step;
    r.total_reward = pool_.slot(i).total_reward.load();
    if (kill_reason) {
      r.failure = kill_reason;
      r.message = kill_message;
    } else {
      r.failure = failure::kCrash;
      r.message = std::string(getPhaseName(phase)) + " at step " + std::to_string(step) +
                  ": the worker was " + describeExit(status);
    }
    ++local_done_;
    record(std::move(r));
  }
  if (next_ < local_.size()) {
    pool_.start(i);
    ++result_.worker_restarts;
  }
}

void Coordinator::killOverdue() {
  const int64_t now = getMonotonicNs();
  std::vector<Worker>& workers = pool_.workers();
  for (std::size_t i = 0; i < workers.size(); ++i) {
    Worker& w = workers[i];
    if (!pool_.processes().isRunning(i) || w.kill_reason) continue;
    const Slot& s = pool_.slot(i);
    const uint32_t phase = s.phase.load();
    if (phase == kIdle) continue;
    // A sandboxed policy's calls are timed by its worker, which kills only
    // the policy's process; this is the backstop.
    const double limit = isPolicyPhase(phase)
                             ? options_.step_timeout + (options_.sandbox_policy ? 5 : 0)
                             : options_.environment_timeout;
    const double elapsed = double(now - s.since_ns.load()) * 1e-9;
    if (elapsed <= limit) continue;
    std::ostringstream message;
    message << getPhaseName(phase) << " at step " << s.step.load() << ": no return within "
            << limit << " s; the worker was killed";
    w.kill_reason = isPolicyPhase(phase) ? failure::kTimeout : failure::kEnvironmentTimeout;
    w.kill_message = message.str();
    pool_.processes().kill(i);
  }
}

void Coordinator::run() {
  std::vector<Worker>& workers = pool_.workers();
  for (std::size_t i = 0; i < workers.size(); ++i) pool_.start(i);

  const auto on_frame = [this](std::size_t i, const std::string& payload) { handleMessage(i, payload); };
  const auto on_end = [this](std::size_t i, int status) { handleExit(i, status); };
  while (!result_.interrupted && !(isLocalDone() && isRemoteDone())) {
    if (hooks_.should_stop && hooks_.should_stop()) {
      result_.interrupted = true;
      result_.stop_reason = "interrupted";
      break;
    }
    takeRemote();
    bool waited = false;
    try {
      waited = pool_.processes().poll(isLocalDone() ? 20 : 100, on_frame, on_end);
    } catch (const std::runtime_error& e) {
      if (dynamic_cast<const Error*>(&e)) throw;
      throw EvaluationError(e.what());
    }
    if (!waited) {
      // Every worker is gone, none is started once this process's own
      // episodes are done: the other ranks' are awaited.
      if (isLocalDone()) {
        usleep(20000);
        continue;
      }
      stopRun("no worker left");
      break;
    }
    killOverdue();
    report(false);
  }

  // Idle workers leave at end of stream; busy ones (an interrupted run) are
  // killed, all at once before any is waited for: under mpirun the files
  // must be written within Open MPI's grace after SIGTERM.
  for (std::size_t i = 0; i < workers.size(); ++i)
    if (result_.interrupted || workers[i].episode >= 0) pool_.processes().kill(i);
  for (std::size_t i = 0; i < workers.size(); ++i) pool_.stop(i, false);
  takeRemote();
  if (!result_.interrupted && records_.size() < result_.planned.size() && options_.ranks > 1 &&
      options_.rank == 0) {
    // Another rank stopped before its episodes were done.
    std::set<std::size_t> have;
    for (const EpisodeRecord& r : records_) have.insert(r.spec.index);
    std::vector<EpisodeSpec> missing;
    for (const EpisodeSpec& spec : result_.planned)
      if (!have.count(spec.index)) missing.push_back(spec);
    result_.interrupted = true;
    result_.stop_reason = std::to_string(missing.size()) +
                          " episode(s) of other ranks missing: " + describeEpisodes(missing);
  }
  report(true);
  std::sort(records_.begin(), records_.end(), [](const EpisodeRecord& a, const EpisodeRecord& b) {
    return a.spec.index < b.spec.index;
  });
  result_.episodes = std::move(records_);
  journal_.write(evaluation_detail::formatJournalEnd(result_, double(getMonotonicNs() - start_ns_) * 1e-9));
}

void Coordinator::takeRemote() {
  if (!hooks_.take_remote || !planned_) return;  // the hook keeps them until the list is made
  for (EpisodeRecord& r : hooks_.take_remote()) {
    const auto at = position_.find(r.spec.index);
    if (at == position_.end()) continue;  // not of this run's list
    r.spec = result_.planned[at->second];
    record(std::move(r));
  }
}

}  // namespace

EvaluationResult evaluatePolicy(const PluginRegistry& registry, const EvaluationOptions& options,
                                const EnvironmentFactory& make_environment,
                                const EvaluationHooks& hooks) {
  if (options.shards < 1 || options.shard >= options.shards || options.ranks < 1 ||
      options.rank >= options.ranks)
    throw EvaluationError("a shard or rank outside its count");
  if (options.workers < 1 || options.workers > 256)
    throw EvaluationError("the number of workers must be between 1 and 256, got " +
                          std::to_string(options.workers));
  if (!(options.step_timeout > 0) || !(options.environment_timeout > 0))
    throw EvaluationError("timeouts must be positive numbers of seconds");
  if (options.levels.empty()) throw EvaluationError("no episodes to run (the level list is empty)");
  const PluginEntry& entry = registry.getEntry(PluginKind::Policy, options.policy);

  EvaluationResult result;
  result.options = options;
  result.policy_library = registry.getLibraries()[entry.library].path;
  result.policy_library_version = registry.getLibraries()[entry.library].version;
  const int64_t start_ns = getMonotonicNs();
  Coordinator(registry, options, make_environment, hooks, result).run();
  result.seconds = double(getMonotonicNs() - start_ns) * 1e-9;
  summarizeEvaluation(result);
  return result;
}

}  // namespace manibench
