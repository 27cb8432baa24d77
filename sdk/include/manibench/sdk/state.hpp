// A plugin's episode state as bytes (ABI 1.2): what the host's state blobs
// (Environment::saveState, demonstrations replayed bit for bit, restoring
// an episode in its middle) hold of a task or a controller.
//
// The host restores an episode by resetting it from the episode's seed,
// which re-derives everything a reset chose, then setting the scene's state
// and handing each plugin the bytes it saved (abi.h, "state"). So a plugin
// saves only what changes during an episode outside the scene: filters,
// integrators, counters, phases. A task or controller with such state
// implements Stateful beside Task or Controller:
//
//   class MyController : public sdk::Controller, public sdk::Stateful {
//     void saveState(sdk::StateWriter& out) const override { out.writeMatrix(filtered_); }
//     void restoreState(sdk::StateReader& in) override { in.readMatrix(filtered_); }
//   };
//
// One without it saves nothing of its own (the SDK still saves what it keeps
// for the plugin, such as TaskSpec::success_hold_steps' count).
// `manibench demos replay --check` finds state that was missed: the replay
// parts ways with the recording at the first step that needed it.
#pragma once

#include <manibench/sdk/common.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace manibench::sdk {

class StateWriter {
 public:
  template <class T>
  void write(const T& value) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>,
                  "write numbers, enums, strings, vectors or Eigen matrices");
    writeBytes(&value, sizeof(T));
  }
  void write(const std::string& text) {
    write<uint64_t>(text.size());
    writeBytes(text.data(), text.size());
  }
  template <class T>
  void write(const std::vector<T>& values) {
    static_assert(std::is_arithmetic_v<T>, "vectors of numbers");
    write<uint64_t>(values.size());
    writeBytes(values.data(), values.size() * sizeof(T));
  }
  // Any dense Eigen matrix or vector (an Isometry3d: its .matrix()).
  template <class Derived>
  void writeMatrix(const Eigen::DenseBase<Derived>& m) {
    write<int64_t>(m.rows());
    write<int64_t>(m.cols());
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      for (Eigen::Index r = 0; r < m.rows(); ++r) write<double>(m(r, c));
  }
  void writeBytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const uint8_t*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
  }
  const std::vector<uint8_t>& bytes() const { return bytes_; }
  void clear() { bytes_.clear(); }

 private:
  std::vector<uint8_t> bytes_;
};

// Reads what a StateWriter wrote, in the same order; bytes that end early
// or do not fit (a matrix of another size) throw sdk::Error.
class StateReader {
 public:
  StateReader(const uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  template <class T>
  T read() {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>, "read numbers or enums");
    T value;
    readBytes(&value, sizeof(T));
    return value;
  }
  template <class T>
  void read(T& value) {
    value = read<T>();
  }
  void read(std::string& text) {
    const uint64_t n = read<uint64_t>();
    need(n);
    text.assign(reinterpret_cast<const char*>(data_ + position_), n);
    position_ += n;
  }
  template <class T>
  void read(std::vector<T>& values) {
    static_assert(std::is_arithmetic_v<T>, "vectors of numbers");
    const uint64_t n = read<uint64_t>();
    need(n * sizeof(T));
    values.resize(n);
    readBytes(values.data(), n * sizeof(T));
  }
  // A matrix of the size written: fixed-size ones must match, dynamic ones
  // are resized.
  template <class Derived>
  void readMatrix(Eigen::PlainObjectBase<Derived>& m) {
    const int64_t rows = read<int64_t>(), cols = read<int64_t>();
    if (rows < 0 || cols < 0 ||
        (Derived::RowsAtCompileTime != Eigen::Dynamic && rows != Derived::RowsAtCompileTime) ||
        (Derived::ColsAtCompileTime != Eigen::Dynamic && cols != Derived::ColsAtCompileTime))
      throw Error("state: a " + std::to_string(rows) + " x " + std::to_string(cols) +
                      " matrix where this plugin keeps another size",
                  MB_INVALID_ARGUMENT);
    need(uint64_t(rows) * uint64_t(cols) * sizeof(double));
    m.resize(rows, cols);
    for (Eigen::Index c = 0; c < cols; ++c)
      for (Eigen::Index r = 0; r < rows; ++r) m(r, c) = read<double>();
  }
  void readBytes(void* out, std::size_t size) {
    need(size);
    std::memcpy(out, data_ + position_, size);
    position_ += size;
  }
  bool atEnd() const { return position_ == size_; }
  std::size_t getRemaining() const { return size_ - position_; }

 private:
  void need(uint64_t size) const {
    if (size > size_ - position_)
      throw Error("state: the bytes end early (" + std::to_string(size_ - position_) +
                      " left, " + std::to_string(size) + " needed): not this plugin's state",
                  MB_INVALID_ARGUMENT);
  }
  const uint8_t* data_;
  std::size_t size_;
  std::size_t position_ = 0;
};

// A task or controller with episode state outside the scene (see above).
class Stateful {
 public:
  virtual ~Stateful() = default;
  virtual void saveState(StateWriter& out) const = 0;
  virtual void restoreState(StateReader& in) = 0;
};

namespace detail {

// The SDK's own framing of a plugin's state: a version, what the SDK keeps
// for the plugin (written by `save_sdk`), then the plugin's Stateful part.
constexpr uint32_t kSdkStateVersion = 1;

template <class Plugin, class SaveSdk>
mb_status saveState(const Plugin& plugin, SaveSdk&& save_sdk, uint8_t* out, uint64_t capacity,
                    uint64_t* out_size, mb_error* err) {
  return guard(err, [&] {
    if (out_size == nullptr) throw Error("get_state: no size to write", MB_INVALID_ARGUMENT);
    StateWriter writer;
    writer.write(kSdkStateVersion);
    save_sdk(writer);
    if (const auto* stateful = dynamic_cast<const Stateful*>(&plugin)) {
      writer.write<uint8_t>(1);
      stateful->saveState(writer);
    } else {
      writer.write<uint8_t>(0);
    }
    *out_size = writer.bytes().size();
    if (out != nullptr && capacity >= writer.bytes().size())
      std::memcpy(out, writer.bytes().data(), writer.bytes().size());
  });
}

template <class Plugin, class RestoreSdk>
mb_status restoreState(Plugin& plugin, RestoreSdk&& restore_sdk, const uint8_t* data,
                       uint64_t size, mb_error* err) {
  return guard(err, [&] {
    if (data == nullptr && size > 0) throw Error("set_state: no bytes", MB_INVALID_ARGUMENT);
    StateReader reader(data, size);
    const uint32_t version = reader.read<uint32_t>();
    if (version != kSdkStateVersion)
      throw Error("set_state: state written by SDK state version " + std::to_string(version) +
                      ", this plugin reads version " + std::to_string(kSdkStateVersion),
                  MB_INVALID_ARGUMENT);
    restore_sdk(reader);
    const bool saved_stateful = reader.read<uint8_t>() != 0;
    auto* stateful = dynamic_cast<Stateful*>(&plugin);
    if (saved_stateful != (stateful != nullptr))
      throw Error(saved_stateful ? "set_state: the state holds a part this plugin does not keep"
                                 : "set_state: the state lacks the part this plugin keeps",
                  MB_INVALID_ARGUMENT);
    if (stateful) stateful->restoreState(reader);
    if (!reader.atEnd())
      throw Error("set_state: " + std::to_string(reader.getRemaining()) +
                      " bytes left over: not this plugin's state",
                  MB_INVALID_ARGUMENT);
  });
}

}  // namespace detail
}  // namespace manibench::sdk
