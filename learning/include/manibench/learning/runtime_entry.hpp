// The one function libmanibench_learning_runtime exports for the
// torch_policy plugin, which opens the library with dlopen (so that loading
// the plugin does not load libtorch). Both are built from this tree with
// the same compiler and SDK, so a C++ object may cross: the policy the
// plugin then owns and calls through sdk::Policy's virtual functions.
#pragma once

#include <cstddef>

namespace manibench::sdk {
class Policy;
struct PolicyContext;
}  // namespace manibench::sdk

// A new policy, or nullptr with the reason in `error`.
extern "C" __attribute__((visibility("default"))) manibench::sdk::Policy* manibench_learning_make_policy(
    const char* config_yaml, const manibench::sdk::PolicyContext* context, char* error, std::size_t error_size);
using ManibenchLearningMakePolicy = manibench::sdk::Policy* (*)(const char*, const manibench::sdk::PolicyContext*,
                                                              char*, std::size_t);
inline constexpr const char* kManibenchLearningMakePolicy = "manibench_learning_make_policy";
inline constexpr const char* kManibenchLearningRuntimeFile = "libmanibench_learning_runtime.so";
