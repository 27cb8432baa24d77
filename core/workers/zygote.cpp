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

bool readByte(int fd, char& byte) {
  for (;;) {
    const ssize_t n = ::read(fd, &byte, 1);
    if (n < 0 && errno == EINTR) continue;
    return n == 1;
  }
}

// The pid of a started worker and, with it, its channel as SCM_RIGHTS; pid
// 0 alone when none started.
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
  return sendmsg(control, &message, MSG_NOSIGNAL) >= 0;
}

// The zygote's life: each byte read on `control` is a request for a worker.
int runZygote(int control, const std::function<int(int fd)>& body) {
  signal(SIGCHLD, SIG_IGN);  // workers are reaped by the kernel
  char request = 0;
  while (readByte(control, request)) {
    ChildOptions options;
    options.close_in_child = {control};
    const Child child = spawnChild(options, [&body](int fd) {
      signal(SIGCHLD, SIG_DFL);  // a worker's own children are its to reap
      return body(fd);
    });
    const pid_t pid = child.pid > 0 ? child.pid : 0;
    const bool sent = sendWorker(control, pid, child.fd);
    if (pid > 0) close(child.fd);
    if (!sent) break;
  }
  return 0;
}

}  // namespace

Zygote::Zygote(std::function<int(int fd)> body) {
  ChildOptions options;
  options.ignore_termination = true;
  const Child zygote = spawnChild(options, [&body](int control) { return runZygote(control, body); });
  if (zygote.pid < 0) throw std::runtime_error(zygote.error);
  pid_ = zygote.pid;
  control_ = zygote.fd;
}

Zygote::~Zygote() {
  close(control_);
  int status = 0;
  while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
}

Child Zygote::spawn() {
  Child child;
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
  while ((n = ::send(control_, &request, 1, MSG_NOSIGNAL)) < 0 && errno == EINTR) {
  }
  if (n == 1)
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

}  // namespace manibench
