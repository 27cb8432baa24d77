// Processes that do a run's work: the one place manibench forks
// (docs/architecture.md, "Worker processes").
//
// spawnChild starts one child process tied to this one; WorkerPool keeps W
// of them, each with a framed channel (wire_format.hpp), and lets its user
// run an event loop over their frames, replace a dead one and stop them
// all. What a unit of work is, and what a dead worker's unit becomes (a
// failed episode, trajectories not converted), stays its user's: the pool
// reports the end of a channel and the wait status.
//
// Why fork, and when: a worker builds its own environment, EGL context and
// policy after the fork, because EGL, llvmpipe's threads and GNU OpenMP's
// pool do not survive one. A parent that has such state by the time it
// forks (the learner, once libtorch runs) forks early a small process that
// forks the workers for it (Launch::kZygote: learning's environment workers).
#pragma once

#include <manibench/wire_format.hpp>

#include <sys/types.h>

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace manibench {

// How a child is tied to its parent.
struct ChildOptions {
  // A Unix stream socket pair: the child's end goes to its body, the
  // parent's is returned (close-on-exec on both sides).
  bool channel = true;
  // Killed (SIGKILL) when the parent dies (PR_SET_PDEATHSIG); a child whose
  // parent died before that was set leaves at once.
  bool die_with_parent = true;
  // Ctrl-C reaches the whole process group: the parent decides what stops.
  bool ignore_interrupt = true;
  // SIGTERM and SIGHUP ignored too (a child whose parent stops it by
  // closing its channel: learning's zygote and environment workers).
  bool ignore_termination = false;
  // A process group of its own (the sandboxed policy, whose whole group is
  // killed when it is replaced).
  bool own_process_group = false;
  // The parent's descriptors the child closes first: another worker's
  // channel held by a sibling would hide that worker's death (no end of
  // stream).
  std::vector<int> close_in_child;
};

struct Child {
  pid_t pid = -1;
  int fd = -1;        // the parent's end of the channel (-1 without one)
  std::string error;  // when pid is -1: why no child was started
};

// Flushes stdio (a buffered line would be written by both), forks and runs
// `body(fd)` in the child (fd: its end of the channel, or -1), which exits
// with the status body returns, or 70 when it throws. The parent gets the
// child's pid and its end of the channel, or an error.
Child spawnChild(const ChildOptions& options, const std::function<int(int fd)>& body);

// "signal 11 (SIGSEGV, Segmentation fault)"
std::string describeSignal(int sig);
// "killed by signal 11 (...)", "exited with status 3": a wait status.
std::string describeExit(int status);

// The one place a child is waited for (manibench's own children: workers,
// the zygote, the policy process, the programs a trainer runs). Waits for
// child `pid`, retrying when a signal interrupts: its wait status.
int waitForChild(pid_t pid);
// Without waiting: true, with its wait status, when child `pid` has ended
// (it is reaped); false while it runs.
bool findChildExit(pid_t pid, int& status);

class Zygote;

// Where a pool's workers are forked.
enum class Launch {
  // By this process, when each is started.
  kHere,
  // By a zygote this pool forks at once, in its constructor (Zygote, below):
  // for a parent that will have threads that must not cross a fork (the
  // learner, once libtorch runs) by the time it replaces a worker.
  kZygote,
};

// W worker processes, each running `body(index, fd)` with a framed channel.
// The pool owns them: it starts, kills and reaps each, and hands the one who
// runs the event loop each worker's end with its wait status. A worker
// leaves only through spawnChild's exit path: its body returns its status.
class WorkerPool {
 public:
  using Body = std::function<int(std::size_t index, int fd)>;
  using FrameHandler = std::function<void(std::size_t index, const std::string& payload)>;
  // Worker `index` has ended and been reaped: `status` is its wait status.
  // The handler may start it again.
  using EndHandler = std::function<void(std::size_t index, int status)>;
  // Starts none yet: start(i) each. Launch::kZygote forks the zygote now
  // (make the pool before libtorch runs: its OpenMP pool is what must not
  // cross the fork) and throws std::runtime_error when it cannot.
  WorkerPool(std::size_t count, Body body, ChildOptions options = {}, Launch launch = Launch::kHere);
  // stopAll(): nothing outlives the pool.
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  std::size_t size() const { return workers_.size(); }
  bool isRunning(std::size_t i) const { return workers_[i].fd >= 0; }
  pid_t getPid(std::size_t i) const { return workers_[i].pid; }
  // Starts worker i (its frames buffer emptied); throws std::runtime_error
  // when it cannot.
  void start(std::size_t i);
  // Closes worker i's channel (a waiting worker reads end of stream and
  // leaves), kills it first when `kill`, reaps it: its wait status (0 for
  // a worker not running).
  int stop(std::size_t i, bool kill);
  // Every running worker killed first, then each reaped: one slow to go
  // does not hold the others' kill back.
  void stopAll();
  // SIGKILLs worker i without waiting: its channel ends, which poll reports.
  void kill(std::size_t i);
  // Sends worker i one frame; false when it is gone (poll or receive then
  // reports it).
  bool send(std::size_t i, const wire::Writer& message);
  // Worker i's next frame, waiting until `deadline`, for a user that asks
  // one worker and waits for its answer (a worker is read either this way
  // or by poll, not both). Anything but kFrame: the worker is
  // not stopped yet (stop it, kill it first on kTimedOut, for its status).
  wire::Received receive(std::size_t i, std::string& payload, std::chrono::steady_clock::time_point deadline);
  // Waits up to `timeout_ms` for the running workers' channels; hands each
  // whole frame to on_frame(i, payload) and each ended channel, once the
  // worker is reaped, to on_end(i, status). A handler that stops (or
  // restarts) worker i ends the handling of what i sent. Returns false when
  // no worker is running (nothing was waited for).
  bool poll(int timeout_ms, const FrameHandler& on_frame, const EndHandler& on_end);

 private:
  struct Worker {
    pid_t pid = -1;
    int fd = -1;
    std::string buffer;  // bytes received, not yet a whole frame
  };
  void read(std::size_t i, const FrameHandler& on_frame, const EndHandler& on_end);

  Body body_;
  ChildOptions options_;
  std::unique_ptr<Zygote> zygote_;  // Launch::kZygote
  std::vector<Worker> workers_;
};

// A process forked early, before its parent has threads or state that must
// not cross a fork (libtorch's GNU OpenMP pool: the children hang), that
// forks the workers for it later, the first ones and the replacements: each
// is started by spawnChild in the zygote and tied to it, and its channel is
// handed to the parent (SCM_RIGHTS). The zygote reaps its workers for the
// parent (reap). The zygote and its workers ignore SIGINT, SIGTERM and
// SIGHUP (they reach the whole process group; the parent decides): when the
// parent closes a channel, or goes, they read end of stream and leave.
// WorkerPool's Launch::kZygote is its one user.
class Zygote {
 public:
  // Forks the zygote now; `body(index, fd)` runs in each worker. Throws
  // std::runtime_error when it cannot.
  explicit Zygote(std::function<int(std::size_t index, int fd)> body);
  // Closes the control socket and reaps the zygote.
  ~Zygote();
  Zygote(const Zygote&) = delete;
  Zygote& operator=(const Zygote&) = delete;

  // A new worker running body(index, ...): its pid and the parent's end of
  // its channel, or pid -1 and why (the zygote has gone or could not fork).
  Child spawn(std::size_t index);
  // Waits (in the zygote) for worker `pid` to end: its wait status, or -1
  // when the zygote has gone.
  int reap(pid_t pid);

 private:
  pid_t pid_ = -1;
  int control_ = -1;
};

}  // namespace manibench
