// Environment workers: processes that each own one Environment and step it
// on request, so that W environments run their physics in parallel while
// the learner updates its networks (supplement C.2's sample-collecting
// processes, without Python).
//
// Why processes started by a zygote: libtorch's GNU OpenMP pool must not
// be started in a process that then forks (the children hang), yet a worker
// that dies has to be replaced while the learner trains. So the workers are
// the core's WorkerPool with Launch::kZygote (<manibench/worker_pool.hpp>):
// it forks one small process (the zygote) before the learner touches
// libtorch; every
// worker, the first ones and the replacements, is forked by the zygote, its
// socket handed to the learner, and reaped by the zygote for its wait
// status (a killed worker is reported with its signal). Workers never touch
// libtorch. Each channel carries frames of the one wire format
// (<manibench/wire_format.hpp>): an action of A doubles out, an
// observation, the reward and the flags back. The zygote and the workers
// are tied to their parents (PR_SET_PDEATHSIG).
//
// When the learner goes, the zygote and the workers read end-of-file and
// exit: nothing outlives the run.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <sys/types.h>
#include <vector>

namespace manibench {
class Environment;
class WorkerPool;
namespace wire {
class Writer;
}
}  // namespace manibench

namespace manibench::learning {

// A worker's process ended (killed, crashed) while the learner waited for
// it. The pool has already started its replacement (a fresh environment
// with no episode): reset it.
class WorkerDied : public std::runtime_error {
 public:
  WorkerDied(unsigned worker, const std::string& message) : std::runtime_error(message), worker_(worker) {}
  unsigned getWorker() const { return worker_; }

 private:
  unsigned worker_;
};

// What a worker answers.
struct WorkerReply {
  bool ok = true;
  std::string error;  // !ok: why (an EpisodeFailure's message, a bad object, ...)
  Eigen::VectorXd observation;
  double reward = 0;
  bool terminated = false, truncated = false, success = false;
  double physics_seconds = 0;  // in the environment's reset/step (the worker's own clock)
  std::vector<uint8_t> state;  // saveState's blob
};

class EnvironmentWorkers {
 public:
  // Runs in each worker, after the fork: makes its environment.
  using Factory = std::function<std::unique_ptr<Environment>()>;
  // Forks the zygote, then has it fork `count` workers. Call it before the
  // process starts libtorch's thread pools.
  EnvironmentWorkers(Factory factory, unsigned count);
  ~EnvironmentWorkers();
  EnvironmentWorkers(const EnvironmentWorkers&) = delete;
  EnvironmentWorkers& operator=(const EnvironmentWorkers&) = delete;

  unsigned size() const;
  pid_t getPid(unsigned worker) const;

  // Requests; each is answered by one receive(worker), in order. Several
  // workers may be sent to before any is received from: they run in
  // parallel.
  void sendReset(unsigned worker, const std::string& object_id, uint64_t seed);
  void sendStep(unsigned worker, const Eigen::VectorXd& action);
  void sendSaveState(unsigned worker);
  void sendRestoreState(unsigned worker, const std::vector<uint8_t>& state);
  // The answer to the oldest request not yet received. Throws WorkerDied
  // (after starting a replacement) when the worker's process has ended, or
  // when it has not answered within the reply timeout (it is killed first).
  WorkerReply receive(unsigned worker);
  // How long receive() waits for one answer; 0 (the default): for ever.
  void setReplyTimeout(double seconds);

 private:
  void send(unsigned worker, const wire::Writer& message);

  double reply_timeout_ = 0;
  // core/workers' pool, its workers forked by its zygote (Launch::kZygote)
  std::unique_ptr<WorkerPool> pool_;
  // Per worker: a send failed, the process is gone (receive reports it).
  std::vector<bool> lost_;
};

}  // namespace manibench::learning
