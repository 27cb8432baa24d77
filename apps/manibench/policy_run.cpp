#include "policy_run.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdlib>

namespace manibench::cli {

namespace {

double parsePositive(const Arguments& args, const std::string& option, double fallback, const char* usage) {
  const auto given = args.options.find(option);
  if (given == args.options.end()) return fallback;
  char* end = nullptr;
  const double value = std::strtod(given->second.c_str(), &end);
  if (!given->second.empty() && *end == '\0' && std::isfinite(value) && value > 0) return value;
  throw UsageError("--" + option + " needs a positive number, got '" + given->second + "'", usage);
}

}  // namespace

void parseWorkerOptions(const Arguments& args, const std::string& split, const char* usage,
                        EvaluationOptions& options) {
  options.split = parseSplit(args, split, usage);
  options.seed = parseSeed(valueOr(args, "seed", "0"), usage);
  const uint64_t workers = parseSeed(valueOr(args, "workers", "1"), usage, "--workers");
  if (workers < 1 || workers > 256) throw UsageError("--workers must be 1 to 256", usage);
  options.workers = unsigned(workers);
  options.step_timeout = parsePositive(args, "step-timeout", options.step_timeout, usage);
  options.environment_timeout = parsePositive(args, "env-timeout", options.environment_timeout, usage);
  if (args.options.count("objects")) {
    try {
      options.objects = parseIdList(args.options.at("objects"));
    } catch (const InvalidArgument& e) {
      throw UsageError(e.what(), usage);
    }
  }
}

PolicyRun preparePolicyRun(PluginRegistry& registry, const Arguments& args, const std::string& task,
                           const char* usage, EvaluationOptions& options) {
  PolicyRun run;
  run.sources = getConfigSources(args, parseObservationMode(args, usage));
  for (const std::string& file : run.sources.files) options.config_notes.push_back("--config " + file);
  for (const std::string& set : run.sources.overrides) options.config_notes.push_back("--set " + set);
  run.policy = choosePolicy(registry, args, usage);
  options.policy = run.policy.name;
  options.policy_config = run.policy.config;
  options.config_notes.insert(options.config_notes.end(), run.policy.notes.begin(), run.policy.notes.end());
  applyPolicyController(registry, options.policy, args, run.sources, usage);
  applySandboxOptions(args, options, run.policy.files, usage);
  run.task_id = resolveTaskId(registry, task);
  run.config = loadTaskConfig(registry, task, run.sources);
  run.environment = calcEnvironmentOptions(run.config);  // bad values fail here
  // A fixed-object id whose objects do not exist fails here, not in every
  // worker.
  if (run.task_id.isFixed()) {
    const TaskInstance probe(registry, run.task_id.task, run.environment.task_config);
    selectFixedObjects(run.task_id, probe.listObjects("train"), probe.listObjects("test"));
  }
  // Without the early done the workers' environments do not stop on
  // success: every episode runs to the time limit.
  options.early_done = !args.options.count(kNoEarlyDoneFlag);
  run.factory = [&registry, task, sources = run.sources, stop = options.early_done] {
    return makeEnvironment(registry, task, sources, stop);
  };
  // Under mpirun the ranks share the work; rank 0 alone prints and writes.
  if (MpiRanks::isStartedByMpi()) run.mpi = std::make_unique<MpiRanks>();
  run.writer = !run.mpi || run.mpi->getRank() == 0;
  const bool progress = run.writer && !args.options.count("no-progress");
  run.progress_bar = progress && isatty(STDERR_FILENO);
  run.progress_lines = progress && !run.progress_bar && run.mpi;
  return run;
}

bool ProgressLines::isDue(double elapsed, bool finished) {
  if (elapsed - last_ < 10 && !finished) return false;
  last_ = elapsed;
  return true;
}

}  // namespace manibench::cli
