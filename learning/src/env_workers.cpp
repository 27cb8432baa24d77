#include <manibench/learning/env_workers.hpp>
#include <manibench/learning/spec.hpp>

#include <manibench/environment.hpp>
#include <manibench/stopwatch.hpp>

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

// --- messages: a u64 length, then the bytes -----------------------------------------------

class Writer {
 public:
  template <class T>
  void put(const T& value) {
    const auto* p = reinterpret_cast<const uint8_t*>(&value);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  void putBytes(const void* data, std::size_t size) {
    put<uint64_t>(size);
    const auto* p = static_cast<const uint8_t*>(data);
    bytes.insert(bytes.end(), p, p + size);
  }
  void putString(const std::string& s) { putBytes(s.data(), s.size()); }
  void putVector(const Eigen::VectorXd& v) { putBytes(v.data(), std::size_t(v.size()) * sizeof(double)); }
  std::vector<uint8_t> bytes;
};

class Reader {
 public:
  explicit Reader(const std::vector<uint8_t>& bytes) : bytes_(bytes) {}
  template <class T>
  T get() {
    T value;
    std::memcpy(&value, take(sizeof(T)), sizeof(T));
    return value;
  }
  std::vector<uint8_t> getBytes() {
    const uint64_t size = get<uint64_t>();
    const uint8_t* p = take(size);
    return std::vector<uint8_t>(p, p + size);
  }
  std::string getString() {
    const std::vector<uint8_t> b = getBytes();
    return std::string(b.begin(), b.end());
  }
  Eigen::VectorXd getVector() {
    const uint64_t size = get<uint64_t>();
    Eigen::VectorXd v(Eigen::Index(size / sizeof(double)));
    std::memcpy(v.data(), take(size), size);
    return v;
  }

 private:
  const uint8_t* take(std::size_t size) {
    if (position_ + size > bytes_.size()) throw std::runtime_error("a worker message cut short");
    const uint8_t* p = bytes_.data() + position_;
    position_ += size;
    return p;
  }
  const std::vector<uint8_t>& bytes_;
  std::size_t position_ = 0;
};

std::string formatSeconds(double seconds) {
  std::ostringstream out;
  out << seconds;
  return out.str();
}

bool writeAll(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::send(fd, p, size, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= std::size_t(n);
  }
  return true;
}

enum class ReadResult { kOk, kClosed, kTimedOut };

// Waits until `fd` is readable or `deadline` (none: Clock's max) passes.
bool waitReadable(int fd, Clock::time_point deadline) {
  for (;;) {
    int timeout_ms = -1;
    if (deadline != Clock::time_point::max()) {
      const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
      if (left <= 0) return false;
      timeout_ms = int(std::min(std::ceil(left * 1e3), 1e9));
    }
    pollfd p{fd, POLLIN, 0};
    const int n = ::poll(&p, 1, timeout_ms);
    if (n > 0) return true;  // readable, or closed / failed: read() says which
    if (n < 0 && errno != EINTR) return true;
  }
}

ReadResult readAll(int fd, void* data, std::size_t size, Clock::time_point deadline) {
  auto* p = static_cast<uint8_t*>(data);
  while (size > 0) {
    if (!waitReadable(fd, deadline)) return ReadResult::kTimedOut;
    const ssize_t n = ::read(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return ReadResult::kClosed;
    p += n;
    size -= std::size_t(n);
  }
  return ReadResult::kOk;
}

bool readAll(int fd, void* data, std::size_t size) {
  auto* p = static_cast<uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::read(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= std::size_t(n);
  }
  return true;
}

bool writeMessage(int fd, const std::vector<uint8_t>& message) {
  const uint64_t size = message.size();
  return writeAll(fd, &size, sizeof size) && writeAll(fd, message.data(), message.size());
}

bool readMessage(int fd, std::vector<uint8_t>& message) {
  uint64_t size = 0;
  if (!readAll(fd, &size, sizeof size)) return false;
  message.resize(size);
  return readAll(fd, message.data(), size);
}

ReadResult readMessage(int fd, std::vector<uint8_t>& message, Clock::time_point deadline) {
  uint64_t size = 0;
  const ReadResult r = readAll(fd, &size, sizeof size, deadline);
  if (r != ReadResult::kOk) return r;
  message.resize(size);
  return readAll(fd, message.data(), size, deadline);
}

// --- the worker process -------------------------------------------------------------------

void putStep(Writer& w, const Environment& env, const StepResult& r, double seconds) {
  w.put<uint8_t>(1);
  w.putVector(env.getObservation());
  w.put<double>(r.reward);
  w.put<uint8_t>(r.terminated);
  w.put<uint8_t>(r.truncated);
  w.put<uint8_t>(r.success);
  w.put<double>(seconds);
  w.putBytes(nullptr, 0);
}

std::vector<uint8_t> answer(Environment* env, const std::string& make_error, const std::vector<uint8_t>& request) {
  Writer w;
  try {
    if (!env) throw std::runtime_error("cannot make the environment: " + make_error);
    Reader r(request);
    const Clock::time_point started = Clock::now();
    switch (r.get<uint8_t>()) {
      case kReset: {
        const std::string object = r.getString();
        env->reset(object, r.get<uint64_t>());
        putStep(w, *env, StepResult(), secondsSince(started));
        break;
      }
      case kStep: {
        const StepResult result = env->step(r.getVector());
        putStep(w, *env, result, secondsSince(started));
        break;
      }
      case kSaveState: {
        const std::vector<uint8_t> state = env->saveState();
        putStep(w, *env, StepResult(), 0);
        w.bytes.resize(w.bytes.size() - sizeof(uint64_t));
        w.putBytes(state.data(), state.size());
        break;
      }
      case kRestoreState:
        env->restoreState(r.getBytes());
        putStep(w, *env, StepResult(), secondsSince(started));
        break;
      default:
        throw std::runtime_error("an unknown request");
    }
  } catch (const std::exception& e) {
    w.bytes.clear();
    w.put<uint8_t>(0);
    w.putString(e.what());
  }
  return std::move(w.bytes);
}

[[noreturn]] void runWorker(int fd, const EnvironmentWorkers::Factory& factory) {
  signal(SIGCHLD, SIG_DFL);
  std::unique_ptr<Environment> env;
  std::string make_error;
  try {
    env = factory();
  } catch (const std::exception& e) {
    make_error = e.what();
  }
  std::vector<uint8_t> request;
  while (readMessage(fd, request))
    if (!writeMessage(fd, answer(env.get(), make_error, request))) break;
  _exit(0);
}

// --- the zygote ---------------------------------------------------------------------------

// Each byte read is a request for a worker; answered with the worker's pid
// and its socket (SCM_RIGHTS), or pid 0 when the fork failed.
[[noreturn]] void runZygote(int control, const EnvironmentWorkers::Factory& factory) {
  signal(SIGCHLD, SIG_IGN);  // workers are reaped by the kernel
  char request = 0;
  while (readAll(control, &request, 1)) {
    int pair[2];
    pid_t pid = 0;
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair) == 0) {
      pid = fork();
      if (pid == 0) {
        close(control);
        close(pair[0]);
        runWorker(pair[1], factory);
      }
      close(pair[1]);
      if (pid < 0) pid = 0;
    }
    msghdr message{};
    iovec data{&pid, sizeof pid};
    message.msg_iov = &data;
    message.msg_iovlen = 1;
    alignas(cmsghdr) char control_buffer[CMSG_SPACE(sizeof(int))] = {};
    if (pid > 0) {
      message.msg_control = control_buffer;
      message.msg_controllen = sizeof control_buffer;
      cmsghdr* c = CMSG_FIRSTHDR(&message);
      c->cmsg_level = SOL_SOCKET;
      c->cmsg_type = SCM_RIGHTS;
      c->cmsg_len = CMSG_LEN(sizeof(int));
      std::memcpy(CMSG_DATA(c), &pair[0], sizeof(int));
    }
    const bool sent = sendmsg(control, &message, MSG_NOSIGNAL) >= 0;
    if (pid > 0) close(pair[0]);
    if (!sent) break;
  }
  _exit(0);
}

}  // namespace

EnvironmentWorkers::EnvironmentWorkers(Factory factory, unsigned count) {
  if (count == 0) throw LearningError("at least one environment worker is needed");
  int control[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, control) != 0)
    throw LearningError(std::string("cannot start the environment workers: ") + std::strerror(errno));
  zygote_pid_ = fork();
  if (zygote_pid_ < 0) throw LearningError(std::string("cannot fork: ") + std::strerror(errno));
  if (zygote_pid_ == 0) {
    // Ctrl-C reaches the whole process group: the learner stops the run
    // and its workers with it.
    signal(SIGINT, SIG_IGN);
    signal(SIGTERM, SIG_IGN);
    signal(SIGHUP, SIG_IGN);
    close(control[0]);
    runZygote(control[1], factory);
  }
  close(control[1]);
  zygote_fd_ = control[0];
  for (unsigned i = 0; i < count; ++i) workers_.push_back(spawn());
}

EnvironmentWorkers::~EnvironmentWorkers() {
  for (Worker& w : workers_) close(w.fd);
  close(zygote_fd_);
  int status = 0;
  while (waitpid(zygote_pid_, &status, 0) < 0 && errno == EINTR) {
  }
}

EnvironmentWorkers::Worker EnvironmentWorkers::spawn() {
  const char request = 1;
  pid_t pid = 0;
  msghdr message{};
  iovec data{&pid, sizeof pid};
  message.msg_iov = &data;
  message.msg_iovlen = 1;
  alignas(cmsghdr) char control_buffer[CMSG_SPACE(sizeof(int))] = {};
  message.msg_control = control_buffer;
  message.msg_controllen = sizeof control_buffer;
  ssize_t n = -1;
  if (writeAll(zygote_fd_, &request, 1))
    while ((n = recvmsg(zygote_fd_, &message, MSG_CMSG_CLOEXEC)) < 0 && errno == EINTR) {
    }
  const cmsghdr* c = n > 0 ? CMSG_FIRSTHDR(&message) : nullptr;
  if (pid <= 0 || c == nullptr || c->cmsg_type != SCM_RIGHTS)
    throw LearningError("cannot start an environment worker (the worker launcher has gone or could not fork)");
  Worker w;
  std::memcpy(&w.fd, CMSG_DATA(c), sizeof(int));
  w.pid = pid;
  return w;
}

void EnvironmentWorkers::send(unsigned worker, const std::vector<uint8_t>& message) {
  Worker& w = workers_.at(worker);
  if (!w.lost && !writeMessage(w.fd, message)) w.lost = true;
}

void EnvironmentWorkers::sendReset(unsigned worker, const std::string& object_id, uint64_t seed) {
  Writer w;
  w.put<uint8_t>(kReset);
  w.putString(object_id);
  w.put<uint64_t>(seed);
  send(worker, w.bytes);
}

void EnvironmentWorkers::sendStep(unsigned worker, const Eigen::VectorXd& action) {
  Writer w;
  w.put<uint8_t>(kStep);
  w.putVector(action);
  send(worker, w.bytes);
}

void EnvironmentWorkers::sendSaveState(unsigned worker) {
  Writer w;
  w.put<uint8_t>(kSaveState);
  send(worker, w.bytes);
}

void EnvironmentWorkers::sendRestoreState(unsigned worker, const std::vector<uint8_t>& state) {
  Writer w;
  w.put<uint8_t>(kRestoreState);
  w.putBytes(state.data(), state.size());
  send(worker, w.bytes);
}

void EnvironmentWorkers::setReplyTimeout(double seconds) {
  if (!(seconds >= 0)) throw LearningError("the workers' reply timeout must be at least 0 s (0: none)");
  reply_timeout_ = seconds;
}

WorkerReply EnvironmentWorkers::receive(unsigned worker) {
  Worker& w = workers_.at(worker);
  std::vector<uint8_t> message;
  const Clock::time_point deadline =
      reply_timeout_ > 0 ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(reply_timeout_))
                         : Clock::time_point::max();
  const ReadResult read = w.lost ? ReadResult::kClosed : readMessage(w.fd, message, deadline);
  if (read != ReadResult::kOk) {
    const pid_t pid = w.pid;
    // A worker that hangs (a task stuck in a loop or a system call) is
    // killed: it is alive, so the pid is still its own. One that died is
    // gone already (the zygote's children are reaped by the kernel).
    if (read == ReadResult::kTimedOut) ::kill(pid, SIGKILL);
    close(w.fd);
    w = spawn();
    const std::string what = read == ReadResult::kTimedOut
                                 ? ") did not answer within " + formatSeconds(reply_timeout_) + " s; killed it"
                                 : ") died";
    throw WorkerDied(worker, "environment worker " + std::to_string(worker) + " (pid " + std::to_string(pid) + what +
                                 "; started pid " + std::to_string(w.pid) + " in its place");
  }
  Reader r(message);
  WorkerReply reply;
  reply.ok = r.get<uint8_t>() != 0;
  if (!reply.ok) {
    reply.error = r.getString();
    return reply;
  }
  reply.observation = r.getVector();
  reply.reward = r.get<double>();
  reply.terminated = r.get<uint8_t>() != 0;
  reply.truncated = r.get<uint8_t>() != 0;
  reply.success = r.get<uint8_t>() != 0;
  reply.physics_seconds = r.get<double>();
  reply.state = r.getBytes();
  return reply;
}

}  // namespace manibench::learning
