// Waiting on a word of memory shared between processes: make_vec's step
// block (python/src/step_block.cpp) and the evaluation's sandboxed policy
// block (core/evaluation/policy_process.cpp) spin briefly, then sleep here.
#pragma once

#include <linux/futex.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <climits>
#include <cstdint>

namespace manibench {

// Sleeps while `word` holds `expected`, at most `timeout_s` (0: no limit).
// Both processes map the same memory: the futex is keyed by the page, so
// no FUTEX_PRIVATE_FLAG.
inline void futexWait(std::atomic<uint32_t>& word, uint32_t expected, double timeout_s) {
  static_assert(sizeof(std::atomic<uint32_t>) == sizeof(uint32_t));
  timespec timeout{};
  timeout.tv_sec = time_t(timeout_s);
  timeout.tv_nsec = long((timeout_s - double(timeout.tv_sec)) * 1e9);
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(&word), FUTEX_WAIT, expected,
          timeout_s > 0 ? &timeout : nullptr, nullptr, 0);
}

// Wakes every process sleeping on `word`.
inline void futexWakeAll(std::atomic<uint32_t>& word) {
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(&word), FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
}

// The spin loop's pause (lets the sibling hyperthread run).
inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

}  // namespace manibench
