// manibench eval: the evaluation kit (docs/evaluation.md). A policy on a
// task's objects, episodes in worker processes, results as a table, CSV and
// JSON.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <optional>
#include <manibench/evaluation.hpp>
#include <manibench/task_name.hpp>
#include <sstream>

#include "cli.hpp"
#include "eval_setup.hpp"
#include "mpi_ranks.hpp"
#include "policy_run.hpp"

namespace manibench::cli {

namespace {

const std::string kEvalUsageText = R"(usage: manibench eval [TASK] --policy NAME|PATH.so|PATH.py [options]
       manibench eval merge DIR... [--out DIR]
       manibench eval --verify DIR [--sample N] [--workers N]

Evaluates a policy on a task's objects (ManiSkill's evaluation kit): every
selected object times every level is one episode, with a seed derived from
--seed, the object and the level, so two runs give the same numbers. Episodes
run in worker processes: a policy that crashes, hangs or returns NaN or a
wrong-size action fails only its episode (recorded with the reason and step).
Prints a table per object (episodes, success rate, each success condition's
satisfactory rate; for doors and drawers the share of episodes that opened
25, 50, 75 and 90 % of the range), a row per category where the objects
have one (a PartNet folder's name), and writes summary.csv, episodes.csv
and summary.json.
certificate.json says what the results came from (SHA-256 of the plugins,
the policy's files, each object's files, the configuration). Ctrl-C stops
the run and writes the results collected so far.

Options:
  --task TASK             the task (or give it as the first word); a fixed-object
                          id <Task>_<object>-v<N> (e.g. Reach_3-v0) evaluates
                          only those objects, whatever --split says
)" + std::string(kPolicyUsage) + R"(  --obs MODE              observation mode: state, pointcloud or rgbd
                          (default: the configuration's observation.mode)
  --split train|test      objects to evaluate on (default test)
  --objects ID,ID,...     only these objects of the split
  --episodes-per-object N levels 0..N-1 of every object (default 5)
  --levels LIST           these levels instead, e.g. 0-9 or 3,7,12 or 0-4,9
  --seed S                base seed of the episode seeds (default 0)
  --no-early-done         run every episode to its time limit instead of
                          ending it at its first success (ManiSkill3's
                          protocol): success_once and success_at_end differ
  --workers N             worker processes (default 1)
  --step-timeout SEC      a policy call (reset, act) longer than this fails
                          its episode (default 10)
  --env-timeout SEC       limit for an environment reset/step and a worker's
                          setup (default 300)
  --out DIR               where the files go (default results)
  --no-progress           no progress bar (it is shown only on a terminal)
  --benchmark             run the evaluation with 1 worker, then with
                          --workers, check that both give the same results
                          and print the speedup
  --shard I/N             run only share I of N of the episode list (every
                          N-th episode; seeds as in the whole run): for job
                          arrays, combined by `eval merge` (docs/distributed.md)
  --resume                run only the episodes the journal in --out lacks
                          (a run that was killed or stopped); the files then
                          hold every episode
  --controller NAME       override the task's default controller (default: the
                          one the policy names, e.g. an expert's mobile_panda_ee)
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key; repeatable
)" + std::string(kSandboxUsage) + R"(Exit status: 0 when every episode ran (failed episodes included), 1 on an
error, 130 when interrupted (partial results written).
Under mpirun (mpirun -np R manibench eval ...) the ranks share the episodes
and rank 0 writes the files a single run writes (docs/distributed.md).

eval --verify DIR checks the report in DIR against its certificate.json
(build, plugin and policy files, object files, configuration) and runs its
episodes again (all, or --sample N of them): exit 0 when each is the
report's bit for bit, else 1 naming what differs first (docs/evaluation.md).

eval merge DIR... combines the results of shards (or of runs cut short) from
their journals into --out (default results): the files the whole run writes,
byte for byte. Episodes no DIR has are named (object, seed); the merged
files are then partial and `eval ... --out DIR --resume` runs what is
missing. Results of different evaluations are an error naming the
difference.
)";
}  // namespace

const char* const kEvalUsage = kEvalUsageText.c_str();

namespace {

// One line, redrawn in place on the terminal.
void drawProgress(const EvaluationProgress& p) {
  std::string details = ", " + std::to_string(p.successes) + " successful";
  if (p.failures) details += ", " + std::to_string(p.failures) + " failed";
  drawProgressBar(p.done, p.total, "episodes", details, p.elapsed);
}

bool sameResults(const EvaluationResult& a, const EvaluationResult& b) {
  std::ostringstream x, y;
  writeEpisodesCsv(x, a);
  writeEpisodesCsv(y, b);
  return x.str() == y.str();
}

// Under mpirun: a line now and then (Slurm's log keeps them too).
void printProgressLine(const EvaluationProgress& p) {
  static ProgressLines lines;
  if (!lines.isDue(p.elapsed, p.done >= p.total)) return;
  std::cerr << "progress: " << p.done << " of " << p.total << " episodes (every rank), " << p.successes
            << " successful, " << formatDuration(p.elapsed) << " elapsed\n";
}

// eval's own options: the episode list (levels, the shard).
void parseEpisodeList(const Arguments& args, EvaluationOptions& options) {
  try {
    if (args.options.count("levels")) {
      if (args.options.count("episodes-per-object"))
        throw UsageError("give --levels or --episodes-per-object, not both", kEvalUsage);
      options.levels = parseLevels(args.options.at("levels"));
    } else {
      const uint64_t n =
          parseSeed(valueOr(args, "episodes-per-object", "5"), kEvalUsage, "--episodes-per-object");
      if (n == 0 || n > 1000000)
        throw UsageError("--episodes-per-object must be 1 to 1000000", kEvalUsage);
      for (uint64_t level = 0; level < n; ++level) options.levels.push_back(level);
    }
    if (args.options.count("shard")) parseShard(args.options.at("shard"), options.shard, options.shards);
  } catch (const InvalidArgument& e) {
    throw UsageError(e.what(), kEvalUsage);
  }
}

// A rank but 0: runs its part, sends each record to rank 0, prints nothing
// but errors. Its exit status is 0 (an error is rank 0's to report: a
// non-zero status would make mpirun end the job before rank 0 writes).
int runOtherRank(const PluginRegistry& registry, const EvaluationOptions& options, const EnvironmentFactory& factory,
                 const EvaluationHooks& hooks, RankedEvaluation& ranked, int rank) {
  try {
    const EvaluationResult part = evaluatePolicy(registry, options, factory, hooks);
    ranked.finish(part.interrupted ? part.stop_reason : "");
  } catch (const std::exception& e) {
    std::cerr << "manibench: rank " << rank << ": " << e.what() << "\n";
    ranked.fail(e.what());
  }
  return 0;
}

// eval merge DIR... [--out DIR]
int mergeEvaluations(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 3, {"out"}, {}, kEvalUsage, {});
  if (args.help) {
    std::cout << kEvalUsage;
    return 0;
  }
  if (args.positional.empty()) throw UsageError("eval merge needs result folders", kEvalUsage);
  std::vector<EvaluationJournal> journals;
  for (const std::string& dir : args.positional)
    journals.push_back(readJournal((std::filesystem::path(dir) / kJournalFileName).string()));
  std::vector<EpisodeSpec> missing;
  const EvaluationResult merged = mergeJournals(journals, missing);
  const std::string out = valueOr(args, "out", "results");
  std::filesystem::create_directories(out);
  writeJournal((std::filesystem::path(out) / kJournalFileName).string(), merged);
  printEvaluationTable(std::cout, merged);
  for (const std::string& path : writeEvaluationFiles(out, merged)) std::cout << "wrote " << path << "\n";
  if (!missing.empty()) {
    std::cerr << "manibench: " << missing.size() << " of " << merged.planned.size()
              << " episodes are in none of the folders: " << describeEpisodes(missing, 20)
              << "; the files are partial: `manibench eval ... --out " << out
              << " --resume` runs them\n";
    return 1;
  }
  return 0;
}

// The journal of --out; with --resume, what it holds is not run again.
void prepareJournal(const Arguments& args, const std::string& out_dir, EvaluationOptions& options) {
  options.journal_path = (std::filesystem::path(out_dir) / kJournalFileName).string();
  if (!args.options.count("resume") || !std::filesystem::exists(options.journal_path)) return;
  const EvaluationJournal journal = readJournal(options.journal_path);
  options.resumed = journal.result.episodes;
  options.resumed_header = journal.header;
  std::cout << "resuming: " << options.resumed.size() << " episode(s) done in " << options.journal_path << "\n";
}

void printEvaluationStart(const EvaluationOptions& options, const PolicyRun& run) {
  std::cout << "evaluating policy " << options.policy << " on " << options.task << " ("
            << (run.task_id.isFixed() ? "its fixed objects" : options.split + " split") << "), "
            << options.levels.size() << " level(s) per object, seed " << options.seed << ", " << options.workers
            << " worker(s)"
            << (options.shards > 1
                    ? ", shard " + std::to_string(options.shard + 1) + "/" + std::to_string(options.shards)
                    : std::string())
            << (run.mpi ? ", " + std::to_string(run.mpi->getSize()) + " MPI rank(s)" : std::string())
            << ", the policy "
            << (options.sandbox_policy ? "sandboxed (" + describeSandbox() + ")"
                                       : std::string("in the workers (--trusted-policy)"))
            << "\n"
            << std::flush;
}

// The evaluation; with --benchmark, first with one worker into `baseline`
// (a run stopped then is the result, and the benchmark is off).
EvaluationResult runEvaluation(const PluginRegistry& registry, const EvaluationOptions& options,
                               const PolicyRun& run, const EvaluationHooks& hooks, bool& benchmark,
                               EvaluationResult& baseline) {
  if (benchmark) {
    EvaluationOptions one = options;
    one.workers = 1;
    std::cout << "benchmark: first with 1 worker, then with " << options.workers << "\n" << std::flush;
    one.journal_path.clear();
    baseline = evaluatePolicy(registry, one, run.factory, hooks);
    if (run.progress_bar) std::cerr << "\n";
    if (baseline.interrupted) {
      benchmark = false;
      return baseline;
    }
  }
  EvaluationResult result = evaluatePolicy(registry, options, run.factory, hooks);
  if (run.progress_bar) std::cerr << "\n";
  return result;
}

// The table, the files, the exit status.
int reportEvaluation(const EvaluationOptions& options, const EvaluationResult& result, bool benchmark,
                     const EvaluationResult& baseline, const std::string& out_dir,
                     const std::vector<std::string>& rank_errors) {
  // The files first: a stdout that blocks (mpirun's pipe) must not keep
  // them from disk.
  const std::vector<std::string> written = writeEvaluationFiles(out_dir, result);
  std::cout << "policy " << options.policy << " (" << result.policy_library << ", version "
            << result.policy_library_version << "), controller " << result.task.controller << ", observation "
            << toString(result.task.observation_mode) << "\n\n";
  printEvaluationTable(std::cout, result);
  std::cout << "\n"
            << result.episodes.size() << " of " << result.planned.size() << " episodes in " << std::fixed
            << std::setprecision(2) << result.seconds << " s (" << std::setprecision(1)
            << (result.seconds > 0 ? result.episodes.size() / result.seconds : 0) << " episodes/s, "
            << options.workers << " worker(s), " << result.worker_restarts << " worker restart(s))\n";
  if (benchmark) {
    std::cout << "benchmark: 1 worker " << std::setprecision(2) << baseline.seconds << " s, " << options.workers
              << " workers " << result.seconds << " s, speedup "
              << (result.seconds > 0 ? baseline.seconds / result.seconds : 0) << "x; results "
              << (sameResults(baseline, result) ? "identical" : "DIFFER") << "\n";
  }
  std::cout.unsetf(std::ios::fixed);
  for (const std::string& error : rank_errors) std::cerr << "manibench: " << error << "\n";
  for (const std::string& path : written) std::cout << "wrote " << path << "\n";
  if (result.interrupted) {
    std::cerr << "manibench: evaluation stopped (" << result.stop_reason << "): " << result.episodes.size()
              << " of " << result.planned.size() << " episodes; partial results written\n";
    return result.stop_reason == "interrupted" ? 130 : 1;
  }
  if (benchmark && !sameResults(baseline, result)) {
    std::cerr << "manibench: the runs with 1 and " << options.workers << " workers gave different results\n";
    return 1;
  }
  return 0;
}

}  // namespace

std::vector<std::string> describeEvalCommand(const Arguments& args) {
  // What --verify runs again: everything but where the files go and how
  // the work is spread (neither changes a result: docs/evaluation.md).
  static const std::vector<std::string> kLeftOut = {"out", "workers", "shard", "resume", "no-progress",
                                                    "benchmark"};
  static const std::vector<std::string> kFlags = {"no-progress", "benchmark", "resume", kTrustedPolicyFlag,
                                                  kNoEarlyDoneFlag};
  std::vector<std::string> command = args.positional;
  for (const auto& [key, value] : args.options) {
    if (std::find(kLeftOut.begin(), kLeftOut.end(), key) != kLeftOut.end()) continue;
    const bool flag = std::find(kFlags.begin(), kFlags.end(), key) != kFlags.end();
    command.push_back("--" + key + (flag ? "" : "=" + value));
  }
  for (const auto& [key, values] : args.repeated)
    for (const std::string& value : values) command.push_back("--" + key + "=" + value);
  return command;
}

Arguments parseEvalArguments(int argc, char** argv, int first) {
  return parseArguments(argc, argv, first,
                        {"task", "policy", "policy-config", "obs", "split", "objects", "episodes-per-object",
                         "levels", "seed", "workers", "step-timeout", "env-timeout", "out", "controller", "config",
                         "set", "policy-cpu-limit", "policy-memory-limit", "policy-output-limit", "policy-read",
                         "shard"},
                        {"no-progress", "benchmark", "resume", kTrustedPolicyFlag, kNoEarlyDoneFlag}, kEvalUsage,
                        {"config", "set", "policy-read"});
}

namespace {

// The files a policy configuration names (torch_policy's `checkpoint:`,
// a population's per-object policy.yaml, in turn), each scalar that is a
// regular file as written or beside the configuration: the policy's own
// files too, hashed into the certificate.
void addNamedFiles(const std::string& yaml_file, std::vector<std::string>& files, int depth = 0) {
  namespace fs = std::filesystem;
  ConfigNode config;
  try {
    config = loadConfigFile(yaml_file);
  } catch (const std::exception&) {
    return;  // not YAML: the file itself is hashed, the policy reports its own errors
  }
  const fs::path folder = fs::path(yaml_file).parent_path();
  std::function<void(const ConfigNode&)> walk = [&](const ConfigNode& node) {
    if (node.isScalar() && !node.scalar.empty() && node.scalar.size() < 4096) {
      std::error_code error;
      for (const fs::path& candidate : {fs::path(node.scalar), folder / node.scalar})
        if (fs::is_regular_file(candidate, error)) {
          const std::string path = candidate.string();
          if (std::find(files.begin(), files.end(), path) != files.end()) return;
          files.push_back(path);
          const std::string extension = candidate.extension().string();
          if ((extension == ".yaml" || extension == ".yml") && depth < 3) addNamedFiles(path, files, depth + 1);
          return;
        }
    }
    for (const ConfigNode& item : node.items) walk(item);
    for (const ConfigEntry& entry : node.entries) walk(entry.value);
  };
  walk(config);
}

}  // namespace

std::unique_ptr<EvalSetup> prepareEval(const Arguments& args) {
  std::string task = valueOr(args, "task", "");
  if (args.positional.size() > 1 || (args.positional.size() == 1 && !task.empty()))
    throw UsageError("eval takes one TASK (as a word or --task)", kEvalUsage);
  if (!args.positional.empty()) task = args.positional[0];
  if (task.empty()) throw UsageError("eval needs a TASK", kEvalUsage);
  if (!args.options.count("policy"))
    throw UsageError("eval needs --policy NAME|PATH.so|PATH.py", kEvalUsage);
  auto setup = std::make_unique<EvalSetup>();
  EvaluationOptions& options = setup->options;
  options.task = task;
  parseWorkerOptions(args, "test", kEvalUsage, options);
  parseEpisodeList(args, options);
  // Everything that can be checked here fails before any worker starts.
  loadPlugins(setup->registry);
  setup->run = preparePolicyRun(setup->registry, args, task, kEvalUsage, options);
  options.command = describeEvalCommand(args);
  options.policy_files = setup->run.policy.files;
  if (args.options.count("policy-config")) addNamedFiles(args.options.at("policy-config"), options.policy_files);
  options.configuration = formatConfig(setup->run.config);
  options.working_directory = std::filesystem::current_path().string();
  return setup;
}

int commandEval(int argc, char** argv) {
  if (argc > 2 && std::string(argv[2]) == "merge") return mergeEvaluations(argc, argv);
  for (int i = 2; i < argc; ++i)
    if (std::string(argv[i]) == "--verify" || std::string(argv[i]).rfind("--verify=", 0) == 0)
      return verifyEvaluation(argc, argv);
  const Arguments args = parseEvalArguments(argc, argv, 2);
  if (args.help) {
    std::cout << kEvalUsage;
    return 0;
  }
  const std::unique_ptr<EvalSetup> setup = prepareEval(args);
  EvaluationOptions& options = setup->options;
  const PluginRegistry& registry = setup->registry;
  const PolicyRun& run = setup->run;
  const std::string out_dir = valueOr(args, "out", "results");
  bool benchmark = args.options.count("benchmark") != 0;
  if (benchmark && run.mpi) throw UsageError("--benchmark runs without mpirun", kEvalUsage);
  if (run.writer) prepareJournal(args, out_dir, options);
  EvaluationHooks hooks;
  if (run.progress_bar) hooks.on_progress = drawProgress;
  if (run.progress_lines) hooks.on_progress = printProgressLine;
  const StopSignals stop_signals;
  std::optional<RankedEvaluation> ranked;
  shareAmongRanks(run, options, hooks, ranked);
  if (!run.writer) return runOtherRank(registry, options, run.factory, hooks, *ranked, run.mpi->getRank());

  printEvaluationStart(options, run);
  EvaluationResult baseline;
  const EvaluationResult result = runEvaluation(registry, options, run, hooks, benchmark, baseline);
  // stop_signals lives until the files are written (reportEvaluation writes
  // them before it prints): a second SIGTERM (mpirun's, Slurm's) or a stdout
  // that blocks must not cost the episodes the journal has. Under mpirun the
  // files have to be in place within Open MPI's grace between SIGTERM and
  // SIGKILL (1 s by default).
  return reportEvaluation(options, result, benchmark, baseline, out_dir,
                          ranked ? ranked->getErrors() : std::vector<std::string>());
}

}  // namespace manibench::cli
