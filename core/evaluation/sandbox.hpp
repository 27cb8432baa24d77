// The sandbox of an evaluated policy's process (policy_process.cpp), made
// of facilities an unprivileged user gets on a stock Debian kernel, so that
// it holds the same as root, as a CI user and inside a container:
//
//   seccomp (libseccomp)  system calls: no sockets (no network), no new
//                         processes (clone without CLONE_THREAD, fork,
//                         vfork) and no programs (execve), signals only to
//                         itself, no access to other processes' memory
//                         (ptrace, process_vm_*), no new session or group,
//                         no namespaces, mounts, io_uring, BPF, keyrings,
//                         modules, no raised limits. A refused call traps
//                         (SIGSYS): the process records the call in its
//                         shared block and ends, and the environment's
//                         process names the call in the episode's message.
//   Landlock              files: read-only access to the system's libraries
//                         (/usr, /lib*, a few files of /etc, /proc and
//                         /sys the runtimes read), the policy's own files
//                         (its library or script folder, its configuration
//                         folder, --policy-read paths); read-write only in
//                         its private temporary directory. Landlock denies
//                         with EACCES ("Permission denied"): the policy sees
//                         an error, nothing is read or written. A kernel
//                         without Landlock (before 5.13, or not enabled)
//                         runs without the file rules, and the run says so.
//   rlimits               memory (RLIMIT_AS: the address space the policy
//                         may add), output (RLIMIT_FSIZE: its log and
//                         temporary files), no core files.
//   PR_SET_PDEATHSIG      the policy dies with the environment's process;
//                         it has a process group of its own, killed at its
//                         end.
// CPU time is measured by the environment's process (the policy's CPU
// clock per episode), which kills the policy past the limit.
//
// Namespaces (unshare) are not used: unprivileged user namespaces are off
// in many CI containers (Docker's default seccomp profile refuses
// unshare(CLONE_NEWUSER)) and restricted by Ubuntu's AppArmor, while
// seccomp and Landlock need no privilege. What a network namespace or a
// PID namespace would give (no network, no signals out) the seccomp rules
// give without one.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace manibench::evaluation_detail {

struct SandboxSettings {
  std::vector<std::string> read_paths;   // read-only (and the system's libraries)
  std::string private_dir;               // the only writable place
  uint64_t memory_bytes = 0;             // RLIMIT_AS beyond what is mapped at the start; 0: none
  uint64_t output_bytes = 0;             // RLIMIT_FSIZE; 0: none
  // Where the SIGSYS handler writes the refused call's number and first
  // argument (in the block the environment's process reads).
  int32_t* refused_syscall = nullptr;
  uint64_t* refused_argument = nullptr;
};

// Whether this kernel enforces Landlock; its ABI version (0: no).
int getLandlockAbi();

// Applies the sandbox to the calling process, in a process that has one
// thread (after fork). Throws std::runtime_error naming what failed.
void enterSandbox(const SandboxSettings& settings);

// "kill (a signal to a process outside the sandbox)": the refused call's
// name and why it is refused.
std::string describeRefusedCall(int32_t syscall_number, uint64_t first_argument);

// The exit status of a process that ended in the SIGSYS handler.
inline constexpr int kRefusedExitStatus = 121;

}  // namespace manibench::evaluation_detail
