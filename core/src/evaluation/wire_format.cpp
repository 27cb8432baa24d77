#include "wire_format.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>

namespace manibench::evaluation_detail {

bool sendMessage(int fd, const Writer& w) {
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

void writeReady(Writer& w, const EvaluationTaskInfo& info) {
  w.u8(static_cast<uint8_t>(info.observation_mode)).str(info.controller);
  w.strings(info.condition_names).strings(info.split_objects);
  w.u32(info.max_episode_steps).u32(info.action_dim).u32(info.observation_dim);
}

EvaluationTaskInfo readReady(Reader& in) {
  EvaluationTaskInfo info;
  info.observation_mode = static_cast<ObservationMode>(in.u8());
  info.controller = in.str();
  info.condition_names = in.strings();
  info.split_objects = in.strings();
  info.max_episode_steps = in.u32();
  info.action_dim = in.u32();
  info.observation_dim = in.u32();
  return info;
}

void writeRun(Writer& w, const EpisodeSpec& spec) {
  w.u64(spec.index).str(spec.object_id).u64(spec.level).u64(spec.seed);
}

EpisodeSpec readRun(Reader& in) {
  EpisodeSpec spec;
  spec.index = in.u64();
  spec.object_id = in.str();
  spec.level = in.u64();
  spec.seed = in.u64();
  return spec;
}

void writeResult(Writer& w, const EpisodeRecord& r) {
  w.u64(r.spec.index).u32(r.steps).f64(r.total_reward).u8(r.success ? 1 : 0);
  w.u32(static_cast<uint32_t>(r.flags.size()));
  for (uint8_t f : r.flags) w.u8(f);
  w.str(r.failure).i64(r.failure_step).str(r.message).f64(r.seconds);
}

uint64_t readResult(Reader& in, EpisodeRecord& r) {
  const uint64_t index = in.u64();
  r.steps = in.u32();
  r.total_reward = in.f64();
  r.success = in.u8() != 0;
  r.flags.resize(in.u32());
  for (uint8_t& f : r.flags) f = in.u8();
  r.failure = in.str();
  r.failure_step = in.i64();
  r.message = in.str();
  r.seconds = in.f64();
  return index;
}

}  // namespace manibench::evaluation_detail
