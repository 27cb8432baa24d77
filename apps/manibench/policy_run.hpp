// The setup of the commands that run a policy in the evaluation kit's
// worker processes (eval, demos generate): the options both take, the
// policy (cli.hpp's choosePolicy) and its sandbox, the configuration, the
// task checked before any worker starts, MPI ranks, and how progress is
// shown. Each command adds only what is its own (eval: levels, journal,
// benchmark; demos generate: trajectories per object, the file).
#pragma once

#include <manibench/config.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/task_name.hpp>

#include <memory>
#include <optional>
#include <string>

#include "cli.hpp"
#include "mpi_ranks.hpp"

namespace manibench::cli {

// --split (default `split`), --seed, --workers (1 to 256), --step-timeout,
// --env-timeout and --objects into `options`.
void parseWorkerOptions(const Arguments& args, const std::string& split, const char* usage,
                        EvaluationOptions& options);

struct PolicyRun {
  PolicyChoice policy;
  ConfigSources sources;  // the user's layers, then the policy's controller
  TaskId task_id;
  ConfigNode config;  // the task's configuration, checked
  EnvironmentOptions environment;
  EnvironmentFactory factory;  // an environment as configured, in a worker
  std::unique_ptr<MpiRanks> mpi;  // under mpirun
  bool writer = true;             // no MPI, or rank 0: prints and writes
  bool progress_bar = false;      // the writer on a terminal
  bool progress_lines = false;    // the writer under mpirun, off a terminal
};

// Everything that can fail before a worker starts: the policy (into
// `options`' policy, configuration and sandbox), the configuration (its
// sources into options.config_notes), the policy's controller, the task's
// configuration; then the MPI ranks when started by mpirun. `registry`
// has its plugins loaded and outlives the factory.
PolicyRun preparePolicyRun(PluginRegistry& registry, const Arguments& args, const std::string& task,
                           const char* usage, EvaluationOptions& options);

// Stops on SIGINT, SIGTERM and SIGHUP (while the caller's StopSignals
// lives) and, under mpirun, shares the work among the ranks (`ranked`:
// RankedEvaluation or RankedGeneration, with its options and hooks).
template <class Ranked, class Options, class Hooks>
void shareAmongRanks(const PolicyRun& run, Options& options, Hooks& hooks, std::optional<Ranked>& ranked) {
  hooks.should_stop = [] { return StopSignals::isRequested(); };
  if (!run.mpi) return;
  ranked.emplace(*run.mpi);
  ranked->prepare(options, hooks, hooks.should_stop);
}

// Under mpirun stderr is a pipe, not the terminal: whether a progress line
// is due (every 10 s, and the last).
class ProgressLines {
 public:
  bool isDue(double elapsed, bool finished);

 private:
  double last_ = -1;
};

}  // namespace manibench::cli
