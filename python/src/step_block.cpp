#include "step_block.hpp"

#include <manibench/error.hpp>
#include <manibench/futex.hpp>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <new>
#include <stdexcept>
#include <system_error>

namespace manibench::python {
namespace {

constexpr std::size_t kAlign = 64;

std::size_t roundUp(std::size_t n) { return (n + kAlign - 1) / kAlign * kAlign; }

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::size_t calcSize(const StepBlockLayout& layout, std::size_t* slot_bytes) {
  std::size_t bytes = roundUp(sizeof(StepSlotHeader));
  bytes += roundUp(layout.action_dim * sizeof(double));
  bytes += roundUp(layout.condition_count);
  bytes += roundUp(layout.condition_count * sizeof(double));
  for (std::size_t field : layout.field_bytes) bytes += roundUp(field);
  *slot_bytes = bytes;
  return bytes * layout.slot_count;
}

std::string makeUniqueName() {
  static std::atomic<unsigned> counter{0};
  const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
  return "/manibench-vec-" + std::to_string(getpid()) + "-" + std::to_string(counter++) + "-" +
         std::to_string(now % 1000000007);
}

}  // namespace

StepBlock::StepBlock(std::string name, const StepBlockLayout& layout, std::byte* base,
                     std::size_t size, bool owner)
    : name_(std::move(name)), layout_(layout), base_(base), size_(size), owner_(owner),
      linked_(owner) {
  calcOffsets();
}

StepBlock::StepBlock(StepBlock&& other) noexcept
    : name_(std::move(other.name_)), layout_(std::move(other.layout_)), base_(other.base_),
      size_(other.size_), owner_(other.owner_), linked_(other.linked_),
      slot_bytes_(other.slot_bytes_), action_offset_(other.action_offset_),
      flags_offset_(other.flags_offset_), values_offset_(other.values_offset_),
      field_offsets_(std::move(other.field_offsets_)) {
  other.base_ = nullptr;
  other.linked_ = false;
}

StepBlock::~StepBlock() {
  if (linked_) unlinkName();
  if (base_) munmap(base_, size_);
}

void StepBlock::calcOffsets() {
  calcSize(layout_, &slot_bytes_);
  std::size_t at = roundUp(sizeof(StepSlotHeader));
  action_offset_ = at;
  at += roundUp(layout_.action_dim * sizeof(double));
  flags_offset_ = at;
  at += roundUp(layout_.condition_count);
  values_offset_ = at;
  at += roundUp(layout_.condition_count * sizeof(double));
  field_offsets_.clear();
  for (std::size_t field : layout_.field_bytes) {
    field_offsets_.push_back(at);
    at += roundUp(field);
  }
}

StepBlock StepBlock::create(const StepBlockLayout& layout) {
  if (layout.slot_count == 0) throw InvalidArgument("a step block needs at least one slot");
  std::size_t slot_bytes = 0;
  const std::size_t size = calcSize(layout, &slot_bytes);
  const std::string name = makeUniqueName();
  const int fd = shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  if (fd < 0)
    throw std::system_error(errno, std::generic_category(), "make_vec: shm_open(" + name + ")");
  // posix_fallocate reserves the pages now: on a full /dev/shm (a
  // container's 64 MB) a write into a merely truncated object is a SIGBUS.
  if (const int error = posix_fallocate(fd, 0, off_t(size)); error != 0) {
    close(fd);
    shm_unlink(name.c_str());
    throw std::system_error(error, std::generic_category(),
                            "make_vec: cannot size the shared block " + name + " to " +
                                std::to_string(size) + " bytes (is /dev/shm full?)");
  }
  void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const int error = errno;
  close(fd);
  if (base == MAP_FAILED) {
    shm_unlink(name.c_str());
    throw std::system_error(error, std::generic_category(), "make_vec: mmap of " + name);
  }
  auto* bytes = static_cast<std::byte*>(base);
  StepBlock block(name, layout, bytes, size, true);
  // The new object reads as zeros; the headers' atomics start at their initializers.
  for (std::size_t s = 0; s < layout.slot_count; ++s)
    new (bytes + s * block.slot_bytes_) StepSlotHeader();
  return block;
}

StepBlock StepBlock::attach(const std::string& name, const StepBlockLayout& layout) {
  std::size_t slot_bytes = 0;
  const std::size_t size = calcSize(layout, &slot_bytes);
  const int fd = shm_open(name.c_str(), O_RDWR, 0600);
  if (fd < 0)
    throw std::system_error(errno, std::generic_category(), "make_vec: shm_open(" + name + ")");
  struct stat info {};
  if (fstat(fd, &info) != 0 || std::size_t(info.st_size) != size) {
    close(fd);
    throw std::runtime_error("make_vec: the shared block " + name + " has " +
                             std::to_string(info.st_size) + " bytes, this worker's layout " +
                             std::to_string(size) + " (different observation layouts?)");
  }
  void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const int error = errno;
  close(fd);
  if (base == MAP_FAILED)
    throw std::system_error(error, std::generic_category(), "make_vec: mmap of " + name);
  return StepBlock(name, layout, static_cast<std::byte*>(base), size, false);
}

void StepBlock::unlinkName() {
  if (!linked_) return;
  shm_unlink(name_.c_str());
  linked_ = false;
}

StepSlotHeader& StepBlock::updHeader(std::size_t slot) {
  return *std::launder(reinterpret_cast<StepSlotHeader*>(base_ + slot * slot_bytes_));
}
double* StepBlock::updAction(std::size_t slot) {
  return reinterpret_cast<double*>(base_ + slot * slot_bytes_ + action_offset_);
}
uint8_t* StepBlock::updFlags(std::size_t slot) {
  return reinterpret_cast<uint8_t*>(base_ + slot * slot_bytes_ + flags_offset_);
}
double* StepBlock::updValues(std::size_t slot) {
  return reinterpret_cast<double*>(base_ + slot * slot_bytes_ + values_offset_);
}
std::byte* StepBlock::updField(std::size_t slot, std::size_t field) {
  return base_ + getFieldOffset(slot, field);
}
std::size_t StepBlock::getFieldOffset(std::size_t slot, std::size_t field) const {
  return slot * slot_bytes_ + field_offsets_.at(field);
}

void StepBlock::post(StepCommand command, const double* actions) {
  for (std::size_t s = 0; s < layout_.slot_count; ++s) {
    StepSlotHeader& h = updHeader(s);
    if (command == StepCommand::Step)
      std::memcpy(updAction(s), actions + s * layout_.action_dim,
                  layout_.action_dim * sizeof(double));
    h.command.store(uint32_t(command), std::memory_order_relaxed);
    // seq_cst: the worker either sees the new number before it sleeps, or
    // it said it sleeps before we look (then we wake it).
    h.command_seq.fetch_add(1);
    if (h.worker_sleeping.load()) futexWakeAll(h.command_seq);
  }
}

std::vector<std::size_t> StepBlock::waitAll(double timeout_s) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::size_t> pending;
  for (std::size_t s = 0; s < layout_.slot_count; ++s) {
    StepSlotHeader& h = updHeader(s);
    const uint32_t target = h.command_seq.load(std::memory_order_relaxed);
    // The parent does not spin: with as many workers as cores, a spinning
    // parent takes a core from a worker.
    while (h.done_seq.load(std::memory_order_acquire) != target) {
      const double left = timeout_s - secondsSince(start);
      if (left <= 0) break;
      h.parent_sleeping.store(1);
      const uint32_t done = h.done_seq.load();
      if (done != target) futexWait(h.done_seq, done, left);
      h.parent_sleeping.store(0);
    }
    if (h.done_seq.load(std::memory_order_acquire) != target) pending.push_back(s);
  }
  return pending;
}

StepCommand StepBlock::waitCommand(std::size_t slot, double spin_wait_s, int parent_pid) {
  StepSlotHeader& h = updHeader(slot);
  const uint32_t seen = h.seen_seq;
  if (h.command_seq.load(std::memory_order_acquire) == seen && spin_wait_s > 0) {
    // Spinning keeps this core awake: on a virtual machine a halted core
    // runs the next step 20-40 % slower.
    const auto start = std::chrono::steady_clock::now();
    unsigned spins = 0;
    while (h.command_seq.load(std::memory_order_acquire) == seen) {
      cpuRelax();
      if (++spins % 64 == 0 && secondsSince(start) > spin_wait_s) break;
    }
  }
  while (h.command_seq.load(std::memory_order_acquire) == seen) {
    // Woken at least twice a second to notice an orphaned worker.
    if (getppid() != parent_pid) return StepCommand::ToPipe;
    h.worker_sleeping.store(1);
    if (h.command_seq.load() == seen) futexWait(h.command_seq, seen, 0.5);
    h.worker_sleeping.store(0);
  }
  h.seen_seq = h.command_seq.load(std::memory_order_acquire);
  return StepCommand(h.command.load(std::memory_order_relaxed));
}

void StepBlock::finish(std::size_t slot, StepResultPlace place) {
  StepSlotHeader& h = updHeader(slot);
  h.place = uint32_t(place);
  h.done_seq.store(h.seen_seq);  // seq_cst: see post()
  if (h.parent_sleeping.load()) futexWakeAll(h.done_seq);
}

}  // namespace manibench::python
