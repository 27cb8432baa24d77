#include <manibench/learning/env_workers.hpp>
#include <manibench/learning/spec.hpp>

#include <manibench/environment.hpp>
#include <manibench/stopwatch.hpp>
#include <manibench/wire_format.hpp>
#include <manibench/worker_pool.hpp>


#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>

namespace manibench::learning {

namespace {

enum Request : uint8_t { kReset = 1, kStep = 2, kSaveState = 3, kRestoreState = 4 };

std::string formatSeconds(double seconds) {
  std::ostringstream out;
  out << seconds;
  return out.str();
}

// --- the worker process -------------------------------------------------------------------

// The requests and answers, in the one wire format (<manibench/wire_format.hpp>):
//   request: u8 Request; kReset: str object, u64 seed; kStep: array of
//     doubles (the action); kRestoreState: array of bytes (the state).
//   answer: u8 ok; then either str error, or an array of doubles (the
//     observation), f64 reward, u8 terminated, truncated, success, f64
//     seconds, an array of bytes (saveState's state; empty for the others).
void putStep(wire::Writer& w, const Environment& env, const StepResult& r, double seconds,
             const std::vector<uint8_t>& state = {}) {
  const Eigen::VectorXd& observation = env.getObservation();
  w.u8(1);
  w.array(observation.data(), std::size_t(observation.size()));
  w.f64(r.reward).u8(r.terminated).u8(r.truncated).u8(r.success).f64(seconds);
  w.array(state.data(), state.size());
}

Eigen::VectorXd getVector(wire::Reader& r) {
  Eigen::VectorXd v(Eigen::Index(r.arrayCount<double>()));
  r.take(v.data(), std::size_t(v.size()) * sizeof(double));
  return v;
}

std::string answer(Environment* env, const std::string& make_error, const std::string& request) {
  wire::Writer w;
  try {
    if (!env) throw std::runtime_error("cannot make the environment: " + make_error);
    wire::Reader r(request);
    const Clock::time_point started = Clock::now();
    switch (r.u8()) {
      case kReset: {
        const std::string object = r.str();
        env->reset(object, r.u64());
        putStep(w, *env, StepResult(), secondsSince(started));
        break;
      }
      case kStep: {
        const StepResult result = env->step(getVector(r));
        putStep(w, *env, result, secondsSince(started));
        break;
      }
      case kSaveState:
        putStep(w, *env, StepResult(), 0, env->saveState());
        break;
      case kRestoreState: {
        std::vector<uint8_t> state;
        r.field(state);
        env->restoreState(state);
        putStep(w, *env, StepResult(), secondsSince(started));
        break;
      }
      default:
        throw std::runtime_error("an unknown request");
    }
  } catch (const std::exception& e) {
    w = wire::Writer();
    w.u8(0).str(e.what());
  }
  return w.data();
}

int runWorker(int fd, const EnvironmentWorkers::Factory& factory) {
  std::unique_ptr<Environment> env;
  std::string make_error;
  try {
    env = factory();
  } catch (const std::exception& e) {
    make_error = e.what();
  }
  std::string request;
  while (wire::receiveFrame(fd, request))
    if (!wire::sendFrame(fd, answer(env.get(), make_error, request))) break;
  return 0;
}

}  // namespace

EnvironmentWorkers::EnvironmentWorkers(Factory factory, unsigned count) {
  if (count == 0) throw LearningError("at least one environment worker is needed");
  ChildOptions options;
  options.ignore_termination = true;  // the learner stops them by closing their channels
  try {
    pool_ = std::make_unique<WorkerPool>(
        count, [factory](std::size_t, int fd) { return runWorker(fd, factory); }, options, Launch::kZygote);
    for (unsigned i = 0; i < count; ++i) pool_->start(i);
  } catch (const std::runtime_error& e) {
    throw LearningError(std::string("cannot start the environment workers: ") + e.what());
  }
  lost_.assign(count, false);
}

// The pool closes the channels (the workers read end of stream and leave),
// kills what still runs, reaps them, then the zygote.
EnvironmentWorkers::~EnvironmentWorkers() = default;

unsigned EnvironmentWorkers::size() const { return unsigned(pool_->size()); }

pid_t EnvironmentWorkers::getPid(unsigned worker) const { return pool_->getPid(worker); }

void EnvironmentWorkers::send(unsigned worker, const wire::Writer& message) {
  if (!lost_.at(worker) && !pool_->send(worker, message)) lost_[worker] = true;
}

void EnvironmentWorkers::sendReset(unsigned worker, const std::string& object_id, uint64_t seed) {
  wire::Writer w;
  w.u8(kReset).str(object_id).u64(seed);
  send(worker, w);
}

void EnvironmentWorkers::sendStep(unsigned worker, const Eigen::VectorXd& action) {
  wire::Writer w;
  w.u8(kStep).array(action.data(), std::size_t(action.size()));
  send(worker, w);
}

void EnvironmentWorkers::sendSaveState(unsigned worker) {
  wire::Writer w;
  w.u8(kSaveState);
  send(worker, w);
}

void EnvironmentWorkers::sendRestoreState(unsigned worker, const std::vector<uint8_t>& state) {
  wire::Writer w;
  w.u8(kRestoreState).array(state.data(), state.size());
  send(worker, w);
}

void EnvironmentWorkers::setReplyTimeout(double seconds) {
  if (!(seconds >= 0)) throw LearningError("the workers' reply timeout must be at least 0 s (0: none)");
  reply_timeout_ = seconds;
}

WorkerReply EnvironmentWorkers::receive(unsigned worker) {
  std::string message;
  const Clock::time_point deadline =
      reply_timeout_ > 0 ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(reply_timeout_))
                         : Clock::time_point::max();
  const wire::Received read =
      lost_.at(worker) ? wire::Received::kClosed : pool_->receive(worker, message, deadline);
  if (read != wire::Received::kFrame) {
    const pid_t pid = pool_->getPid(worker);
    // A worker that hangs (a task stuck in a loop or a system call) is
    // killed; one whose channel ended is reaped for its status.
    const int status = pool_->stop(worker, read == wire::Received::kTimedOut);
    lost_[worker] = false;
    try {
      pool_->start(worker);
    } catch (const std::runtime_error& e) {
      throw LearningError("environment worker " + std::to_string(worker) + " (pid " + std::to_string(pid) + ") " +
                          describeExit(status) + ", and no other could be started: " + e.what());
    }
    const std::string what = read == wire::Received::kTimedOut
                                 ? ") did not answer within " + formatSeconds(reply_timeout_) + " s; killed it"
                                 : ") " + describeExit(status);
    throw WorkerDied(worker, "environment worker " + std::to_string(worker) + " (pid " + std::to_string(pid) + what +
                                 "; started pid " + std::to_string(pool_->getPid(worker)) + " in its place");
  }
  wire::Reader r(message);
  WorkerReply reply;
  reply.ok = r.u8() != 0;
  if (!reply.ok) {
    reply.error = r.str();
    return reply;
  }
  reply.observation = getVector(r);
  reply.reward = r.f64();
  reply.terminated = r.u8() != 0;
  reply.truncated = r.u8() != 0;
  reply.success = r.u8() != 0;
  reply.physics_seconds = r.f64();
  r.field(reply.state);
  return reply;
}

}  // namespace manibench::learning
