// Shared helpers for the test programs (no manibench library: a test of any
// layer links them). The build tree's plugin registries: test_registry.hpp.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

namespace manibench::testing {

// Whether `text` contains `part`.
inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// The message of the E that `body` throws; "" and a test failure when it
// throws nothing (anything else propagates).
template <class E, class Body>
std::string catchMessage(Body&& body) {
  try {
    body();
  } catch (const E& e) {
    return e.what();
  }
  ADD_FAILURE() << "nothing was thrown";
  return "";
}

// Expects every one of `parts` in `message` (an error, say).
void expectMentions(const std::string& message, const std::vector<std::string>& parts);

// The bytes of a file ("" when it cannot be read).
std::string readFile(const std::string& path);

// A copy of tests/fixtures/<fixture> in a fresh temporary folder, to
// change or break; removed with the object.
class FixtureCopy {
 public:
  explicit FixtureCopy(const std::string& fixture);
  ~FixtureCopy();
  const std::string& folder() const { return folder_; }
  std::string file(const std::string& name) const { return folder_ + "/" + name; }
  // Replaces the first `from` in file `name` by `to`; a test failure when
  // `from` is not there.
  void replace(const std::string& name, const std::string& from, const std::string& to);
  FixtureCopy(const FixtureCopy&) = delete;  // one owner removes the folder
  FixtureCopy& operator=(const FixtureCopy&) = delete;

 private:
  std::string folder_;
};

// In a copy of partnet_mini: 100001's door made a flap across the
// cabinet's width, hinged along its bottom or top edge at the panel's back
// face (its handle 5.5-7.5 cm in front of the hinge), opening outward.
// Hinged at its bottom, the task leaves it out (it would open into the
// ground).
void makeFlap(FixtureCopy& copy, bool bottom);

// This process's resident memory (VmRSS), kB; -1 if unknown.
long readRssKb();

// Under AddressSanitizer (make sanitize) freed memory waits in a
// quarantine, so resident memory grows whatever the code does: the tests of
// flat memory skip themselves there.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitized = true;
#else
inline constexpr bool kAddressSanitized = false;
#endif

struct CommandResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs the built `manibench` CLI with `arguments` (each passed as one word),
// with extra environment assignments "NAME=value" in `environment`;
// `in_child` (may be empty) runs in the forked child just before the exec
// (e.g. to install a seccomp filter that the CLI and its children inherit).
CommandResult runCli(const std::vector<std::string>& arguments,
                     const std::vector<std::string>& environment = {},
                     const std::function<void()>& in_child = {});
// The same for another program (found in PATH when `program` has no slash).
CommandResult runProgram(const std::string& program, const std::vector<std::string>& arguments,
                         const std::vector<std::string>& environment = {},
                         const std::function<void()>& in_child = {});

}  // namespace manibench::testing
