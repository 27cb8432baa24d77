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
// forks the workers for it (Zygote, below: learning's environment workers).
#pragma once

#include <manibench/wire_format.hpp>

#include <sys/types.h>

#include <cstddef>
#include <functional>
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

// W worker processes, each running `body(index, fd)` with a framed channel.
class WorkerPool {
 public:
  using Body = std::function<int(std::size_t index, int fd)>;
  // Starts none yet: start(i) each.
  WorkerPool(std::size_t count, Body body, ChildOptions options = {});
  // Kills the workers still running and waits for them.
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
  // leaves), kills it first when `kill`, waits for it: its wait status.
  int stop(std::size_t i, bool kill);
  // SIGKILLs worker i without waiting: its channel ends, which poll reports.
  void kill(std::size_t i);
  // Sends worker i one frame; false when it is gone (poll then reports it).
  bool send(std::size_t i, const wire::Writer& message);
  // Waits up to `timeout_ms` for the running workers' channels; hands each
  // whole frame to on_frame(i, payload) and each ended channel to
  // on_end(i), which is to stop(i, false) it (and may start it again). A
  // handler that stops worker i ends the handling of what i sent. Returns
  // false when no worker is running (nothing was waited for).
  bool poll(int timeout_ms, const std::function<void(std::size_t, const std::string&)>& on_frame,
            const std::function<void(std::size_t)>& on_end);

 private:
  struct Worker {
    pid_t pid = -1;
    int fd = -1;
    std::string buffer;  // bytes received, not yet a whole frame
  };
  void read(std::size_t i, const std::function<void(std::size_t, const std::string&)>& on_frame,
            const std::function<void(std::size_t)>& on_end);

  Body body_;
  ChildOptions options_;
  std::vector<Worker> workers_;
};

// A process forked early, before its parent has threads or state that must
// not cross a fork (libtorch's GNU OpenMP pool: the children hang), that
// forks the workers for it later, the first ones and the replacements: each
// is started by spawnChild in the zygote and tied to it, and its channel is
// handed to the parent (SCM_RIGHTS). The zygote and its workers ignore
// SIGINT, SIGTERM and SIGHUP (they reach the whole process group; the
// parent decides): when the parent closes a channel, or goes, they read
// end of stream and leave.
class Zygote {
 public:
  // Forks the zygote now; `body(fd)` runs in each worker. Throws
  // std::runtime_error when it cannot.
  explicit Zygote(std::function<int(int fd)> body);
  // Closes the control socket and waits for the zygote to leave.
  ~Zygote();
  Zygote(const Zygote&) = delete;
  Zygote& operator=(const Zygote&) = delete;

  // A new worker: its pid and the parent's end of its channel, or pid -1
  // and why (the zygote has gone or could not fork).
  Child spawn();

 private:
  pid_t pid_ = -1;
  int control_ = -1;
};

}  // namespace manibench
