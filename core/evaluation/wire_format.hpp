// The messages between the evaluation's coordinator and its workers, over a
// Unix socket pair: a u32 length, then a payload written by Writer. Both
// ends are this same binary, so host byte order is fine.
#pragma once

#include <manibench/trajectory.hpp>
#include <manibench/evaluation.hpp>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace manibench::evaluation_detail {

// Writer and Reader share one vocabulary, field(x), so that the layout of a
// message is written once (the transfer* functions below) for both ends.
class Writer {
 public:
  Writer& u8(uint8_t v) { return raw(&v, 1); }
  Writer& u32(uint32_t v) { return raw(&v, 4); }
  Writer& u64(uint64_t v) { return raw(&v, 8); }
  Writer& i64(int64_t v) { return raw(&v, 8); }
  Writer& f64(double v) { return raw(&v, 8); }
  Writer& str(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    data_ += s;
    return *this;
  }
  Writer& strings(const std::vector<std::string>& list) {
    u32(static_cast<uint32_t>(list.size()));
    for (const std::string& s : list) str(s);
    return *this;
  }
  // Numbers, flags and enums as their bytes.
  template <class T>
  void field(const T& v) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>, "no layout for this type");
    raw(&v, sizeof(T));
  }
  void field(const std::string& v) { str(v); }
  void field(const std::vector<std::string>& v) { strings(v); }
  // Arrays of numbers: a u64 count, then their bytes.
  template <class T>
  void field(const std::vector<T>& v) {
    static_assert(std::is_arithmetic_v<T>, "no layout for this type");
    u64(v.size());
    raw(v.data(), v.size() * sizeof(T));
  }
  template <class... T>
  void fields(const T&... v) {
    (field(v), ...);
  }
  const std::string& data() const { return data_; }

 private:
  Writer& raw(const void* p, std::size_t n) {
    data_.append(static_cast<const char*>(p), n);
    return *this;
  }
  std::string data_;
};

// Reads what a Writer wrote; a payload that ends early throws
// std::runtime_error.
class Reader {
 public:
  explicit Reader(const std::string& data) : data_(data) {}
  uint8_t u8() { return get<uint8_t>(); }
  uint32_t u32() { return get<uint32_t>(); }
  uint64_t u64() { return get<uint64_t>(); }
  int64_t i64() { return get<int64_t>(); }
  double f64() { return get<double>(); }
  std::string str() {
    const uint32_t n = u32();
    need(n);
    std::string s = data_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::vector<std::string> strings() {
    std::vector<std::string> list(u32());
    for (std::string& s : list) s = str();
    return list;
  }
  template <class T>
  void field(T& v) {
    v = get<T>();
  }
  void field(std::string& v) { v = str(); }
  void field(std::vector<std::string>& v) { v = strings(); }
  template <class T>
  void field(std::vector<T>& v) {
    static_assert(std::is_arithmetic_v<T>, "no layout for this type");
    const uint64_t n = u64();
    if (n > (data_.size() - pos_) / sizeof(T)) throw std::runtime_error("truncated message from a worker");
    v.resize(n);
    // An empty vector's data() may be null, which memcpy must not get.
    if (n > 0) std::memcpy(v.data(), data_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
  }
  template <class... T>
  void fields(T&... v) {
    (field(v), ...);
  }

 private:
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  void need(std::size_t n) {
    if (pos_ + n > data_.size()) throw std::runtime_error("truncated message from a worker");
  }
  const std::string& data_;
  std::size_t pos_ = 0;
};

// The first byte of every payload.
enum Message : uint8_t {
  kReady = 1,       // worker -> coordinator: set up; the task as configured
  kSetupError = 2,  // worker -> coordinator: could not set up; why
  kResult = 3,      // worker -> coordinator: one episode's record
  kRun = 10,        // coordinator -> worker: run this episode
};

// Writes one whole message; false when the other end is gone.
bool sendMessage(int fd, const Writer& w);
// Blocking read of one message (the worker's side); false at end of stream.
bool receiveMessage(int fd, std::string& payload);
// Moves the first whole message of `buffer` (bytes received so far, the
// coordinator's side) into `payload`; false while none is complete.
bool takeMessage(std::string& buffer, std::string& payload);

// The payloads after their Message byte, written (Stream = Writer, const
// records) or read (Stream = Reader) field by field.

// kReady: the task as the worker's environment configures it.
template <class Stream, class Info>
void transferReady(Stream& s, Info& info) {
  s.fields(info.observation_mode, info.controller, info.condition_names, info.split_objects,
           info.max_episode_steps, info.action_dim, info.observation_dim);
}

// kRun: the episode to run.
template <class Stream, class Spec>
void transferRun(Stream& s, Spec& spec) {
  s.fields(spec.index, spec.object_id, spec.level, spec.seed);
}

// kResult: the episode's index (of its spec, which the coordinator has
// whole), then its outcome.
template <class Stream, class Record>
void transferResult(Stream& s, Record& r) {
  s.fields(r.spec.index, r.steps, r.total_reward, r.success, r.flags, r.failure, r.failure_step,
           r.message, r.seconds);
}

// After kResult's record: a recorded trajectory (a u8 says whether one
// follows), then a u8: whether the worker leaves after this episode.
template <class Stream, class Recorded>
void transferTrajectory(Stream& s, Recorded& t) {
  s.fields(t.object_id, t.level, t.seed, t.steps, t.success, t.total_reward, t.action_dim,
           t.condition_count, t.actions, t.policy_actions, t.rewards, t.terminated, t.truncated, t.success_flags,
           t.conditions, t.mode, t.state_dim, t.state, t.mask_count, t.point_counts, t.xyz,
           t.point_rgb, t.point_masks, t.camera_count, t.height, t.width, t.image_rgb, t.image_rgb_bytes,
           t.depth, t.image_masks, t.env_states, t.env_state_offsets);
}

}  // namespace manibench::evaluation_detail
