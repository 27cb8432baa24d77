// StepBlock: the shared memory through which make_vec's parent and its
// worker processes exchange the steps (python/manibench/vector.py).
//
// Why: pickling an observation and an info dict through a pipe, and the
// Python that goes with it, cost about 0.25 ms per worker and step, a
// quarter of a cabinet env step. Through the block a step costs the
// parent one store of the actions and one wait, and the worker one copy
// of its observation; neither runs Python. Everything that is not a plain
// step (reset, close, call, an error, the auto-reset) still goes through
// the worker's pipe: the block says so (Result::OnPipe).
//
// One slot per worker: a header (the two sequence numbers the processes
// wait on, the scalars of the step), the action, the per-condition flags
// and values, and the observation's fields in the order of
// describeObservation. Waiting is a spin of at most spin_wait seconds, then
// a futex on the sequence number (shared between processes: no
// FUTEX_PRIVATE_FLAG), with a flag telling the other side to wake it.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace manibench::python {

// What one slot holds; the same in the parent and every worker (both
// compute it from the environment's description).
struct StepBlockLayout {
  std::size_t slot_count = 0;
  std::size_t action_dim = 0;
  std::size_t condition_count = 0;
  std::vector<std::size_t> field_bytes;  // the observation's fields, in order
};

// The commands the parent posts.
enum class StepCommand : uint32_t {
  Step = 1,    // step with the slot's action (or auto-reset: Result::OnPipe)
  ToPipe = 2,  // leave the step loop: the next command comes through the pipe
};

// Where the result of a posted Step is.
enum class StepResultPlace : uint32_t {
  InBlock = 0,  // scalars and observation in the slot
  OnPipe = 1,   // the worker sent it (an auto-reset, or an error) through its pipe
};

// Why the worker's step loop (serveSteps) returned.
enum class ServeExit : uint32_t {
  ToPipe = 2,     // the parent posted ToPipe
  AutoReset = 3,  // a Step arrived for an episode that ended
  EpisodeEnded = 4,  // (same-step auto-reset) this Step ended the episode: the
                     // header holds its scalars, the slot is not finished
};

struct alignas(64) StepSlotHeader {
  // Written by the parent.
  std::atomic<uint32_t> command_seq{0};
  std::atomic<uint32_t> command{0};
  std::atomic<uint32_t> worker_sleeping{0};
  // Written by the worker (another cache line: the two sides do not share one).
  alignas(64) std::atomic<uint32_t> done_seq{0};
  std::atomic<uint32_t> parent_sleeping{0};
  uint32_t seen_seq = 0;     // the last command the worker took
  uint32_t place = 0;        // StepResultPlace of the last Step
  uint32_t needs_reset = 0;  // the episode ended at the last step
  uint32_t point_count = 0;  // pointcloud: the rows written (<= the field's rows)
  uint8_t terminated = 0, truncated = 0, success = 0;
  int64_t elapsed_steps = 0;
  double reward = 0;
};

class StepBlock {
 public:
  // A new block (a POSIX shared memory object with a unique name, mapped
  // and zeroed); unlinkName() once every worker has attached.
  static StepBlock create(const StepBlockLayout& layout);
  // The block `name` made by create() in another process.
  static StepBlock attach(const std::string& name, const StepBlockLayout& layout);

  StepBlock(StepBlock&& other) noexcept;
  StepBlock& operator=(StepBlock&&) = delete;
  StepBlock(const StepBlock&) = delete;
  ~StepBlock();

  const std::string& getName() const { return name_; }
  const StepBlockLayout& getLayout() const { return layout_; }
  void unlinkName();

  StepSlotHeader& updHeader(std::size_t slot);
  double* updAction(std::size_t slot);
  uint8_t* updFlags(std::size_t slot);
  double* updValues(std::size_t slot);
  std::byte* updField(std::size_t slot, std::size_t field);
  std::byte* updData() { return base_; }
  std::size_t getFieldOffset(std::size_t slot, std::size_t field) const;
  std::size_t getSize() const { return size_; }

  // ---- parent side ----
  // Posts `command` to every slot (Step: with the row of `actions`,
  // slot_count x action_dim, row-major).
  void post(StepCommand command, const double* actions);
  // Waits until every slot has finished the last posted command or
  // `timeout_s` passed; returns the slots not finished (empty: all done).
  std::vector<std::size_t> waitAll(double timeout_s);

  // ---- worker side ----
  // Waits (spin, then futex) for the parent's next command on `slot`;
  // takes it (seen_seq) and returns it. Returns ToPipe without taking one
  // when this process's parent is no longer `parent_pid` (the parent died:
  // its pipe then says so, and the worker ends).
  StepCommand waitCommand(std::size_t slot, double spin_wait_s, int parent_pid);
  // Marks the slot's taken command finished with the result at `place`,
  // waking the parent if it sleeps.
  void finish(std::size_t slot, StepResultPlace place);

 private:
  StepBlock(std::string name, const StepBlockLayout& layout, std::byte* base, std::size_t size,
            bool owner);
  void calcOffsets();

  std::string name_;
  StepBlockLayout layout_;
  std::byte* base_ = nullptr;
  std::size_t size_ = 0;
  bool owner_ = false;  // created it: unlinks the name if still linked
  bool linked_ = false;
  std::size_t slot_bytes_ = 0;
  std::size_t action_offset_ = 0, flags_offset_ = 0, values_offset_ = 0;
  std::vector<std::size_t> field_offsets_;
};

}  // namespace manibench::python
