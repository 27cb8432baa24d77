// An evaluation worker: a forked process that builds its own Environment
// and PolicyInstance (after the fork: EGL contexts must not cross it), runs
// the episodes the coordinator sends, one at a time, and publishes what it
// is doing in a shared-memory slot, so that the coordinator still knows the
// episode and step when the worker dies or has to be killed.
#pragma once

#include <manibench/evaluation.hpp>
#include <manibench/worker_pool.hpp>

#include <atomic>
#include <cstdint>
#include <string>

namespace manibench::evaluation_detail {

// What a worker is doing.
enum Phase : uint32_t { kIdle, kSetup, kEnvReset, kPolicyReset, kPolicyAct, kEnvStep };

// "policy act", "environment step", ...: for failure messages.
const char* getPhaseName(uint32_t phase);
// Whether a failure in `phase` is the policy's (else the environment's).
inline bool isPolicyPhase(uint32_t phase) { return phase == kPolicyReset || phase == kPolicyAct; }

// One worker's status, in memory shared with the coordinator.
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

int64_t getMonotonicNs();
// Publishes `phase`, entered now.
void enterPhase(Slot& slot, Phase phase);

// What a worker needs from the coordinator's process (inherited by fork).
struct WorkerContext {
  const PluginRegistry* registry;
  const EvaluationOptions* options;
  const EnvironmentFactory* make_environment;
  std::string scratch_dir;  // the run's temporary folder (sandboxed policies' folders)
};

// The worker process's whole life on socket `fd`: set up, report kReady (or
// kSetupError), run episodes until the socket closes; returns the
// process's exit status (WorkerPool's body: the pool's exit path ends it).
int runWorker(int fd, Slot& slot, const WorkerContext& context);

}  // namespace manibench::evaluation_detail
