#include <manibench/learning/env_workers.hpp>
#include <manibench/learning/spec.hpp>

#include <manibench/environment.hpp>
#include <manibench/stopwatch.hpp>
#include <manibench/wire_format.hpp>
#include <manibench/worker_pool.hpp>

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

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
  try {
    zygote_ = std::make_unique<Zygote>([factory](int fd) { return runWorker(fd, factory); });
  } catch (const std::runtime_error& e) {
    throw LearningError(std::string("cannot start the environment workers: ") + e.what());
  }
  for (unsigned i = 0; i < count; ++i) workers_.push_back(spawn());
}

EnvironmentWorkers::~EnvironmentWorkers() {
  // The workers read end of stream and leave, then the zygote.
  for (Worker& w : workers_) close(w.fd);
  zygote_.reset();
}

EnvironmentWorkers::Worker EnvironmentWorkers::spawn() {
  const Child child = zygote_->spawn();
  if (child.pid < 0) throw LearningError("cannot start an environment worker (" + child.error + ")");
  Worker w;
  w.fd = child.fd;
  w.pid = child.pid;
  return w;
}

void EnvironmentWorkers::send(unsigned worker, const wire::Writer& message) {
  Worker& w = workers_.at(worker);
  if (!w.lost && !wire::sendFrame(w.fd, message)) w.lost = true;
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
  Worker& w = workers_.at(worker);
  std::string message;
  const Clock::time_point deadline =
      reply_timeout_ > 0 ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(reply_timeout_))
                         : Clock::time_point::max();
  const wire::Received read = w.lost ? wire::Received::kClosed : wire::receiveFrame(w.fd, message, deadline);
  if (read != wire::Received::kFrame) {
    const pid_t pid = w.pid;
    // A worker that hangs (a task stuck in a loop or a system call) is
    // killed: it is alive, so the pid is still its own. One that died is
    // gone already (the zygote's children are reaped by the kernel).
    if (read == wire::Received::kTimedOut) ::kill(pid, SIGKILL);
    close(w.fd);
    w = spawn();
    const std::string what = read == wire::Received::kTimedOut
                                 ? ") did not answer within " + formatSeconds(reply_timeout_) + " s; killed it"
                                 : ") died";
    throw WorkerDied(worker, "environment worker " + std::to_string(worker) + " (pid " + std::to_string(pid) + what +
                                 "; started pid " + std::to_string(w.pid) + " in its place");
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
