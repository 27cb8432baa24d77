// A family generator's object ids: the numbers of a range per split
// ("train 3000-3029, test 3100-3109"), written plainly.
#pragma once

#include <manibench/kit/common.hpp>

#include <optional>
#include <string>
#include <vector>

namespace manibench::kit {

// A generator's object ids: the numbers [first, first + count) of each split.
struct NumberedIds {
  struct Range {
    int first = 0, count = 0;
    bool contains(int n) const { return n >= first && n < first + count; }
    int last() const { return first + count - 1; }
  };
  Range train, test;

  // The ids of `split` ("train" or "test"), in order.
  std::vector<std::string> list(const std::string& split) const {
    const Range r = getRange(split);
    std::vector<std::string> ids;
    for (int i = 0; i < r.count; ++i) ids.push_back(std::to_string(r.first + i));
    return ids;
  }
  // Whether `id` is one of the test split (true), of the train split
  // (false), or not one of these numbers written plainly (nullopt).
  std::optional<bool> classify(const std::string& id) const {
    const std::optional<int> n = parse(id);
    if (!n) return std::nullopt;
    if (train.contains(*n)) return false;
    if (test.contains(*n)) return true;
    return std::nullopt;
  }
  // Whether `id` is a test id; any other text is an error (MB_NOT_FOUND)
  // naming `what` ("generated chair") and the ranges.
  bool requireTest(const std::string& id, const std::string& what) const {
    const std::optional<bool> test = classify(id);
    if (!test) throw Error("no " + what + " '" + id + "' (" + describe() + ")", MB_NOT_FOUND);
    return *test;
  }
  // "train 3000-3029, test 3100-3109", for errors.
  std::string describe() const {
    return "train " + std::to_string(train.first) + "-" + std::to_string(train.last()) + ", test " +
           std::to_string(test.first) + "-" + std::to_string(test.last());
  }
  // The number an id writes (digits only, no leading zero), or nullopt.
  static std::optional<int> parse(const std::string& id) {
    if (id.empty() || id.size() > 9 || id.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
    const int n = std::stoi(id);
    if (std::to_string(n) != id) return std::nullopt;
    return n;
  }
  static void checkSplit(const std::string& split) {
    if (split != "train" && split != "test")
      throw Error("unknown split '" + split + "' (use train or test)", MB_INVALID_ARGUMENT);
  }

 private:
  Range getRange(const std::string& split) const {
    checkSplit(split);
    return split == "train" ? train : test;
  }
};

}  // namespace manibench::kit
