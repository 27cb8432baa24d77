// The evaluation's worker pool. The coordinating process forks workers; each
// builds its own Environment and PolicyInstance after the fork (EGL contexts
// must not cross a fork) and runs the episodes it is sent, one at a time.
//
// A worker talks to the coordinator over a Unix socket pair (length-prefixed
// messages) and publishes what it is doing (phase, step, since when) in a
// shared-memory slot. So when a worker dies (a policy's segfault or abort)
// or has to be killed (a policy call past the step timeout), the coordinator
// still knows the episode and step, records the failure and starts a new
// worker; the evaluation goes on.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <manibench/episode.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/plugin_instances.hpp>
#include <map>
#include <sstream>

namespace manibench {
namespace {

// ---- wire format: u32 length, then a payload written by Writer. Both ends
// are this same binary, so host byte order is fine.

class Writer {
 public:
  Writer& u8(uint8_t v) { return raw(&v, 1); }
  Writer& u32(uint32_t v) { return raw(&v, 4); }
  Writer& u64(uint64_t v) { return raw(&v, 8); }
  Writer& i64(int64_t v) { return raw(&v, 8); }
  Writer& f64(double v) { return raw(&v, 8); }
  Writer& str(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    data_ += s;
    return *this;
  }
  Writer& strings(const std::vector<std::string>& list) {
    u32(static_cast<uint32_t>(list.size()));
    for (const std::string& s : list) str(s);
    return *this;
  }
  const std::string& data() const { return data_; }

 private:
  Writer& raw(const void* p, std::size_t n) {
    data_.append(static_cast<const char*>(p), n);
    return *this;
  }
  std::string data_;
};

class Reader {
 public:
  explicit Reader(const std::string& data) : data_(data) {}
  uint8_t u8() { return get<uint8_t>(); }
  uint32_t u32() { return get<uint32_t>(); }
  uint64_t u64() { return get<uint64_t>(); }
  int64_t i64() { return get<int64_t>(); }
  double f64() { return get<double>(); }
  std::string str() {
    const uint32_t n = u32();
    need(n);
    std::string s = data_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::vector<std::string> strings() {
    std::vector<std::string> list(u32());
    for (std::string& s : list) s = str();
    return list;
  }

 private:
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  void need(std::size_t n) {
    if (pos_ + n > data_.size()) throw std::runtime_error("truncated message from a worker");
  }
  const std::string& data_;
  std::size_t pos_ = 0;
};

enum Message : uint8_t {
  kReady = 1,       // worker -> coordinator: set up; the task as configured
  kSetupError = 2,  // worker -> coordinator: could not set up; why
  kResult = 3,      // worker -> coordinator: one episode's record
  kRun = 10,        // coordinator -> worker: run this episode
};

bool sendMessage(int fd, const Writer& w) {
  const uint32_t size = static_cast<uint32_t>(w.data().size());
  std::string frame(reinterpret_cast<const char*>(&size), 4);
  frame += w.data();
  std::size_t sent = 0;
  while (sent < frame.size()) {
    const ssize_t n = ::send(fd, frame.data() + sent, frame.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

// Blocking read of one message (the worker's side); false at end of stream.
bool receiveMessage(int fd, std::string& payload) {
  auto readExact = [fd](char* p, std::size_t n) {
    while (n > 0) {
      const ssize_t got = ::read(fd, p, n);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      p += got;
      n -= static_cast<std::size_t>(got);
    }
    return true;
  };
  uint32_t size = 0;
  if (!readExact(reinterpret_cast<char*>(&size), 4)) return false;
  payload.resize(size);
  return readExact(payload.data(), size);
}

// ---- what a worker is doing, in memory shared with the coordinator.

enum Phase : uint32_t { kIdle, kSetup, kEnvReset, kPolicyReset, kPolicyAct, kEnvStep };

const char* getPhaseName(uint32_t phase) {
  switch (phase) {
    case kSetup:
      return "setup (building the environment and policy)";
    case kEnvReset:
      return "environment reset";
    case kPolicyReset:
      return "policy reset";
    case kPolicyAct:
      return "policy act";
    case kEnvStep:
      return "environment step";
    default:
      return "idle";
  }
}

bool isPolicyPhase(uint32_t phase) { return phase == kPolicyReset || phase == kPolicyAct; }

struct Slot {
  std::atomic<uint32_t> phase;
  std::atomic<uint32_t> step;
  std::atomic<int64_t> since_ns;
  std::atomic<double> total_reward;  // of the episode so far
};
static_assert(std::atomic<int64_t>::is_always_lock_free &&
                  std::atomic<uint32_t>::is_always_lock_free &&
                  std::atomic<double>::is_always_lock_free,
              "the shared slots need lock-free atomics");

int64_t getMonotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

void enterPhase(Slot& slot, Phase phase) {
  slot.since_ns.store(getMonotonicNs());
  slot.phase.store(phase);
}

std::string describeSignal(int sig) {
  const char* name = nullptr;
  switch (sig) {
    case SIGSEGV:
      name = "SIGSEGV";
      break;
    case SIGABRT:
      name = "SIGABRT";
      break;
    case SIGBUS:
      name = "SIGBUS";
      break;
    case SIGFPE:
      name = "SIGFPE";
      break;
    case SIGILL:
      name = "SIGILL";
      break;
    case SIGKILL:
      name = "SIGKILL";
      break;
    case SIGTERM:
      name = "SIGTERM";
      break;
    case SIGTRAP:
      name = "SIGTRAP";
      break;
    default:
      break;
  }
  std::string text = "signal " + std::to_string(sig);
  if (name) text += std::string(" (") + name + ", " + strsignal(sig) + ")";
  return text;
}

std::string describeExit(int status) {
  if (WIFSIGNALED(status)) return "killed by " + describeSignal(WTERMSIG(status));
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "stopped (wait status " + std::to_string(status) + ")";
}

// ---- the worker process.

struct WorkerContext {
  const PluginRegistry* registry;
  const EvaluationOptions* options;
  const EnvironmentFactory* make_environment;
};

void writeRecord(Writer& w, const EpisodeRecord& r) {
  w.u8(kResult).u64(r.spec.index).u32(r.steps).f64(r.total_reward).u8(r.success ? 1 : 0);
  w.u32(static_cast<uint32_t>(r.flags.size()));
  for (uint8_t f : r.flags) w.u8(f);
  w.str(r.failure).i64(r.failure_step).str(r.message).f64(r.seconds);
}

void readRecord(Reader& in, EpisodeRecord& r) {
  in.u64();  // index, checked by the caller
  r.steps = in.u32();
  r.total_reward = in.f64();
  r.success = in.u8() != 0;
  r.flags.resize(in.u32());
  for (uint8_t& f : r.flags) f = in.u8();
  r.failure = in.str();
  r.failure_step = in.i64();
  r.message = in.str();
  r.seconds = in.f64();
}

// What a worker does after an episode.
enum class After { kGoOn, kNewPolicy, kLeave };

Phase toWorkerPhase(EpisodePhase phase) {
  switch (phase) {
    case EpisodePhase::EnvReset:
      return kEnvReset;
    case EpisodePhase::PolicyReset:
      return kPolicyReset;
    case EpisodePhase::PolicyAct:
      return kPolicyAct;
    case EpisodePhase::EnvStep:
      return kEnvStep;
  }
  return kIdle;
}

// Runs one episode; failures of the policy or the environment are recorded,
// never thrown. The slot follows the episode's phases (the coordinator's
// view of a worker that hangs or dies).
After runWorkerEpisode(Environment& env, PolicyInstance& policy, Slot& slot,
                       EpisodeRecord& record) {
  const auto start = getMonotonicNs();
  const std::size_t conditions = env.getTaskDescription().success_conditions.size();
  record.flags.assign(conditions, 0);
  After after = After::kGoOn;
  EpisodeHooks hooks;
  hooks.on_phase = [&slot](EpisodePhase phase, uint32_t step) {
    slot.step.store(step);
    enterPhase(slot, toWorkerPhase(phase));
  };
  hooks.on_step = [&slot, &record](const StepResult&, const EpisodeResult& so_far) {
    record.total_reward = so_far.total_reward;
    slot.total_reward.store(record.total_reward);
    return true;
  };
  try {
    slot.step.store(0);
    slot.total_reward.store(0);
    const EpisodeResult result =
        runEpisode(env, policy, record.spec.object_id, record.spec.seed, hooks);
    record.success = result.success;
    record.flags = result.final_flags;
    record.flags.resize(conditions, 0);
  } catch (const std::exception& e) {
    const uint32_t phase = slot.phase.load();
    record.failure_step = slot.step.load();
    record.success = false;
    record.flags.assign(conditions, 0);
    // The policy object may be in any state after failing: a new one.
    after = After::kNewPolicy;
    if (dynamic_cast<const InvalidAction*>(&e)) {
      record.failure = failure::kInvalidAction;
    } else if (const auto* call = dynamic_cast<const PluginCallError*>(&e);
               call && isPolicyPhase(phase)) {
      // The SDK reports a wrong-size action as an invalid argument of act.
      record.failure = (phase == kPolicyAct && call->status() == MB_INVALID_ARGUMENT)
                           ? failure::kInvalidAction
                           : failure::kPolicyError;
    } else if (isPolicyPhase(phase)) {
      record.failure = failure::kPolicyError;
    } else {
      record.failure = failure::kEnvironmentError;
      after = After::kLeave;  // a fresh process rather than a scene in an unknown state
    }
    record.message = std::string(getPhaseName(phase)) + " at step " +
                     std::to_string(record.failure_step) + ": " + e.what();
  }
  record.steps = env.getElapsedSteps();
  record.seconds = double(getMonotonicNs() - start) * 1e-9;
  enterPhase(slot, kIdle);
  return after;
}

std::unique_ptr<PolicyInstance> makePolicy(const WorkerContext& context, const Environment& env) {
  return std::make_unique<PolicyInstance>(*context.registry, context.options->policy,
                                          context.options->policy_config,
                                          env.calcPolicyLayout(env.getObservationMode()));
}

[[noreturn]] void runWorker(int fd, Slot& slot, const WorkerContext& context) {
  enterPhase(slot, kSetup);
  std::unique_ptr<Environment> env;
  std::unique_ptr<PolicyInstance> policy;
  {
    Writer w;
    try {
      env = (*context.make_environment)();
      policy = makePolicy(context, *env);
      const TaskDescription& task = env->getTaskDescription();
      w.u8(kReady).u8(static_cast<uint8_t>(env->getObservationMode()));
      w.str(env->getControllerDescription().name);
      w.strings(task.success_conditions);
      w.strings(env->listObjects(context.options->split));
      w.u32(task.max_episode_steps).u32(env->getControllerDescription().action_dim);
      w.u32(task.observation_dim);
    } catch (const std::exception& e) {
      w = Writer();
      w.u8(kSetupError).str(e.what());
    }
    enterPhase(slot, kIdle);
    sendMessage(fd, w);
    if (!policy) {
      std::fflush(nullptr);
      _exit(0);
    }
  }
  std::string payload;
  while (receiveMessage(fd, payload)) {
    try {
      Reader in(payload);
      if (in.u8() != kRun) break;
      EpisodeRecord record;
      record.spec.index = in.u64();
      record.spec.object_id = in.str();
      record.spec.level = in.u64();
      record.spec.seed = in.u64();
      const After after = runWorkerEpisode(*env, *policy, slot, record);
      Writer w;
      writeRecord(w, record);
      if (!sendMessage(fd, w) || after == After::kLeave) break;
      if (after == After::kNewPolicy) {
        enterPhase(slot, kSetup);
        policy.reset();
        policy = makePolicy(context, *env);
        enterPhase(slot, kIdle);
      }
    } catch (const std::exception& e) {
      // Even a new policy could not be made: tell, and leave.
      Writer w;
      w.u8(kSetupError).str(e.what());
      sendMessage(fd, w);
      break;
    }
  }
  std::fflush(nullptr);
  _exit(0);
}

// ---- the coordinator.

struct Worker {
  pid_t pid = -1;
  int fd = -1;
  std::string buffer;    // bytes received, not yet a whole message
  int64_t episode = -1;  // index of the episode it runs, -1 when idle
  bool ready = false;
  const char* kill_reason = nullptr;  // set when the coordinator killed it
  std::string kill_message;
};

class Pool {
 public:
  Pool(const WorkerContext& context, unsigned count) : context_(context), workers_(count) {
    void* memory = mmap(nullptr, sizeof(Slot) * count, PROT_READ | PROT_WRITE,
                        MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (memory == MAP_FAILED)
      throw EvaluationError(std::string("cannot map the workers' shared memory: ") +
                            std::strerror(errno));
    slots_ = static_cast<Slot*>(memory);
    for (unsigned i = 0; i < count; ++i) new (&slots_[i]) Slot();
  }
  ~Pool() {
    for (std::size_t i = 0; i < workers_.size(); ++i) stop(i, true);
    munmap(slots_, sizeof(Slot) * workers_.size());
  }
  Pool(const Pool&) = delete;
  Pool& operator=(const Pool&) = delete;

  std::vector<Worker>& workers() { return workers_; }
  Slot& slot(std::size_t i) { return slots_[i]; }

  void start(std::size_t i) {
    int fds[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
      throw EvaluationError(std::string("cannot create a worker's socket: ") +
                            std::strerror(errno));
    Slot& s = slots_[i];
    s.step.store(0);
    s.total_reward.store(0);
    enterPhase(s, kSetup);
    // Buffered output would otherwise be written twice, once by the child.
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) {
      close(fds[0]);
      close(fds[1]);
      throw EvaluationError(std::string("cannot fork a worker: ") + std::strerror(errno));
    }
    if (pid == 0) {
      // The child keeps only its own end: another worker holding a socket
      // would hide that worker's death (no end of stream).
      close(fds[0]);
      for (const Worker& w : workers_)
        if (w.fd >= 0) close(w.fd);
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(1);
      // Ctrl-C reaches the whole process group; the coordinator decides.
      signal(SIGINT, SIG_IGN);
      signal(SIGPIPE, SIG_DFL);
      try {
        runWorker(fds[1], s, context_);
      } catch (...) {
        // Whatever escaped (not a std::exception): the coordinator records
        // the exit status as a crash.
      }
      std::fflush(nullptr);
      _exit(70);
    }
    close(fds[1]);
    Worker& w = workers_[i];
    w = Worker();
    w.pid = pid;
    w.fd = fds[0];
  }

  // Ends worker i (killing it when `kill`) and waits for it; the exit status.
  int stop(std::size_t i, bool kill) {
    Worker& w = workers_[i];
    int status = 0;
    if (w.fd >= 0) close(w.fd);  // a waiting worker reads end of stream and leaves
    w.fd = -1;
    if (w.pid > 0) {
      if (kill) ::kill(w.pid, SIGKILL);
      while (waitpid(w.pid, &status, 0) < 0 && errno == EINTR) {
      }
    }
    w.pid = -1;
    return status;
  }

 private:
  WorkerContext context_;
  std::vector<Worker> workers_;
  Slot* slots_ = nullptr;
};

}  // namespace

EvaluationResult evaluatePolicy(const PluginRegistry& registry, const EvaluationOptions& options,
                                const EnvironmentFactory& make_environment,
                                const EvaluationHooks& hooks) {
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
  const WorkerContext context{&registry, &options, &make_environment};
  Pool pool(context, options.workers);
  std::vector<Worker>& workers = pool.workers();
  std::vector<EpisodeRecord> records;
  std::size_t next = 0;  // next episode of result.planned to hand out
  bool planned = false;
  std::size_t successes = 0, failures = 0;
  int64_t last_progress_ns = 0;

  auto report = [&](bool force) {
    if (!hooks.on_progress) return;
    const int64_t now = getMonotonicNs();
    if (!force && now - last_progress_ns < 200000000) return;
    last_progress_ns = now;
    hooks.on_progress({records.size(), result.planned.size(), successes, failures,
                       double(now - start_ns) * 1e-9});
  };
  auto record = [&](EpisodeRecord r) {
    if (r.success) ++successes;
    if (r.failed()) ++failures;
    records.push_back(std::move(r));
    report(true);
  };
  auto dispatch = [&](std::size_t i) {
    Worker& w = workers[i];
    if (!planned || !w.ready || w.episode >= 0 || next >= result.planned.size()) return;
    const EpisodeSpec& spec = result.planned[next++];
    w.episode = static_cast<int64_t>(spec.index);
    Writer m;
    m.u8(kRun).u64(spec.index).str(spec.object_id).u64(spec.level).u64(spec.seed);
    sendMessage(w.fd, m);  // a dead worker is noticed by poll
  };
  // The first worker to report sets the episode list up.
  auto plan = [&](EvaluationTaskInfo info) {
    result.task = std::move(info);
    std::vector<std::string> objects = options.objects;
    if (objects.empty()) objects = result.task.split_objects;
    for (const std::string& id : objects)
      if (std::find(result.task.split_objects.begin(), result.task.split_objects.end(), id) ==
          result.task.split_objects.end()) {
        std::string available;
        for (const std::string& o : result.task.split_objects)
          available += (available.empty() ? "" : ", ") + o;
        throw EvaluationError("object '" + id + "' is not in the " + options.split + " split of " +
                              options.task + " (its objects: " + available + ")");
      }
    if (objects.empty())
      throw EvaluationError("the " + options.split + " split of " + options.task +
                            " has no objects");
    result.planned = makeEpisodeList(objects, options.levels, options.seed);
    planned = true;
  };
  auto stopRun = [&](const std::string& reason) {
    if (records.empty() && !result.interrupted)
      throw EvaluationError(reason);  // nothing done: nothing to keep
    result.interrupted = true;
    result.stop_reason = reason;
  };

  for (std::size_t i = 0; i < workers.size(); ++i) pool.start(i);

  std::vector<pollfd> fds;
  while (!result.interrupted && !(planned && records.size() == result.planned.size())) {
    if (hooks.should_stop && hooks.should_stop()) {
      result.interrupted = true;
      result.stop_reason = "interrupted";
      break;
    }
    fds.clear();
    std::vector<std::size_t> owners;
    for (std::size_t i = 0; i < workers.size(); ++i)
      if (workers[i].fd >= 0) {
        fds.push_back({workers[i].fd, POLLIN, 0});
        owners.push_back(i);
      }
    if (fds.empty()) {
      // Every worker is gone and none can be started: cannot happen unless
      // the list is done, which the loop condition covers.
      stopRun("no worker left");
      break;
    }
    const int ready = poll(fds.data(), fds.size(), 100);
    if (ready < 0 && errno != EINTR)
      throw EvaluationError(std::string("poll failed: ") + std::strerror(errno));

    for (std::size_t k = 0; ready > 0 && k < fds.size() && !result.interrupted; ++k) {
      if (!(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const std::size_t i = owners[k];
      Worker& w = workers[i];
      char chunk[65536];
      const ssize_t got = ::read(w.fd, chunk, sizeof(chunk));
      if (got < 0 && errno == EINTR) continue;
      if (got > 0) {
        w.buffer.append(chunk, static_cast<std::size_t>(got));
        while (w.buffer.size() >= 4) {
          uint32_t size = 0;
          std::memcpy(&size, w.buffer.data(), 4);
          if (w.buffer.size() < 4 + std::size_t(size)) break;
          const std::string payload = w.buffer.substr(4, size);
          w.buffer.erase(0, 4 + std::size_t(size));
          Reader in(payload);
          const uint8_t type = in.u8();
          if (type == kReady) {
            EvaluationTaskInfo info;
            info.observation_mode = static_cast<ObservationMode>(in.u8());
            info.controller = in.str();
            info.condition_names = in.strings();
            info.split_objects = in.strings();
            info.max_episode_steps = in.u32();
            info.action_dim = in.u32();
            info.observation_dim = in.u32();
            w.ready = true;
            if (!planned) plan(std::move(info));
          } else if (type == kSetupError) {
            const std::string message = in.str();
            pool.stop(i, true);
            stopRun("a worker could not set up: " + message);
            break;
          } else if (type == kResult) {
            EpisodeRecord r;
            Reader peek(payload);
            peek.u8();
            const uint64_t index = peek.u64();
            if (w.episode < 0 || uint64_t(w.episode) != index)
              throw EvaluationError("worker reported episode " + std::to_string(index) +
                                    " it was not running");
            r.spec = result.planned[index];
            readRecord(in, r);
            w.episode = -1;
            record(std::move(r));
          }
        }
        if (w.fd >= 0) dispatch(i);
        continue;
      }
      // End of stream: the worker is gone (crashed, killed, or left).
      const bool was_ready = w.ready;
      const int64_t episode = w.episode;
      const char* kill_reason = w.kill_reason;
      const std::string kill_message = w.kill_message;
      const uint32_t phase = pool.slot(i).phase.load();
      const uint32_t step = pool.slot(i).step.load();
      const int status = pool.stop(i, false);
      if (!was_ready) {
        stopRun("a worker died while building the environment and policy (" +
                (kill_message.empty() ? describeExit(status) : kill_message) + ")");
        break;
      }
      if (episode >= 0) {
        EpisodeRecord r;
        r.spec = result.planned[std::size_t(episode)];
        r.flags.assign(result.task.condition_names.size(), 0);
        r.failure_step = step;
        r.steps = step;
        r.total_reward = pool.slot(i).total_reward.load();
        if (kill_reason) {
          r.failure = kill_reason;
          r.message = kill_message;
        } else {
          r.failure = failure::kCrash;
          r.message = std::string(getPhaseName(phase)) + " at step " + std::to_string(step) +
                      ": the worker was " + describeExit(status);
        }
        record(std::move(r));
      }
      if (next < result.planned.size()) {
        pool.start(i);
        ++result.worker_restarts;
      }
    }

    // Calls past their time limit: kill the worker; its end of stream above
    // records the episode.
    const int64_t now = getMonotonicNs();
    for (std::size_t i = 0; i < workers.size(); ++i) {
      Worker& w = workers[i];
      if (w.pid <= 0 || w.kill_reason) continue;
      const Slot& s = pool.slot(i);
      const uint32_t phase = s.phase.load();
      if (phase == kIdle) continue;
      const double limit =
          isPolicyPhase(phase) ? options.step_timeout : options.environment_timeout;
      const double elapsed = double(now - s.since_ns.load()) * 1e-9;
      if (elapsed <= limit) continue;
      std::ostringstream message;
      message << getPhaseName(phase) << " at step " << s.step.load() << ": no return within "
              << limit << " s; the worker was killed";
      w.kill_reason = isPolicyPhase(phase) ? failure::kTimeout : failure::kEnvironmentTimeout;
      w.kill_message = message.str();
      ::kill(w.pid, SIGKILL);
    }
    report(false);
  }

  // Idle workers leave at end of stream; busy ones (an interrupted run) are
  // killed.
  for (std::size_t i = 0; i < workers.size(); ++i)
    pool.stop(i, result.interrupted || workers[i].episode >= 0);
  report(true);
  std::sort(records.begin(), records.end(), [](const EpisodeRecord& a, const EpisodeRecord& b) {
    return a.spec.index < b.spec.index;
  });
  result.episodes = std::move(records);
  result.seconds = double(getMonotonicNs() - start_ns) * 1e-9;
  summarizeEvaluation(result);
  return result;
}

}  // namespace manibench
