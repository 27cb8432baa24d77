#include <manibench/worker_pool.hpp>

#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace manibench {
namespace {

// A request to the zygote: start worker `value` (an index), or reap worker
// `value` (a pid). The answers: a started worker's pid with its channel
// (SCM_RIGHTS), pid 0 alone when none started; a reaped worker's wait
// status.
struct Request {
  uint64_t kind = 0;  // 64 bits: no padding goes over the socket
  uint64_t value = 0;
};
enum : uint64_t { kSpawn = 1, kReap = 2 };

bool readAll(int fd, void* to, std::size_t bytes) {
  char* p = static_cast<char*>(to);
  while (bytes > 0) {
    const ssize_t n = ::read(fd, p, bytes);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    bytes -= std::size_t(n);
  }
  return true;
}

bool writeAll(int fd, const void* from, std::size_t bytes) {
  const char* p = static_cast<const char*>(from);
  while (bytes > 0) {
    const ssize_t n = ::send(fd, p, bytes, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    bytes -= std::size_t(n);
  }
  return true;
}

bool sendWorker(int control, pid_t pid, int fd) {
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
    std::memcpy(CMSG_DATA(c), &fd, sizeof(int));
  }
  ssize_t n = -1;
  while ((n = sendmsg(control, &message, MSG_NOSIGNAL)) < 0 && errno == EINTR) {
  }
  return n >= 0;
}

// The zygote's life: one request after another, until the parent closes
// the control socket. Its workers are its children: it reaps each when the
// parent asks, and a zombie left when it goes is reaped by init.
int runZygote(int control, const std::function<int(std::size_t, int)>& body) {
  Request request;
  while (readAll(control, &request, sizeof request)) {
    if (request.kind == kReap) {
      const int status = waitForChild(pid_t(request.value));
      if (!writeAll(control, &status, sizeof status)) break;
      continue;
    }
    ChildOptions options;
    options.close_in_child = {control};
    const std::size_t index = std::size_t(request.value);
    const Child child = spawnChild(options, [&body, index](int fd) { return body(index, fd); });
    const pid_t pid = child.pid > 0 ? child.pid : 0;
    const bool sent = sendWorker(control, pid, child.fd);
    if (pid > 0) close(child.fd);
    if (!sent) break;
  }
  return 0;
}

}  // namespace

Zygote::Zygote(std::function<int(std::size_t index, int fd)> body) {
  ChildOptions options;
  options.ignore_termination = true;
  const Child zygote = spawnChild(options, [&body](int control) { return runZygote(control, body); });
  if (zygote.pid < 0) throw std::runtime_error(zygote.error);
  pid_ = zygote.pid;
  control_ = zygote.fd;
}

Zygote::~Zygote() {
  close(control_);
  waitForChild(pid_);
}

Child Zygote::spawn(std::size_t index) {
  Child child;
  Request request;
  request.kind = kSpawn;
  request.value = index;
  pid_t pid = 0;
  msghdr message{};
  iovec data{&pid, sizeof pid};
  message.msg_iov = &data;
  message.msg_iovlen = 1;
  alignas(cmsghdr) char control_buffer[CMSG_SPACE(sizeof(int))] = {};
  message.msg_control = control_buffer;
  message.msg_controllen = sizeof control_buffer;
  ssize_t n = -1;
  if (writeAll(control_, &request, sizeof request))
    while ((n = recvmsg(control_, &message, MSG_CMSG_CLOEXEC)) < 0 && errno == EINTR) {
    }
  const cmsghdr* c = n > 0 ? CMSG_FIRSTHDR(&message) : nullptr;
  if (pid <= 0 || c == nullptr || c->cmsg_type != SCM_RIGHTS) {
    child.error = "the worker launcher has gone or could not fork";
    return child;
  }
  std::memcpy(&child.fd, CMSG_DATA(c), sizeof(int));
  child.pid = pid;
  return child;
}

int Zygote::reap(pid_t pid) {
  Request request;
  request.kind = kReap;
  request.value = uint64_t(pid);
  int status = -1;
  if (!writeAll(control_, &request, sizeof request) || !readAll(control_, &status, sizeof status)) return -1;
  return status;
}

}  // namespace manibench
