#include "sandbox.hpp"

#include <manibench/evaluation.hpp>

#include <fcntl.h>
#include <linux/landlock.h>
#include <sched.h>
#include <seccomp.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <ucontext.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

// Rights of Landlock ABI 3 and 5, which Debian 12's kernel headers (6.1)
// predate; a kernel that knows them enforces them.
#ifndef LANDLOCK_ACCESS_FS_TRUNCATE
#define LANDLOCK_ACCESS_FS_TRUNCATE (1ULL << 14)
#endif
#ifndef LANDLOCK_ACCESS_FS_IOCTL_DEV
#define LANDLOCK_ACCESS_FS_IOCTL_DEV (1ULL << 15)
#endif

namespace manibench::evaluation_detail {
namespace {

int32_t* g_refused_syscall = nullptr;
uint64_t* g_refused_argument = nullptr;

// SIGSYS from a SECCOMP_RET_TRAP rule: records the call and ends the whole
// process (every thread), so that the refusal fails the episode whatever
// the policy would have done with an error code.
void onRefusedCall(int, siginfo_t* info, void* context) {
  if (g_refused_syscall) *g_refused_syscall = info->si_syscall;
  if (g_refused_argument) {
#if defined(__x86_64__)
    *g_refused_argument =
        uint64_t(static_cast<ucontext_t*>(context)->uc_mcontext.gregs[REG_RDI]);
#elif defined(__aarch64__)
    *g_refused_argument = uint64_t(static_cast<ucontext_t*>(context)->uc_mcontext.regs[0]);
#else
    (void)context;
#endif
  }
  syscall(SYS_exit_group, kRefusedExitStatus);
}

[[noreturn]] void fail(const std::string& what, int error) {
  throw std::runtime_error("cannot set up the policy's sandbox: " + what + ": " +
                           std::strerror(error));
}

// Landlock's file rights that this ABI version knows.
uint64_t calcHandledAccess(int abi) {
  uint64_t access = (LANDLOCK_ACCESS_FS_MAKE_SYM << 1) - 1;  // ABI 1: EXECUTE .. MAKE_SYM
  if (abi >= 2) access |= LANDLOCK_ACCESS_FS_REFER;
  if (abi >= 3) access |= LANDLOCK_ACCESS_FS_TRUNCATE;
  if (abi >= 5) access |= LANDLOCK_ACCESS_FS_IOCTL_DEV;
  return access;
}

// The rights that apply to a file (not a directory): a rule for a file
// with directory rights is refused (EINVAL).
uint64_t calcFileAccess(int abi) {
  uint64_t access = LANDLOCK_ACCESS_FS_EXECUTE | LANDLOCK_ACCESS_FS_WRITE_FILE |
                    LANDLOCK_ACCESS_FS_READ_FILE;
  if (abi >= 3) access |= LANDLOCK_ACCESS_FS_TRUNCATE;
  if (abi >= 5) access |= LANDLOCK_ACCESS_FS_IOCTL_DEV;
  return access;
}

void addPathRule(int ruleset, const std::string& path, uint64_t access, int abi) {
  const int fd = open(path.c_str(), O_PATH | O_CLOEXEC);
  if (fd < 0) return;  // a path this system lacks
  struct stat st {};
  if (fstat(fd, &st) == 0 && !S_ISDIR(st.st_mode)) access &= calcFileAccess(abi);
  landlock_path_beneath_attr rule{};
  rule.allowed_access = access & calcHandledAccess(abi);
  rule.parent_fd = fd;
  // A rule that cannot be added leaves that path unreadable: stricter.
  syscall(SYS_landlock_add_rule, ruleset, LANDLOCK_RULE_PATH_BENEATH, &rule, 0);
  close(fd);
}

void restrictFiles(const SandboxSettings& settings, int abi) {
  landlock_ruleset_attr attr{};
  attr.handled_access_fs = calcHandledAccess(abi);
  const int ruleset =
      int(syscall(SYS_landlock_create_ruleset, &attr, sizeof(attr.handled_access_fs), 0));
  if (ruleset < 0) return;  // refused (a container's filter, say): as a kernel without it
  const uint64_t read = LANDLOCK_ACCESS_FS_READ_FILE | LANDLOCK_ACCESS_FS_READ_DIR |
                        LANDLOCK_ACCESS_FS_EXECUTE;
  // The system's libraries and what the C, Python and BLAS runtimes read
  // at startup; nothing of /etc beyond these (no passwords, no hosts).
  for (const char* path :
       {"/usr", "/lib", "/lib64", "/lib32", "/etc/ld.so.cache", "/etc/localtime",
        "/etc/python3", "/etc/python3.11", "/etc/python3.12", "/proc/self", "/proc/cpuinfo",
        "/proc/meminfo", "/sys/devices/system/cpu", "/sys/fs/cgroup", "/dev/urandom"})
    addPathRule(ruleset, path, read, abi);
  addPathRule(ruleset, "/dev/null", read | LANDLOCK_ACCESS_FS_WRITE_FILE, abi);
  for (const std::string& path : settings.read_paths) addPathRule(ruleset, path, read, abi);
  if (!settings.private_dir.empty())
    addPathRule(ruleset, settings.private_dir, calcHandledAccess(abi), abi);
  if (syscall(SYS_landlock_restrict_self, ruleset, 0) != 0) fail("Landlock", errno);
  close(ruleset);
}

// Only ever lowers: where the process already has a stricter hard limit (a
// user's `ulimit -f`, a batch system's), that one stays, since an
// unprivileged process cannot raise it and the policy is held by it anyway.
void setLimit(int resource, uint64_t value, const char* name) {
  rlimit current{};
  if (getrlimit(resource, &current) != 0) fail(name, errno);
  rlim_t wanted = rlim_t(value);
  if (current.rlim_max != RLIM_INFINITY && current.rlim_max < wanted) wanted = current.rlim_max;
  const rlimit limit{wanted, wanted};
  if (setrlimit(resource, &limit) != 0) fail(name, errno);
}

// The address space mapped now (the environment's process's copy, which
// the policy cannot use up): the memory limit comes on top of it.
uint64_t getMappedBytes() {
  long pages = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld", &pages) != 1) pages = 0;
    std::fclose(f);
  }
  return uint64_t(pages) * uint64_t(sysconf(_SC_PAGESIZE));
}

void addRule(scmp_filter_ctx ctx, int syscall_number, std::initializer_list<scmp_arg_cmp> args,
             uint32_t action = SCMP_ACT_TRAP) {
  const int rc = seccomp_rule_add_array(ctx, action, syscall_number, unsigned(args.size()),
                                        args.size() ? args.begin() : nullptr);
  if (rc != 0) fail(std::string("seccomp rule for ") + seccomp_syscall_resolve_num_arch(
                        SCMP_ARCH_NATIVE, syscall_number), -rc);
}

void restrictCalls() {
  scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_ALLOW);
  if (!ctx) fail("seccomp", ENOMEM);
  const uint64_t self = uint64_t(getpid());
  // Refused whatever their arguments.
  for (const char* name :
       {"fork", "vfork", "execve", "execveat", "tkill", "pidfd_open",
        "pidfd_send_signal", "pidfd_getfd", "ptrace", "process_vm_readv", "process_vm_writev",
        "process_madvise", "setsid", "setpgid", "unshare", "setns", "mount", "umount2",
        "pivot_root", "chroot", "bpf", "perf_event_open", "keyctl", "add_key", "request_key",
        "io_uring_setup", "io_uring_enter", "io_uring_register", "userfaultfd",
        "kexec_load", "kexec_file_load", "init_module", "finit_module", "delete_module",
        "reboot", "swapon", "swapoff", "acct", "settimeofday", "clock_settime", "sethostname",
        "setdomainname", "iopl", "ioperm", "quotactl", "open_by_handle_at",
        "name_to_handle_at", "setrlimit", "fanotify_init", "move_mount", "fsopen", "fsmount",
        "open_tree"}) {
    const int number = seccomp_syscall_resolve_name(name);
    if (number != __NR_SCMP_ERROR) addRule(ctx, number, {});
  }
  // No network: a socket of any family but AF_UNIX traps. A Unix socket
  // fails with EACCES instead of trapping: the C library's name service
  // tries one (nscd) when a library asks for a user's home (libtorch does,
  // at load) and goes on without it; a policy gets no socket either way.
  addRule(ctx, SCMP_SYS(socket), {SCMP_A0(SCMP_CMP_NE, AF_UNIX)});
  addRule(ctx, SCMP_SYS(socket), {SCMP_A0(SCMP_CMP_EQ, AF_UNIX)}, SCMP_ACT_ERRNO(EACCES));
  // A thread is a clone with CLONE_THREAD; anything else is a process.
  addRule(ctx, SCMP_SYS(clone), {SCMP_A0(SCMP_CMP_MASKED_EQ, CLONE_THREAD, 0)});
  // clone3's flags are in memory, out of a filter's reach: "not
  // implemented" makes the C library fall back to clone.
  addRule(ctx, SCMP_SYS(clone3), {}, SCMP_ACT_ERRNO(ENOSYS));
  // Signals to itself only.
  for (int number : {SCMP_SYS(kill), SCMP_SYS(tgkill), SCMP_SYS(rt_sigqueueinfo),
                     SCMP_SYS(rt_tgsigqueueinfo)})
    addRule(ctx, number, {SCMP_A0(SCMP_CMP_NE, self)});
  // Raising a limit (as root it could) or catching the refusal's signal.
  addRule(ctx, SCMP_SYS(prlimit64), {SCMP_A2(SCMP_CMP_NE, 0)});
  // (Asking for the handler, with no new one, is fine: Python's signal
  // module asks for every signal's.)
  addRule(ctx, SCMP_SYS(rt_sigaction), {SCMP_A0(SCMP_CMP_EQ, SIGSYS), SCMP_A1(SCMP_CMP_NE, 0)});
  const int rc = seccomp_load(ctx);
  seccomp_release(ctx);
  if (rc != 0) fail("seccomp filter", -rc);
}

}  // namespace

int getLandlockAbi() {
  const long abi =
      syscall(SYS_landlock_create_ruleset, nullptr, 0, LANDLOCK_CREATE_RULESET_VERSION);
  return abi < 0 ? 0 : int(abi);
}

void enterSandbox(const SandboxSettings& settings) {
  g_refused_syscall = settings.refused_syscall;
  g_refused_argument = settings.refused_argument;
  struct sigaction action {};
  action.sa_sigaction = onRefusedCall;
  action.sa_flags = SA_SIGINFO;
  sigemptyset(&action.sa_mask);
  if (sigaction(SIGSYS, &action, nullptr) != 0) fail("SIGSYS handler", errno);
  sigset_t sys;
  sigemptyset(&sys);
  sigaddset(&sys, SIGSYS);
  sigprocmask(SIG_UNBLOCK, &sys, nullptr);

  setLimit(RLIMIT_CORE, 0, "RLIMIT_CORE");
  if (settings.memory_bytes) setLimit(RLIMIT_AS, getMappedBytes() + settings.memory_bytes, "RLIMIT_AS");
  if (settings.output_bytes) setLimit(RLIMIT_FSIZE, settings.output_bytes, "RLIMIT_FSIZE");
  if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) fail("no_new_privs", errno);
  const int abi = getLandlockAbi();
  if (abi > 0) restrictFiles(settings, abi);
  restrictCalls();
}

std::string describeRefusedCall(int32_t syscall_number, uint64_t first_argument) {
  const char* name = seccomp_syscall_resolve_num_arch(SCMP_ARCH_NATIVE, syscall_number);
  std::string text = name ? name : "system call " + std::to_string(syscall_number);
  const std::string call = name ? std::string(name) : "";
  auto is = [&](std::initializer_list<const char*> names) {
    for (const char* n : names)
      if (call == n) return true;
    return false;
  };
  if (is({"socket"}))
    text += " (no network: the policy may not open sockets)";
  else if (is({"clone", "fork", "vfork"}))
    text += " (the policy may not start processes)";
  else if (is({"execve", "execveat"}))
    text += " (the policy may not run programs)";
  else if (is({"kill", "tgkill", "tkill", "rt_sigqueueinfo", "rt_tgsigqueueinfo",
               "pidfd_send_signal", "pidfd_open"}))
    text += " (a signal to process " + std::to_string(int64_t(first_argument)) +
            ", outside the sandbox: the policy may signal only itself)";
  else if (is({"ptrace", "process_vm_readv", "process_vm_writev", "process_madvise",
               "pidfd_getfd"}))
    text += " (access to process " + std::to_string(int64_t(first_argument)) +
            ": the policy may not touch other processes' memory)";
  else if (is({"setrlimit", "prlimit64"}))
    text += " (the policy may not change its limits)";
  else if (is({"rt_sigaction"}))
    text += " (the policy may not handle SIGSYS)";
  else
    text += " (refused by the policy sandbox)";
  free(const_cast<char*>(name));
  return text;
}

}  // namespace manibench::evaluation_detail

namespace manibench {

std::string describeSandbox() {
  const int abi = evaluation_detail::getLandlockAbi();
  return abi > 0 ? "seccomp, Landlock ABI " + std::to_string(abi) + ", rlimits"
                 : "seccomp, rlimits; no file rules (this kernel has no Landlock)";
}

}  // namespace manibench
