// Shared pieces of the C++ SDK: errors, the exception-catching guard every
// trampoline uses, configuration, and the records plugins describe
// themselves with. Header-only; compiled into each plugin.
#pragma once

#include <manibench/abi.h>
#include <manibench/sdk/guard.hpp>
#include <manibench/sdk/numbers.hpp>
#include <manibench/sdk/segment.hpp>

#include <yaml-cpp/yaml.h>

#include <stdexcept>

// An Eigen assertion inside a plugin (a size mismatch, say) must not abort
// the host: it throws, and the trampolines report it. Effective when this
// header is included before any Eigen header.
#ifndef eigen_assert
#define eigen_assert(condition)                                              \
  do {                                                                       \
    if (!(condition))                                                        \
      throw std::logic_error("Eigen assertion failed: " #condition);         \
  } while (false)
#endif

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

// SDK internals are hidden in every plugin so two plugins never share (or
// interpose) each other's registration tables.
#define MANIBENCH_SDK_HIDDEN __attribute__((visibility("hidden")))

namespace manibench::sdk {

namespace detail {

// Copies a filled output struct into the caller's, which may be older and
// smaller: only the fields below the caller's struct_size are written.
template <class Info>
void writeOutputStruct(Info* out, const Info& filled) noexcept {
  const uint32_t n = out->struct_size < sizeof(Info) ? out->struct_size : uint32_t(sizeof(Info));
  std::memcpy(out, &filled, n);
  out->struct_size = n;
}

// Runs `body` as guardBoundary does, a YAML error (a plugin reading its
// configuration) becoming MB_INVALID_ARGUMENT with "configuration: ".
template <class Body>
mb_status guard(mb_error* err, Body&& body) noexcept {
  return guardBoundary(err, [&] {
    try {
      body();
    } catch (const YAML::Exception& e) {
      throw Error(std::string("configuration: ") + e.what(), MB_INVALID_ARGUMENT);
    }
  });
}

}  // namespace detail

// Levenshtein distance: how far a mistyped key is from a known one.
inline std::size_t calcEditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// A plugin's configuration: the YAML text the host passes at creation.
class Config {
 public:
  Config() = default;
  explicit Config(const char* yaml_text)
      : node_(yaml_text && *yaml_text ? YAML::Load(yaml_text) : YAML::Node()) {}
  explicit Config(YAML::Node node) : node_(std::move(node)) {}

  const YAML::Node& node() const { return node_; }
  bool has(const std::string& key) const {
    return node_.IsMap() && node_[key].IsDefined();
  }
  // The value at `key`, or `fallback` when absent; a value of the wrong type
  // is an error naming the key and the line.
  // Booleans follow YAML 1.2 as the host's configuration does: true or
  // false (any case), not yes/no/on/off.
  template <class T>
  T get(const std::string& key, const T& fallback) const {
    if (!has(key)) return fallback;
    const YAML::Node value = node_[key];
    if constexpr (std::is_same_v<T, bool>) {
      const std::string text = value.IsScalar() ? value.Scalar() : std::string();
      if (text == "true" || text == "True" || text == "TRUE") return true;
      if (text == "false" || text == "False" || text == "FALSE") return false;
      throw Error("configuration key '" + key + "' (line " + std::to_string(value.Mark().line + 1) +
                      ") must be true or false, got '" + text + "'",
                  MB_INVALID_ARGUMENT);
    }
    try {
      return value.as<T>();
    } catch (const YAML::Exception&) {
      throw Error("configuration key '" + key + "' (line " +
                      std::to_string(value.Mark().line + 1) +
                      ") has the wrong type",
                  MB_INVALID_ARGUMENT);
    }
  }
  Config child(const std::string& key) const {
    return has(key) ? Config(node_[key]) : Config();
  }
  // Refuses keys other than `known` (a typo would otherwise be ignored in
  // silence), naming the key and the closest known key.
  void requireKnownKeys(const std::vector<std::string>& known, const std::string& what) const {
    if (!node_.IsMap()) return;
    for (auto it = node_.begin(); it != node_.end(); ++it) {
      const std::string key = it->first.Scalar();
      if (std::find(known.begin(), known.end(), key) != known.end()) continue;
      std::string closest;
      std::size_t best = std::string::npos;
      for (const std::string& k : known) {
        const std::size_t d = calcEditDistance(key, k);
        if (d < best) {
          best = d;
          closest = k;
        }
      }
      // No line: the host hands a plugin its section re-emitted, and adds
      // where the key was set itself (annotatePluginError).
      throw Error(what + ": unknown key '" + key + "'" + (best <= 2 ? ", did you mean '" + closest + "'?" : ""),
                  MB_INVALID_ARGUMENT);
    }
  }

 private:
  YAML::Node node_;
};

// Holds segments and the C records pointing into them.
class SegmentTable {
 public:
  SegmentTable() = default;
  explicit SegmentTable(std::vector<Segment> segments)
      : segments_(std::move(segments)) {
    uint32_t offset = 0;
    for (Segment& s : segments_) {
      s.offset = offset;  // offsets follow from the order
      records_.push_back(s.toC());
      offset += s.size;
    }
    total_ = offset;
  }
  SegmentTable(const SegmentTable&) = delete;
  SegmentTable& operator=(const SegmentTable&) = delete;
  uint32_t total() const { return total_; }
  uint32_t count() const { return static_cast<uint32_t>(records_.size()); }
  const mb_segment* data() const { return records_.data(); }

 private:
  std::vector<Segment> segments_;
  std::vector<mb_segment> records_;
  uint32_t total_ = 0;
};

// Holds strings and the C array of pointers to them.
class StringTable {
 public:
  StringTable() = default;
  explicit StringTable(std::vector<std::string> strings)
      : strings_(std::move(strings)) {
    for (const std::string& s : strings_) pointers_.push_back(s.c_str());
  }
  StringTable(const StringTable&) = delete;
  StringTable& operator=(const StringTable&) = delete;
  uint32_t count() const { return static_cast<uint32_t>(pointers_.size()); }
  const char* const* data() const { return pointers_.data(); }
  const std::vector<std::string>& strings() const { return strings_; }

 private:
  std::vector<std::string> strings_;
  std::vector<const char*> pointers_;
};

inline void checkVectorSize(const char* what, std::size_t expected,
                            std::size_t got) {
  if (expected != got)
    throw Error(std::string(what) + ": expected " + std::to_string(expected) +
                    " values, got " + std::to_string(got),
                MB_INVALID_ARGUMENT);
}

}  // namespace manibench::sdk
