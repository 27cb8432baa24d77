#include "policy_process.hpp"

#include <manibench/worker_pool.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <manibench/evaluation.hpp>
#include <manibench/futex.hpp>
#include <memory>
#include <sstream>

#include "sandbox.hpp"
#include "worker.hpp"

namespace manibench::evaluation_detail {

// The observation's arrays, in block order.
enum Array : uint32_t { kState, kXyz, kPointRgb, kPointMasks, kRgb, kRgbBytes, kDepth, kMasks, kArrays };

enum Command : uint32_t { kCommandReset = 1, kCommandAct = 2 };

// The block's first bytes. Each side writes only its own fields; the worker
// reads from the policy's only done_seq, status, the message (clamped) and
// the action, so that whatever a policy writes here fails at most its own
// episode.
struct alignas(64) PolicyBlockHeader {
  // Written by the worker.
  std::atomic<uint32_t> command_seq{0};
  std::atomic<uint32_t> policy_sleeping{0};
  uint32_t command = 0;
  uint32_t step = 0;
  uint64_t seed = 0;
  // A reset's task name and object id, one after the other at the data area.
  uint32_t task_name_size = 0, object_id_size = 0;
  uint32_t mode = 0, mask_count = 0, camera_count = 0, height = 0, width = 0;
  uint64_t counts[kArrays] = {};
  // Written by the policy process (another cache line).
  alignas(64) std::atomic<uint32_t> done_seq{0};
  std::atomic<uint32_t> worker_sleeping{0};
  int32_t status = 0;  // mb_status of the call
  uint32_t message_size = 0;
  int32_t refused_syscall = -1;
  uint64_t refused_argument = 0;
};

namespace {

constexpr std::size_t kAlign = 64;
constexpr std::size_t kMessageBytes = 16384;
constexpr std::size_t kElementBytes[kArrays] = {8, 4, 4, 1, 4, 1, 4, 1};

std::size_t roundUp(std::size_t n) { return (n + kAlign - 1) / kAlign * kAlign; }

std::size_t getMessageOffset() { return roundUp(sizeof(PolicyBlockHeader)); }
std::size_t getActionOffset() { return getMessageOffset() + kMessageBytes; }
std::size_t getDataOffset(uint32_t action_dim) {
  return getActionOffset() + roundUp(std::size_t(action_dim) * sizeof(double));
}

// The array's bytes and element count in the observation.
struct ArrayView {
  const void* data = nullptr;
  std::size_t count = 0;
};

ArrayView viewArray(const Eigen::VectorXd& state, const VisualObservation& v, uint32_t a) {
  switch (a) {
    case kState:
      return {state.data(), std::size_t(state.size())};
    case kXyz:
      return {v.points.xyz.data(), v.points.xyz.size()};
    case kPointRgb:
      return {v.points.rgb.data(), v.points.rgb.size()};
    case kPointMasks:
      return {v.points.masks.data(), v.points.masks.size()};
    case kRgb:
      return {v.rgb.data(), v.rgb.size()};
    case kRgbBytes:
      return {v.rgb_bytes.data(), v.rgb_bytes.size()};
    case kDepth:
      return {v.depth.data(), v.depth.size()};
    default:
      return {v.masks.data(), v.masks.size()};
  }
}

template <class T>
void assignFrom(std::vector<T>& out, const std::byte* data, uint64_t count) {
  out.resize(count);
  if (count) std::memcpy(out.data(), data, count * sizeof(T));
}

// Shared memory inherited from the worker (the coordinator's slots) is the
// coordinator's: unmapped, all but the policy's own block, before any
// policy code runs.
void unmapSharedExcept(const std::byte* block) {
  if (FILE* maps = std::fopen("/proc/self/maps", "r")) {
    std::vector<std::pair<uintptr_t, uintptr_t>> shared;
    char line[4096];
    while (std::fgets(line, sizeof(line), maps)) {
      unsigned long from = 0, to = 0;
      char perms[8] = {};
      if (std::sscanf(line, "%lx-%lx %7s", &from, &to, perms) == 3 && perms[3] == 's' &&
          from != reinterpret_cast<uintptr_t>(block))
        shared.emplace_back(from, to);
    }
    std::fclose(maps);
    for (const auto& [from, to] : shared) munmap(reinterpret_cast<void*>(from), to - from);
  }
}

// The policy's output goes to a log in its directory (relayed by the
// worker, bounded by the output limit); no descriptor of the worker's
// stays; its temporary files and home are the directory.
void enterPrivateDir(const std::string& private_dir) {
  const std::string log = private_dir + "/policy.log";
  const int log_fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0600);
  const int null_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
  if (log_fd < 0 || null_fd < 0) throw std::runtime_error("cannot open the policy's log");
  std::fflush(nullptr);
  dup2(null_fd, 0);
  dup2(log_fd, 1);
  dup2(log_fd, 2);
  syscall(SYS_close_range, 3u, ~0u, 0u);
  setenv("TMPDIR", private_dir.c_str(), 1);
  setenv("TMP", private_dir.c_str(), 1);
  setenv("TEMP", private_dir.c_str(), 1);
  setenv("HOME", private_dir.c_str(), 1);
  if (chdir(private_dir.c_str()) != 0) throw std::runtime_error("cannot enter " + private_dir);
}

// The observation, rebuilt from the block as the worker wrote it.
void readObservation(const PolicyBlockHeader& header, const std::byte* data, Eigen::VectorXd& state,
                     VisualObservation& visual) {
  std::size_t offset = 0;
  const std::byte* at[kArrays];
  for (uint32_t a = 0; a < kArrays; ++a) {
    at[a] = data + offset;
    offset += roundUp(header.counts[a] * kElementBytes[a]);
  }
  state.resize(Eigen::Index(header.counts[kState]));
  if (state.size()) std::memcpy(state.data(), at[kState], std::size_t(state.size()) * 8);
  visual.mode = static_cast<ObservationMode>(header.mode);
  visual.mask_count = header.mask_count;
  visual.points.mask_count = header.mask_count;
  visual.camera_count = header.camera_count;
  visual.height = header.height;
  visual.width = header.width;
  assignFrom(visual.points.xyz, at[kXyz], header.counts[kXyz]);
  assignFrom(visual.points.rgb, at[kPointRgb], header.counts[kPointRgb]);
  assignFrom(visual.points.masks, at[kPointMasks], header.counts[kPointMasks]);
  assignFrom(visual.rgb, at[kRgb], header.counts[kRgb]);
  assignFrom(visual.rgb_bytes, at[kRgbBytes], header.counts[kRgbBytes]);
  assignFrom(visual.depth, at[kDepth], header.counts[kDepth]);
  assignFrom(visual.masks, at[kMasks], header.counts[kMasks]);
}

// The policy process's side: everything from the fork on (spawnChild has
// tied it to its worker and made its process group). Returns only when the
// policy cannot be made (its exit status); otherwise it serves until its
// worker kills it.
int servePolicy(const PolicyProcessSettings& settings, std::byte* block,
                              std::size_t block_bytes, const std::string& private_dir) {
  auto& header = *reinterpret_cast<PolicyBlockHeader*>(block);
  char* message = reinterpret_cast<char*>(block + getMessageOffset());
  auto answer = [&](int32_t status, const std::string& text) {
    header.status = status;
    header.message_size = uint32_t(std::min(text.size(), kMessageBytes));
    std::memcpy(message, text.data(), header.message_size);
    header.done_seq.store(header.command_seq.load());
    if (header.worker_sleeping.load()) futexWakeAll(header.done_seq);
  };
  std::unique_ptr<PolicyInstance> policy;
  try {
    unmapSharedExcept(block);
    enterPrivateDir(private_dir);
    SandboxSettings sandbox;
    sandbox.read_paths = settings.read_paths;
    sandbox.private_dir = private_dir;
    sandbox.memory_bytes = settings.memory_bytes;
    sandbox.output_bytes = settings.output_bytes;
    sandbox.refused_syscall = &header.refused_syscall;
    sandbox.refused_argument = &header.refused_argument;
    enterSandbox(sandbox);
    policy = std::make_unique<PolicyInstance>(*settings.registry, settings.policy,
                                              settings.policy_config, settings.layout);
  } catch (const PluginCallError& e) {
    answer(e.status(), e.what());
    return 0;
  } catch (const std::exception& e) {
    answer(MB_ERROR, e.what());
    return 0;
  }
  answer(MB_OK, "");

  const uint32_t action_dim = settings.layout.action_dim;
  double* action_out = reinterpret_cast<double*>(block + getActionOffset());
  const std::byte* data = block + getDataOffset(action_dim);
  Eigen::VectorXd state, action;
  VisualObservation visual;
  // The creation was command 1; the worker may post the next one as soon as
  // it sees the answer.
  uint32_t seen = 1;
  for (;;) {
    uint32_t seq = header.command_seq.load();
    while (seq == seen) {
      header.policy_sleeping.store(1);
      seq = header.command_seq.load();
      if (seq == seen) futexWait(header.command_seq, seen, 0.1);
      header.policy_sleeping.store(0);
      seq = header.command_seq.load();
    }
    seen = seq;
    try {
      if (header.command == kCommandReset) {
        const std::size_t room = block_bytes - getDataOffset(action_dim);
        const std::size_t task_size = std::min<std::size_t>(header.task_name_size, room);
        const std::size_t object_size = std::min<std::size_t>(header.object_id_size, room - task_size);
        const char* names = reinterpret_cast<const char*>(data);
        policy->reset(PolicyEpisode{std::string(names, task_size), std::string(names + task_size, object_size),
                                    header.seed});
      } else {
        readObservation(header, data, state, visual);
        policy->act(state, header.step, action, visual);
        std::memcpy(action_out, action.data(), std::size_t(action_dim) * sizeof(double));
      }
      answer(MB_OK, "");
    } catch (const PluginCallError& e) {
      answer(e.status(), e.what());
    } catch (const std::exception& e) {
      answer(MB_ERROR, e.what());
    }
  }
}

std::string makePrivateDir(const std::string& parent) {
  const char* base = std::getenv("TMPDIR");
  std::string pattern = (parent.empty() ? std::string(base && *base ? base : "/tmp") : parent) +
                        "/policy-XXXXXX";
  if (!mkdtemp(pattern.data()))
    throw EvaluationError("cannot create the policy's temporary directory: " +
                          std::string(std::strerror(errno)));
  return pattern;
}

bool isOutOfMemory(const std::string& message) {
  return message.find("bad_alloc") != std::string::npos ||
         message.find("MemoryError") != std::string::npos ||
         message.find("Cannot allocate memory") != std::string::npos;
}

}  // namespace

SandboxedPolicy::SandboxedPolicy(const PolicyProcessSettings& settings) : settings_(settings) {
  // Room for the observation as it is now, and four times more: a visual
  // observation's size is fixed by the configuration. Untouched pages of
  // the mapping cost nothing.
  block_bytes_ = getDataOffset(settings.layout.action_dim) +
                 std::max<std::size_t>(64u << 20, 4 * settings.observation_bytes);
  void* memory = mmap(nullptr, block_bytes_, PROT_READ | PROT_WRITE,
                      MAP_SHARED | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (memory == MAP_FAILED)
    throw EvaluationError("cannot map the policy's shared block: " +
                          std::string(std::strerror(errno)));
  block_ = static_cast<std::byte*>(memory);
  header_ = new (block_) PolicyBlockHeader();
  // The creation is command 1: the process answers it before any other.
  seq_ = 1;
  header_->command_seq.store(seq_);
  try {
    private_dir_ = makePrivateDir(settings.scratch_dir);
  } catch (...) {
    munmap(block_, block_bytes_);
    throw;
  }
  // No channel: the shared block is the policy's only way out; its own
  // process group, which kill() ends whole.
  ChildOptions options;
  options.channel = false;
  options.own_process_group = true;
  const Child child =
      spawnChild(options, [this](int) { return servePolicy(settings_, block_, block_bytes_, private_dir_); });
  pid_ = child.pid;
  if (pid_ < 0) {
    munmap(block_, block_bytes_);
    std::filesystem::remove(private_dir_);
    throw EvaluationError("cannot start the policy's process (" + child.error + ")");
  }
  try {
    call(0, settings_.create_timeout);
  } catch (...) {
    kill();
    relayOutput();
    munmap(block_, block_bytes_);
    std::error_code ignored;
    std::filesystem::remove_all(private_dir_, ignored);
    throw;
  }
}

SandboxedPolicy::~SandboxedPolicy() {
  kill();
  relayOutput();
  if (block_) munmap(block_, block_bytes_);
  block_ = nullptr;
  std::error_code ignored;
  if (!private_dir_.empty()) std::filesystem::remove_all(private_dir_, ignored);
}

void SandboxedPolicy::kill() {
  if (pid_ <= 0) return;
  ::kill(-pid_, SIGKILL);
  ::kill(pid_, SIGKILL);
  waitForChild(pid_);
  pid_ = -1;
}

void SandboxedPolicy::relayOutput() {
  if (private_dir_.empty()) return;
  const std::string path = private_dir_ + "/policy.log";
  FILE* log = std::fopen(path.c_str(), "rb");
  if (!log) return;
  std::fseek(log, 0, SEEK_END);
  const long end = std::ftell(log);
  if (end > long(log_offset_)) {
    const uint64_t size = uint64_t(end) - log_offset_;
    const uint64_t shown = std::min<uint64_t>(size, 65536);
    std::string text(shown, '\0');
    std::fseek(log, long(log_offset_), SEEK_SET);
    text.resize(std::fread(text.data(), 1, shown, log));
    std::fwrite(text.data(), 1, text.size(), stderr);
    if (shown < size)
      std::fprintf(stderr, "\n[the policy wrote %llu more bytes, not shown]\n",
                   static_cast<unsigned long long>(size - shown));
    std::fflush(stderr);
    log_offset_ = uint64_t(end);
  }
  std::fclose(log);
}

void SandboxedPolicy::failKilled(const std::string& message, const char* failure) {
  kill();
  throw PolicyProcessFailure(message, failure);
}

void SandboxedPolicy::failDead(int status) {
  pid_ = -1;  // reaped
  std::ostringstream text;
  const char* kind = failure::kCrash;
  if (WIFEXITED(status) && WEXITSTATUS(status) == kRefusedExitStatus &&
      header_->refused_syscall >= 0) {
    kind = failure::kSandbox;
    text << "refused by the sandbox: "
         << describeRefusedCall(header_->refused_syscall, header_->refused_argument)
         << "; the policy process was ended";
  } else if (WIFSIGNALED(status) && WTERMSIG(status) == SIGXFSZ) {
    kind = failure::kSandbox;
    text << "the policy wrote more than its output limit (" << settings_.output_bytes
         << " bytes to its log or temporary files); the policy process was killed by SIGXFSZ";
  } else if (WIFSIGNALED(status) && WTERMSIG(status) == SIGSYS) {
    kind = failure::kSandbox;
    text << "refused by the sandbox: a system call (the policy process was killed by SIGSYS)";
  } else {
    text << "the policy process " << (WIFEXITED(status) ? "" : "was ") << describeExit(status);
  }
  throw PolicyProcessFailure(text.str(), kind);
}

void SandboxedPolicy::call(uint32_t command, double timeout) {
  if (pid_ <= 0) throw PolicyProcessFailure("the policy process is gone", failure::kCrash);
  PolicyBlockHeader& h = *header_;
  if (command != 0) {
    h.command = command;
    h.command_seq.store(++seq_);
    if (h.policy_sleeping.load()) futexWakeAll(h.command_seq);
  }
  const int64_t start = getMonotonicNs();
  clockid_t cpu_clock{};
  const bool has_cpu_clock = clock_getcpuclockid(pid_, &cpu_clock) == 0;
  // No spinning, on either side: a futex round trip per call. Spinning
  // (the worker 50 us for the answer, the policy 20 us for the next
  // command, as make_vec's block does) cost 10-16 % more CPU time per step
  // of Reach-v0 with a machine's load at 8 on 2 cores (bench/sandbox_cost.sh:
  // 221 -> 244-258 CPU ms per 1000 steps), the futex alone 3-7 %
  // (docs/evaluation.md, "Sandbox").
  uint32_t seen = h.done_seq.load();
  while (seen != seq_) {
    h.worker_sleeping.store(1);
    seen = h.done_seq.load();
    if (seen != seq_) futexWait(h.done_seq, seen, 0.01);
    h.worker_sleeping.store(0);
    seen = h.done_seq.load();
    if (seen == seq_) break;
    int status = 0;
    if (findChildExit(pid_, status)) failDead(status);
    if (double(getMonotonicNs() - start) * 1e-9 > timeout) {
      std::ostringstream text;
      text << "no return within " << timeout << " s; the policy process was killed";
      failKilled(text.str(), failure::kTimeout);
    }
    timespec cpu{};
    if (command != 0 && has_cpu_clock && clock_gettime(cpu_clock, &cpu) == 0) {
      const int64_t used =
          int64_t(cpu.tv_sec) * 1000000000LL + cpu.tv_nsec - episode_cpu_start_ns_;
      if (double(used) * 1e-9 > settings_.cpu_limit) {
        std::ostringstream text;
        text << "the policy used more than its CPU time limit (" << settings_.cpu_limit
             << " s in this episode); the policy process was killed";
        failKilled(text.str(), failure::kSandbox);
      }
    }
  }
  std::atomic_thread_fence(std::memory_order_acquire);
  const int32_t status = h.status;
  if (status != MB_OK) {
    const std::string message(reinterpret_cast<const char*>(block_ + getMessageOffset()),
                              std::min<std::size_t>(h.message_size, kMessageBytes));
    if (command == 0) {
      // The create failed: the process leaves; the error is the one an
      // in-process create throws.
      kill();
    }
    if (isOutOfMemory(message))
      throw PolicyProcessFailure(message + " (the policy ran out of its memory limit, " +
                                     std::to_string(settings_.memory_bytes >> 20) + " MiB)",
                                 failure::kSandbox);
    throw PluginCallError(message, mb_status(status));
  }
}

void SandboxedPolicy::reset(const PolicyEpisode& episode) {
  timespec cpu{};
  clockid_t cpu_clock{};
  if (pid_ > 0 && clock_getcpuclockid(pid_, &cpu_clock) == 0 && clock_gettime(cpu_clock, &cpu) == 0)
    episode_cpu_start_ns_ = int64_t(cpu.tv_sec) * 1000000000LL + cpu.tv_nsec;
  header_->seed = episode.seed;
  const std::size_t room = block_bytes_ - getDataOffset(settings_.layout.action_dim);
  if (episode.task_name.size() + episode.object_id.size() > room)
    throw EvaluationError("the episode's task name and object id do not fit the policy's block");
  char* names = reinterpret_cast<char*>(block_ + getDataOffset(settings_.layout.action_dim));
  std::memcpy(names, episode.task_name.data(), episode.task_name.size());
  std::memcpy(names + episode.task_name.size(), episode.object_id.data(), episode.object_id.size());
  header_->task_name_size = uint32_t(episode.task_name.size());
  header_->object_id_size = uint32_t(episode.object_id.size());
  call(kCommandReset, settings_.call_timeout);
}

void SandboxedPolicy::act(const Eigen::VectorXd& observation, uint32_t step,
                          Eigen::VectorXd& action, const VisualObservation& visual) {
  PolicyBlockHeader& h = *header_;
  const uint32_t action_dim = settings_.layout.action_dim;
  std::byte* data = block_ + getDataOffset(action_dim);
  const std::size_t room = block_bytes_ - getDataOffset(action_dim);
  std::size_t offset = 0;
  for (uint32_t a = 0; a < kArrays; ++a) {
    const ArrayView view = viewArray(observation, visual, a);
    const std::size_t bytes = view.count * kElementBytes[a];
    if (offset + bytes > room)
      throw EvaluationError("the observation (" + std::to_string(offset + bytes) +
                            " bytes so far) does not fit the policy's block of " +
                            std::to_string(room) + " bytes");
    if (bytes) std::memcpy(data + offset, view.data, bytes);
    h.counts[a] = view.count;
    offset += roundUp(bytes);
  }
  h.mode = uint32_t(visual.mode);
  h.mask_count = visual.mask_count;
  h.camera_count = visual.camera_count;
  h.height = visual.height;
  h.width = visual.width;
  h.step = step;
  call(kCommandAct, settings_.call_timeout);
  action.resize(action_dim);
  std::memcpy(action.data(), block_ + getActionOffset(), std::size_t(action_dim) * sizeof(double));
}

}  // namespace manibench::evaluation_detail
