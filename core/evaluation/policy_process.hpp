// The evaluated policy in a process of its own (issue 30): the worker
// (the environment's process) forks it, it enters the sandbox
// (sandbox.hpp) and builds the PolicyInstance there; observations and
// actions cross through a shared block, as make_vec's step block does
// (python/src/step_block.hpp): the worker writes the observation and a
// command, the policy process the action and its status. The worker
// computes reward and success and alone reports to the coordinator: the
// policy process has no descriptor of the worker's, shares no memory with
// it but the block (from which the worker reads only the action, the status
// and a bounded message), and cannot signal or trace it.
//
// The worker watches the policy while it waits: a call past the step
// timeout, more CPU time in an episode than the limit, or the process's
// death fail the episode (PolicyProcessFailure); a new policy process then
// serves the next episode, the environment stays.
#pragma once

#include <manibench/episode.hpp>
#include <manibench/error.hpp>
#include <manibench/plugin_instances.hpp>

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace manibench::evaluation_detail {

struct PolicyBlockHeader;

// The policy process failed the episode: died, overran a limit or did
// something the sandbox refuses. `failure` is one of failure::k*.
class PolicyProcessFailure : public Error {
 public:
  PolicyProcessFailure(const std::string& message, const char* failure)
      : Error(message), failure_(failure) {}
  const char* failure() const { return failure_; }

 private:
  const char* failure_;
};

struct PolicyProcessSettings {
  const PluginRegistry* registry = nullptr;
  std::string policy;
  std::string policy_config;
  PolicyLayout layout;
  std::vector<std::string> read_paths;  // the policy's own files, read-only
  double call_timeout = 10;             // s, each reset and act
  double create_timeout = 300;          // s, the process's start and the policy's create
  double cpu_limit = 60;                // s of CPU time per episode
  uint64_t memory_bytes = 0;            // address space the policy may add (0: unlimited)
  uint64_t output_bytes = 0;            // its log and temporary files (0: unlimited)
  std::size_t observation_bytes = 0;    // room for the largest observation
  // Where its private temporary folder is made (the run's scratch folder,
  // which the coordinator removes at the end even when a worker was killed
  // before it could remove its policy's); empty: $TMPDIR.
  std::string scratch_dir;
};

class SandboxedPolicy : public ActingPolicy {
 public:
  // Forks the policy process and waits until its policy is created; a
  // failed create throws the PluginCallError the in-process create would.
  explicit SandboxedPolicy(const PolicyProcessSettings& settings);
  ~SandboxedPolicy() override;
  SandboxedPolicy(const SandboxedPolicy&) = delete;
  SandboxedPolicy& operator=(const SandboxedPolicy&) = delete;

  void reset(const PolicyEpisode& episode) override;
  void act(const Eigen::VectorXd& observation, uint32_t step, Eigen::VectorXd& action,
           const VisualObservation& visual) override;
  // Copies what the policy wrote to its stdout and stderr since the last
  // call to this process's stderr (at most 64 KiB a call).
  void relayOutput();

 private:
  // Posts `command` and waits for the policy's answer, watching the
  // process; throws PolicyProcessFailure or the policy's PluginCallError.
  void call(uint32_t command, double timeout);
  [[noreturn]] void failDead(int status);
  [[noreturn]] void failKilled(const std::string& message, const char* failure);
  void kill();

  PolicyProcessSettings settings_;
  std::byte* block_ = nullptr;
  std::size_t block_bytes_ = 0;
  PolicyBlockHeader* header_ = nullptr;
  pid_t pid_ = -1;
  uint32_t seq_ = 0;
  std::string private_dir_;
  uint64_t log_offset_ = 0;
  int64_t episode_cpu_start_ns_ = 0;
};

}  // namespace manibench::evaluation_detail
