// The one wire format of manibench's processes: every channel between a
// parent and its workers (evaluation, conversion, the learner's environment
// workers) and the records MPI ranks send carry payloads written by Writer
// and read by Reader; a channel frames each payload with its length.
//
// Both ends are this same binary, so numbers go in host byte order. The
// limits, stated once:
//   a frame: a u32 length, then the payload (at most kMaxFrameBytes);
//   a string or a list of strings: a u32 count, then the bytes / strings;
//   an array of numbers: a u64 count, then the numbers' bytes.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace manibench::wire {

// What one frame holds: its length is a u32.
constexpr uint64_t kMaxFrameBytes = UINT32_MAX;

// Writer and Reader share one vocabulary, field(x), so that the layout of a
// message is written once (a transfer function templated on the stream)
// for both ends.
class Writer {
 public:
  Writer& u8(uint8_t v) { return raw(&v, 1); }
  Writer& u32(uint32_t v) { return raw(&v, 4); }
  Writer& u64(uint64_t v) { return raw(&v, 8); }
  Writer& i64(int64_t v) { return raw(&v, 8); }
  Writer& f64(double v) { return raw(&v, 8); }
  Writer& str(const std::string& s) {
    if (s.size() > UINT32_MAX) throw std::length_error("a string of more than 4 GiB in a message");
    u32(static_cast<uint32_t>(s.size()));
    data_ += s;
    return *this;
  }
  Writer& strings(const std::vector<std::string>& list) {
    u32(static_cast<uint32_t>(list.size()));
    for (const std::string& s : list) str(s);
    return *this;
  }
  // An array of `n` numbers: a u64 count, then their bytes.
  template <class T>
  Writer& array(const T* p, std::size_t n) {
    static_assert(std::is_arithmetic_v<T>, "no layout for this type");
    u64(n);
    return raw(p, n * sizeof(T));
  }
  // Numbers, flags and enums as their bytes.
  template <class T>
  void field(const T& v) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>, "no layout for this type");
    raw(&v, sizeof(T));
  }
  void field(const std::string& v) { str(v); }
  void field(const std::vector<std::string>& v) { strings(v); }
  template <class T>
  void field(const std::vector<T>& v) {
    array(v.data(), v.size());
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
  // It keeps a reference: a temporary would be gone before the reading.
  explicit Reader(std::string&&) = delete;
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
  // An array's count, checked against what is left: then `take` its bytes.
  template <class T>
  std::size_t arrayCount() {
    static_assert(std::is_arithmetic_v<T>, "no layout for this type");
    const uint64_t n = u64();
    if (n > (data_.size() - pos_) / sizeof(T)) throw std::runtime_error("truncated message from a worker");
    return std::size_t(n);
  }
  // Copies the next `bytes` bytes to `to` (which may be null when 0).
  void take(void* to, std::size_t bytes) {
    need(bytes);
    // An empty vector's data() may be null, which memcpy must not get.
    if (bytes > 0) std::memcpy(to, data_.data() + pos_, bytes);
    pos_ += bytes;
  }
  template <class T>
  void field(T& v) {
    v = get<T>();
  }
  void field(std::string& v) { v = str(); }
  void field(std::vector<std::string>& v) { v = strings(); }
  template <class T>
  void field(std::vector<T>& v) {
    v.resize(arrayCount<T>());
    take(v.data(), v.size() * sizeof(T));
  }
  template <class... T>
  void fields(T&... v) {
    (field(v), ...);
  }

 private:
  template <class T>
  T get() {
    T v;
    take(&v, sizeof(T));
    return v;
  }
  void need(std::size_t n) {
    if (n > data_.size() - pos_) throw std::runtime_error("truncated message from a worker");
  }
  const std::string& data_;
  std::size_t pos_ = 0;
};

// Writes one whole frame (interrupted writes resumed); false when the other
// end is gone. A payload past kMaxFrameBytes throws std::length_error.
bool sendFrame(int fd, const std::string& payload);
inline bool sendFrame(int fd, const Writer& w) { return sendFrame(fd, w.data()); }

// Reads one whole frame into `payload`, blocking; false at end of stream.
bool receiveFrame(int fd, std::string& payload);

enum class Received { kFrame, kClosed, kTimedOut };
// The same, giving up at `deadline` (steady_clock's max: never).
Received receiveFrame(int fd, std::string& payload, std::chrono::steady_clock::time_point deadline);

// Moves the first whole frame of `buffer` (bytes received so far) into
// `payload`; false while none is complete.
bool takeFrame(std::string& buffer, std::string& payload);

}  // namespace manibench::wire
