#include "wire_format.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <string>

namespace manibench::evaluation_detail {

bool sendMessage(int fd, const Writer& w) {
  if (w.data().size() > UINT32_MAX)
    throw std::runtime_error("a message of " + std::to_string(w.data().size()) +
                             " bytes is more than a frame holds (4 GiB)");
  const uint32_t size = static_cast<uint32_t>(w.data().size());
  std::string frame(reinterpret_cast<const char*>(&size), 4);
  frame += w.data();
  std::size_t sent = 0;
  while (sent < frame.size()) {
    const ssize_t n = ::send(fd, frame.data() + sent, frame.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

bool receiveMessage(int fd, std::string& payload) {
  auto readExact = [fd](char* p, std::size_t n) {
    while (n > 0) {
      const ssize_t got = ::read(fd, p, n);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      p += got;
      n -= static_cast<std::size_t>(got);
    }
    return true;
  };
  uint32_t size = 0;
  if (!readExact(reinterpret_cast<char*>(&size), 4)) return false;
  payload.resize(size);
  return readExact(payload.data(), size);
}

bool takeMessage(std::string& buffer, std::string& payload) {
  if (buffer.size() < 4) return false;
  uint32_t size = 0;
  std::memcpy(&size, buffer.data(), 4);
  if (buffer.size() < 4 + std::size_t(size)) return false;
  payload = buffer.substr(4, size);
  buffer.erase(0, 4 + std::size_t(size));
  return true;
}

}  // namespace manibench::evaluation_detail
