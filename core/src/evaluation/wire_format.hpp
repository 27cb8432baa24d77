// The messages between the evaluation's coordinator and its workers, over a
// Unix socket pair: a u32 length, then a payload written by Writer. Both
// ends are this same binary, so host byte order is fine.
#pragma once

#include <manibench/evaluation.hpp>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench::evaluation_detail {

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

// The payloads after their Message byte.
void writeReady(Writer& w, const EvaluationTaskInfo& info);
EvaluationTaskInfo readReady(Reader& in);
void writeRun(Writer& w, const EpisodeSpec& spec);
EpisodeSpec readRun(Reader& in);
// Everything but the spec, which the coordinator has; returns its index.
void writeResult(Writer& w, const EpisodeRecord& record);
uint64_t readResult(Reader& in, EpisodeRecord& record);

}  // namespace manibench::evaluation_detail
