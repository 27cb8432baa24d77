// Wall time of the host's stages (manibench bench's stage table): the
// environment's physics and task, the observer's rendering and assembly.
#pragma once

#include <chrono>

namespace manibench {

using Clock = std::chrono::steady_clock;

// Seconds from `start` to now.
inline double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace manibench
