#include <manibench/worker_pool.hpp>

#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <stdexcept>

namespace manibench {

Child spawnChild(const ChildOptions& options, const std::function<int(int fd)>& body) {
  Child child;
  int fds[2] = {-1, -1};
  if (options.channel && socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) {
    child.error = std::string("cannot create a socket: ") + std::strerror(errno);
    return child;
  }
  // Buffered output would otherwise be written twice, once by the child.
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    child.error = std::string("cannot fork: ") + std::strerror(errno);
    if (options.channel) {
      close(fds[0]);
      close(fds[1]);
    }
    return child;
  }
  if (pid == 0) {
    if (options.channel) close(fds[0]);
    for (int fd : options.close_in_child) close(fd);
    if (options.die_with_parent) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(1);
    }
    if (options.own_process_group) setpgid(0, 0);
    if (options.ignore_interrupt) signal(SIGINT, SIG_IGN);
    if (options.ignore_termination) {
      signal(SIGTERM, SIG_IGN);
      signal(SIGHUP, SIG_IGN);
    }
    signal(SIGPIPE, SIG_DFL);
    int status = 70;
    try {
      status = body(options.channel ? fds[1] : -1);
    } catch (...) {
      // Whatever escaped: the parent reads the exit status as a crash.
    }
    std::fflush(nullptr);
    _exit(status);
  }
  // Its own process group, set on both sides: whichever runs first.
  if (options.own_process_group) setpgid(pid, pid);
  if (options.channel) close(fds[1]);
  child.pid = pid;
  child.fd = fds[0];
  return child;
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
  if (status == -1) return "gone, its status unknown (the process that started it has gone)";
  if (WIFSIGNALED(status)) return "killed by " + describeSignal(WTERMSIG(status));
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "stopped (wait status " + std::to_string(status) + ")";
}

int waitForChild(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    // ECHILD: not (or no longer) this process's child; nothing to wait for.
    if (errno != EINTR) return 0;
  }
  return status;
}

bool findChildExit(pid_t pid, int& status) {
  int got = 0;
  pid_t r = -1;
  while ((r = waitpid(pid, &got, WNOHANG)) < 0 && errno == EINTR) {
  }
  if (r != pid) return false;
  status = got;
  return true;
}

WorkerPool::WorkerPool(std::size_t count, Body body, ChildOptions options, Launch launch)
    : body_(std::move(body)), options_(std::move(options)), workers_(count) {
  if (launch == Launch::kZygote)
    zygote_ = std::make_unique<Zygote>([this](std::size_t i, int fd) { return body_(i, fd); });
}

WorkerPool::~WorkerPool() {
  stopAll();
  zygote_.reset();
}

void WorkerPool::start(std::size_t i) {
  Child child;
  if (zygote_) {
    child = zygote_->spawn(i);
  } else {
    ChildOptions options = options_;
    options.channel = true;
    for (const Worker& w : workers_)
      if (w.fd >= 0) options.close_in_child.push_back(w.fd);
    child = spawnChild(options, [this, i](int fd) { return body_(i, fd); });
  }
  if (child.pid < 0) throw std::runtime_error("cannot start a worker (" + child.error + ")");
  Worker& w = workers_[i];
  w = Worker();
  w.pid = child.pid;
  w.fd = child.fd;
}

int WorkerPool::stop(std::size_t i, bool kill) {
  Worker& w = workers_[i];
  int status = 0;
  if (w.fd >= 0) close(w.fd);
  w.fd = -1;
  if (w.pid > 0) {
    if (kill) ::kill(w.pid, SIGKILL);
    status = zygote_ ? zygote_->reap(w.pid) : waitForChild(w.pid);
  }
  w.pid = -1;
  return status;
}

void WorkerPool::stopAll() {
  for (std::size_t i = 0; i < workers_.size(); ++i) kill(i);
  for (std::size_t i = 0; i < workers_.size(); ++i) stop(i, false);
}

void WorkerPool::kill(std::size_t i) {
  if (workers_[i].pid > 0) ::kill(workers_[i].pid, SIGKILL);
}

bool WorkerPool::send(std::size_t i, const wire::Writer& message) {
  return workers_[i].fd >= 0 && wire::sendFrame(workers_[i].fd, message);
}

wire::Received WorkerPool::receive(std::size_t i, std::string& payload,
                                   std::chrono::steady_clock::time_point deadline) {
  Worker& w = workers_[i];
  if (w.fd < 0) return wire::Received::kClosed;
  return wire::receiveFrame(w.fd, payload, deadline);
}

void WorkerPool::read(std::size_t i, const FrameHandler& on_frame, const EndHandler& on_end) {
  Worker& w = workers_[i];
  char chunk[65536];
  const ssize_t got = ::read(w.fd, chunk, sizeof(chunk));
  if (got < 0 && errno == EINTR) return;
  if (got <= 0) {
    const int status = stop(i, false);
    on_end(i, status);
    return;
  }
  w.buffer.append(chunk, static_cast<std::size_t>(got));
  const int fd = w.fd;
  std::string payload;
  // A handler that stops (or restarts) the worker ends what it sent.
  while (workers_[i].fd == fd && wire::takeFrame(workers_[i].buffer, payload)) on_frame(i, payload);
}

bool WorkerPool::poll(int timeout_ms, const FrameHandler& on_frame, const EndHandler& on_end) {
  std::vector<pollfd> fds;
  std::vector<std::size_t> owners;
  for (std::size_t i = 0; i < workers_.size(); ++i)
    if (workers_[i].fd >= 0) {
      fds.push_back({workers_[i].fd, POLLIN, 0});
      owners.push_back(i);
    }
  if (fds.empty()) return false;
  const int ready = ::poll(fds.data(), fds.size(), timeout_ms);
  if (ready < 0 && errno != EINTR) throw std::runtime_error(std::string("poll failed: ") + std::strerror(errno));
  for (std::size_t k = 0; ready > 0 && k < fds.size(); ++k)
    if ((fds[k].revents & (POLLIN | POLLHUP | POLLERR)) && workers_[owners[k]].fd == fds[k].fd)
      read(owners[k], on_frame, on_end);
  return true;
}

}  // namespace manibench
