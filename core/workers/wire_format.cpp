#include <manibench/wire_format.hpp>

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>

namespace manibench::wire {
namespace {

using Clock = std::chrono::steady_clock;

// Waits until `fd` is readable, closed or failed (read() then says which),
// or `deadline` passes (false).
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
    if (n > 0 || (n < 0 && errno != EINTR)) return true;
  }
}

Received readExact(int fd, char* p, std::size_t n, Clock::time_point deadline) {
  while (n > 0) {
    if (deadline != Clock::time_point::max() && !waitReadable(fd, deadline)) return Received::kTimedOut;
    const ssize_t got = ::read(fd, p, n);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return Received::kClosed;
    p += got;
    n -= static_cast<std::size_t>(got);
  }
  return Received::kFrame;
}

}  // namespace

bool sendFrame(int fd, const std::string& payload) {
  if (payload.size() > kMaxFrameBytes)
    throw std::length_error("a message of " + std::to_string(payload.size()) +
                            " bytes is more than a frame holds (4 GiB)");
  const uint32_t size = static_cast<uint32_t>(payload.size());
  std::string frame(reinterpret_cast<const char*>(&size), 4);
  frame += payload;
  std::size_t sent = 0;
  while (sent < frame.size()) {
    // MSG_NOSIGNAL: a gone reader is a false return, not SIGPIPE.
    const ssize_t n = ::send(fd, frame.data() + sent, frame.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

Received receiveFrame(int fd, std::string& payload, Clock::time_point deadline) {
  uint32_t size = 0;
  const Received header = readExact(fd, reinterpret_cast<char*>(&size), 4, deadline);
  if (header != Received::kFrame) return header;
  payload.resize(size);
  return readExact(fd, payload.data(), size, deadline);
}

bool receiveFrame(int fd, std::string& payload) {
  return receiveFrame(fd, payload, Clock::time_point::max()) == Received::kFrame;
}

bool takeFrame(std::string& buffer, std::string& payload) {
  if (buffer.size() < 4) return false;
  uint32_t size = 0;
  std::memcpy(&size, buffer.data(), 4);
  if (buffer.size() < 4 + std::size_t(size)) return false;
  payload = buffer.substr(4, size);
  buffer.erase(0, 4 + std::size_t(size));
  return true;
}

}  // namespace manibench::wire
