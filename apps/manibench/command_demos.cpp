// manibench demos: demonstrations (docs/demonstrations.md). generate runs a
// policy in the evaluation kit's workers and keeps its successful episodes;
// replay re-simulates them (--check: bit for bit); convert renders another
// observation mode; info describes a file.
#include <unistd.h>

#include <manibench/demos.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/task_name.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "cli.hpp"
#include "mpi_ranks.hpp"
#include "policy_run.hpp"
#include "video.hpp"

namespace manibench::cli {
namespace {

const char* kDemosUsage = R"(usage: manibench demos generate|merge|replay|convert|info ...

  generate TASK --policy NAME|PATH.so|PATH.py --out FILE.h5 [options]
      Runs the policy (a plugin by name, a library, or a Python policy
      class, as for eval) on the split's objects in worker processes (as
      eval does: same seeds, same isolation) and keeps the successful episodes,
      each ending at its first success, until --per-object of every object.
      Ctrl-C (or SIGTERM/SIGHUP) stops and leaves a readable file with every
      trajectory finished so far.
        --split train|test     objects (default train)
        --objects ID,ID,...    only these objects of the split
        --per-object N         trajectories per object (default 1)
        --max-attempts N       episodes per object at most (default 10 x N)
        --workers N            worker processes (default 1)
        --seed S               base seed of the episode seeds (default 0)
        --obs MODE             observations recorded: state (default: the
                               configuration's), pointcloud or rgbd
        --policy-config FILE   YAML handed to the policy's create (not with
                               PATH.py)
        --action-noise SIGMA   add Gaussian noise of this standard deviation
                               to every action before it is executed (seeded
                               by the episode); the file keeps the executed
                               actions (replay) and the policy's own
                               (policy_actions: labels for learning)
        --controller NAME, --config FILE, --set KEY=VALUE
        --step-timeout SEC, --env-timeout SEC   as for eval
        --trusted-policy, --policy-cpu-limit SEC, --policy-memory-limit MIB,
        --policy-output-limit MIB, --policy-read PATH   as for eval: the
                               policy runs sandboxed unless --trusted-policy
        --no-progress          no progress bar
        --shard I/N            only share I of N of the objects (every N-th),
                               for job arrays; `demos merge` combines the
                               shards' files (docs/distributed.md)
        --resume               FILE.h5 exists (a run cut short): run only
                               the objects it lacks and complete it
  merge FILE.h5... --out FILE.h5
      Combines the files of `generate --shard` runs into the file the whole
      run writes (same trajectories, same order). Objects not finished in
      any of them are named; a file of another run is an error naming the
      difference.
  replay FILE.h5 [--trajectories traj_0,traj_3] [--check] [--video DIR]
      Re-simulates each trajectory from its first state with its actions;
      --check compares every step's state, observation, reward and flags
      with the recording, bit for bit, and reports the first difference.
      --video DIR writes DIR/traj_N.mp4 per trajectory (third-person
      camera, needs ffmpeg; --video-size WxH, default 640x480).
      Exit status 1 when any trajectory differs or cannot be read.
  convert FILE.h5 --obs pointcloud|rgbd --out FILE2.h5 [--workers N]
          [--controller NAME [--keep-failed]] [--trajectories LIST] [--set KEY=VALUE]...
          [--no-progress]
      The same trajectories with the observations of another mode, rendered
      at every recorded state in worker processes. --controller NAME (with
      or without --obs): the trajectories in another controller's actions,
      exactly where the file's controller is a layer over NAME
      (mobile_panda_ee over mobile_panda), at control rate (frame_skip 1);
      otherwise tracked: NAME follows the recorded states in closed loop,
      and a trajectory that no longer succeeds is left out unless
      --keep-failed.
  info FILE.h5 [--write-json]
      Task, versions, configuration sources, objects, counts, lengths,
      success and bytes per step; --write-json (re)writes the JSON sidecar.
)";

std::vector<std::string> parseTrajectoryList(const Arguments& args) {
  if (!args.options.count("trajectories")) return {};
  try {
    return parseIdList(args.options.at("trajectories"));
  } catch (const InvalidArgument& e) {
    throw UsageError(e.what(), kDemosUsage);
  }
}

uint64_t parseCount(const Arguments& args, const std::string& option, uint64_t fallback) {
  const uint64_t n = parseSeed(valueOr(args, option, std::to_string(fallback)), kDemosUsage, "--" + option);
  if (n < 1 || n > 1000000) throw UsageError("--" + option + " must be 1 to 1000000", kDemosUsage);
  return n;
}

std::string onePositional(const Arguments& args, const std::string& what) {
  if (args.positional.size() != 1) throw UsageError("demos " + what + " takes one file", kDemosUsage);
  return args.positional[0];
}

// generate's own options (the policy, the configuration and the options
// eval takes too are policy_run.hpp's).
GenerationOptions parseGenerationOptions(const Arguments& args, const std::string& task) {
  GenerationOptions options;
  EvaluationOptions& evaluation = options.evaluation;
  evaluation.task = task;
  parseWorkerOptions(args, "train", kDemosUsage, evaluation);
  if (args.options.count("action-noise")) {
    char* end = nullptr;
    evaluation.action_noise = std::strtod(args.options.at("action-noise").c_str(), &end);
    if (*end || !(evaluation.action_noise >= 0) || !std::isfinite(evaluation.action_noise))
      throw UsageError("--action-noise needs a non-negative number", kDemosUsage);
  }
  options.per_object = uint32_t(parseCount(args, "per-object", 1));
  options.max_attempts = uint32_t(parseCount(args, "max-attempts", 10 * uint64_t(options.per_object)));
  if (args.options.count("shard")) {
    try {
      parseShard(args.options.at("shard"), options.shard, options.shards);
    } catch (const InvalidArgument& e) {
      throw UsageError(e.what(), kDemosUsage);
    }
  }
  return options;
}

// The file so far and the rest (resumed), or the ranks' trajectories as
// they came (MPI), into `out` in the order the run writes them; the parts
// are removed. The number of trajectories.
std::size_t mergeParts(const std::string& out, const std::string& part, bool resume, const DemoFileInfo& info,
                       const GenerationOptions& options) {
  std::vector<std::string> parts = {part};
  if (resume) {
    parts.insert(parts.begin(), out + ".before.h5");
    std::filesystem::rename(out, parts.front());
  }
  const DemoMergeResult merged = mergeDemonstrations(parts, out, info, options.shard, options.shards);
  for (const std::string& file : parts) {
    std::filesystem::remove(file);
    std::filesystem::remove(getDemoJsonPath(file));
  }
  if (resume) std::cout << "resumed " << out << ": " << merged.trajectories << " trajectories\n";
  return merged.trajectories;
}

// What a generation did, on the terminal; the exit status.
int reportGeneration(const GenerationResult& result, const GenerationOptions& options, const std::string& out) {
  std::size_t short_objects = 0;
  for (const GenerationObjectResult& o : result.objects) {
    if (o.kept >= options.per_object) continue;
    ++short_objects;
    std::cout << "  object " << o.object_id << ": " << o.kept << " of " << options.per_object
              << " after " << o.attempts << " episode(s)"
              << (o.failures ? " (" + std::to_string(o.failures) + " failed)" : "") << "\n";
  }
  std::cout << "wrote " << result.trajectories << " trajectories of " << result.objects.size()
            << " object(s) from " << result.episodes << " episodes in " << std::fixed
            << std::setprecision(2) << result.seconds << " s (" << std::setprecision(1)
            << (result.seconds > 0 ? double(result.episodes) / result.seconds : 0.0)
            << " episodes/s) to " << out << " and " << getDemoJsonPath(out) << "\n";
  std::cout.unsetf(std::ios::fixed);
  if (result.interrupted) {
    std::cerr << "manibench: generation stopped (" << result.stop_reason << "); " << out
              << " holds the " << result.trajectories << " trajectories finished\n";
    return 130;
  }
  if (short_objects) {
    std::cerr << "manibench: " << short_objects << " object(s) got fewer than " << options.per_object
              << " successful episodes within " << options.max_attempts << " attempts\n";
    return 1;
  }
  return 0;
}

// Where this process writes: the file, or (resumed, or trajectories
// arriving from ranks in any order) a part that is merged into it in the
// run's order; another rank writes a scratch file of its own.
std::string choosePartPath(const std::string& out, bool resume, const PolicyRun& run) {
  if (resume) return out + ".rest.h5";
  if (run.mpi && run.writer) return out + ".unordered.h5";
  if (run.writer) return out;
  const char* tmp = std::getenv("TMPDIR");
  return std::string(tmp && *tmp ? tmp : "/tmp") + "/manibench-demos-rank" + std::to_string(run.mpi->getRank()) +
         "-" + std::to_string(getpid()) + ".h5";
}

// What the file records of its making.
DemoFileInfo describeGeneration(const PluginRegistry& registry, const PolicyRun& run, const std::string& task,
                                const std::string& policy, int argc, char** argv) {
  DemoFileInfo info;
  info.manibench_version = getManibenchVersion();
  info.task = run.task_id.task;
  info.environment_id = task;
  info.config = formatConfig(run.config);
  info.plugins = describePlugins(registry);
  const LoadedLibrary& library = registry.getLibraries()[registry.getEntry(PluginKind::Policy, policy).library];
  info.policy = policy + " (" + library.path + ", version " + library.version + ")";
  info.created = formatUtcNow();
  info.command = joinCommand(argc, argv);
  return info;
}

void setProgressHook(const PolicyRun& run, GenerationHooks& hooks) {
  if (run.progress_bar)
    hooks.on_progress = [](const GenerationProgress& p) {
      std::string details = ", " + std::to_string(p.episodes) + " episodes";
      if (p.failures) details += ", " + std::to_string(p.failures) + " failed";
      drawProgressBar(p.kept, p.wanted, "trajectories", details, p.elapsed);
    };
  if (run.progress_lines)
    hooks.on_progress = [lines = ProgressLines()](const GenerationProgress& p) mutable {
      if (!lines.isDue(p.elapsed, p.kept >= p.wanted)) return;
      std::cerr << "progress: " << p.kept << " of " << p.wanted << " trajectories (every rank), " << p.episodes
                << " episodes here, " << formatDuration(p.elapsed) << " elapsed\n";
    };
}

// A rank but 0: its trajectories go to rank 0; exit status 0 (as eval's).
int generateOnOtherRank(const PluginRegistry& registry, const GenerationOptions& options, const PolicyRun& run,
                        const std::string& path, const DemoFileInfo& info, const GenerationHooks& hooks,
                        RankedGeneration& ranked) {
  try {
    const GenerationResult part = generateDemonstrations(registry, options, run.factory, path, info, hooks);
    ranked.finish(formatGenerationResult(part, options.per_object, options.max_attempts));
  } catch (const std::exception& e) {
    std::cerr << "manibench: rank " << run.mpi->getRank() << ": " << e.what() << "\n";
    ranked.fail(e.what());
  }
  for (const std::string& file : {path, getDemoJsonPath(path)}) std::filesystem::remove(file);
  return 0;
}

int generate(int argc, char** argv) {
  const Arguments args = parseArguments(
      argc, argv, 3,
      {"policy", "policy-config", "out", "split", "objects", "per-object", "max-attempts", "workers",
       "seed", "obs", "controller", "config", "set", "step-timeout", "env-timeout", "action-noise",
       "policy-cpu-limit", "policy-memory-limit", "policy-output-limit", "policy-read", "shard"},
      {"no-progress", "resume", kTrustedPolicyFlag}, kDemosUsage, {"config", "set", "policy-read"});
  if (args.positional.size() != 1) throw UsageError("demos generate takes one TASK", kDemosUsage);
  if (!args.options.count("policy")) throw UsageError("demos generate needs --policy", kDemosUsage);
  if (!args.options.count("out")) throw UsageError("demos generate needs --out FILE.h5", kDemosUsage);
  const std::string task = args.positional[0];
  const std::string out = args.options.at("out");
  GenerationOptions options = parseGenerationOptions(args, task);
  EvaluationOptions& evaluation = options.evaluation;

  PluginRegistry registry;
  loadPlugins(registry);
  const PolicyRun run = preparePolicyRun(registry, args, task, kDemosUsage, evaluation);
  const bool resume = run.writer && args.options.count("resume") && std::filesystem::exists(out);
  if ((options.shards > 1 || resume || run.mpi) && evaluation.objects.empty()) {
    // A share of the objects, or those left, is taken from the whole list,
    // which the file records: the split's, as the workers will see it.
    const TaskInstance probe(registry, run.task_id.task, run.environment.task_config);
    evaluation.objects = run.task_id.isFixed() ? selectFixedObjects(run.task_id, probe.listObjects("train"),
                                                                    probe.listObjects("test"))
                                               : probe.listObjects(evaluation.split);
  }
  const std::string path = choosePartPath(out, resume, run);
  const DemoFileInfo info = describeGeneration(registry, run, task, evaluation.policy, argc, argv);
  if (resume) {
    for (const std::string& object : findDoneObjects(out)) options.done_objects.insert(object);
    // Another run's file is an error before anything runs.
    DemoFileInfo expected = info;
    expected.generation = formatGeneration(options, evaluation.objects, options.max_attempts);
    const std::string difference = findGenerationDifference(out, expected);
    if (!difference.empty())
      throw std::runtime_error("--resume: " + out + " is of another generation (" + difference + " here)");
  }
  GenerationHooks hooks;
  setProgressHook(run, hooks);
  const StopSignals stop_signals;
  std::optional<RankedGeneration> ranked;
  shareAmongRanks(run, options, hooks, ranked);
  if (!run.writer) return generateOnOtherRank(registry, options, run, path, info, hooks, *ranked);
  std::cout << "generating " << options.per_object << " trajectory(ies) per object of " << task << " ("
            << evaluation.split << " split) with policy " << evaluation.policy << ", " << evaluation.workers
            << " worker(s)" << (run.mpi ? ", " + std::to_string(run.mpi->getSize()) + " MPI rank(s)" : std::string())
            << ", into " << out << "\n"
            << std::flush;
  std::size_t own = 0;
  for (std::size_t i = 0; i < evaluation.objects.size(); ++i)
    own += i % options.shards == options.shard && !options.done_objects.count(evaluation.objects[i]);
  if (resume && own == 0) {
    std::cout << out << " has every object of its run: nothing to resume\n";
    return 0;
  }
  GenerationResult result = generateDemonstrations(registry, options, run.factory, path, info, hooks);
  // stop_signals lives until the files are written: a second signal must
  // not kill the merge of what was kept.
  if (run.progress_bar) std::cerr << "\n";
  if (ranked)
    for (const std::string& error : ranked->getErrors()) std::cerr << "manibench: " << error << "\n";
  if (path != out) result.trajectories = mergeParts(out, path, resume, info, options);
  return reportGeneration(result, options, out);
}

// demos merge FILE.h5... --out FILE.h5
int merge(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 3, {"out"}, {}, kDemosUsage, {});
  if (args.positional.empty()) throw UsageError("demos merge needs files", kDemosUsage);
  if (!args.options.count("out")) throw UsageError("demos merge needs --out FILE.h5", kDemosUsage);
  const std::string out = args.options.at("out");
  for (const std::string& input : args.positional)
    if (std::filesystem::exists(out) && std::filesystem::equivalent(input, out))
      throw UsageError("--out must be another file than the inputs", kDemosUsage);
  DemoFileInfo info;
  info.created = formatUtcNow();
  info.command = joinCommand(argc, argv);
  const DemoMergeResult merged = mergeDemonstrations(args.positional, out, info);
  std::cout << "wrote " << merged.trajectories << " trajectories of " << merged.done_objects.size()
            << " object(s) to " << out << "\n";
  if (merged.missing.empty()) return 0;
  for (const std::string& m : merged.missing) std::cerr << "manibench: missing: " << m << "\n";
  std::cerr << "manibench: " << merged.missing.size()
            << " object(s) unfinished; `demos generate ... --shard I/N --out SHARD.h5 --resume` on "
               "their shard completes it, then merge again\n";
  return 1;
}

int replay(int argc, char** argv) {
  const Arguments args =
      parseArguments(argc, argv, 3, {"trajectories", "video", "video-size"}, {"check"}, kDemosUsage);
  const std::string path = onePositional(args, "replay");
  const bool check = args.options.count("check") != 0;
  const std::string video_dir = valueOr(args, "video", "");
  const auto [video_width, video_height] = parseVideoSize(args, kDemosUsage);
  if (!video_dir.empty()) {
    std::error_code error;
    std::filesystem::create_directories(video_dir, error);
    if (error) throw std::runtime_error("cannot create " + video_dir + ": " + error.message());
  }
  const DemoReader reader(path);
  std::vector<std::string> names = parseTrajectoryList(args);
  if (names.empty()) names = reader.getTrajectoryNames();
  PluginRegistry registry;
  loadPlugins(registry);
  const std::unique_ptr<Environment> env = makeDemoEnvironment(registry, reader.getInfo());
  std::size_t identical = 0, differ = 0, unreadable = 0;
  for (const std::string& name : names) {
    std::cout << name << ": " << std::flush;
    try {
      const Trajectory t = reader.read(name);
      std::cout << "object " << t.object_id << ", level " << t.level << ", seed " << t.seed << ", "
                << t.steps << " steps: " << std::flush;
      std::unique_ptr<EpisodeVideo> video;
      if (!video_dir.empty())
        video = std::make_unique<EpisodeVideo>(*env, (std::filesystem::path(video_dir) / (name + ".mp4")).string(),
                                               video_width, video_height);
      const ReplayResult r = replayTrajectory(*env, t, check, [&](uint32_t step) {
        if (!video) return;
        if (step == 0) video->aimAtRobot();
        video->record();
      });
      if (video) video->close();
      if (!check) {
        std::cout << "replayed " << r.steps << " steps\n";
      } else if (r.matches) {
        ++identical;
        std::cout << "bit-identical\n";
      } else {
        ++differ;
        std::cout << "DIFFERS at " << r.divergence << "\n";
      }
    } catch (const std::exception& e) {
      ++unreadable;
      std::cout << "error: " << e.what() << "\n";
    }
  }
  std::cout << names.size() << " trajectories";
  if (check) std::cout << ": " << identical << " bit-identical, " << differ << " differ";
  if (unreadable) std::cout << ", " << unreadable << " could not be replayed";
  std::cout << "\n";
  return differ || unreadable ? 1 : 0;
}

int convert(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 3,
                                        {"obs", "out", "workers", "trajectories", "set", "controller"},
                                        {"no-progress", "keep-failed"}, kDemosUsage);
  const std::string path = onePositional(args, "convert");
  const std::optional<ObservationMode> mode = parseObservationMode(args, kDemosUsage);
  const bool controller = args.options.count("controller") > 0;
  if (!mode && !controller)
    throw UsageError("demos convert needs --obs pointcloud|rgbd|state or --controller NAME", kDemosUsage);
  if (!args.options.count("out")) throw UsageError("demos convert needs --out FILE.h5", kDemosUsage);
  const std::string out = args.options.at("out");
  if (out == path) throw UsageError("--out must be another file than the input", kDemosUsage);
  const unsigned workers = unsigned(std::min<uint64_t>(parseCount(args, "workers", 1), 256));
  std::vector<std::string> overrides;
  if (args.repeated.count("set")) overrides = args.repeated.at("set");
  if (mode) overrides.push_back(std::string("observation.mode=") + toString(*mode));
  if (controller) overrides.push_back("control.controller=" + args.options.at("controller"));

  PluginRegistry registry;
  loadPlugins(registry);
  DemoFileInfo info;
  {
    const DemoReader reader(path);
    info = reader.getInfo();
  }
  info.plugins = describePlugins(registry);
  info.manibench_version = getManibenchVersion();
  info.created = formatUtcNow();
  info.command = joinCommand(argc, argv);
  const bool progress = !args.options.count("no-progress") && isatty(STDERR_FILENO);
  ConversionHooks hooks;
  if (progress)
    hooks.on_progress = [](std::size_t done, std::size_t total, double elapsed) {
      drawProgressBar(done, total, "trajectories", "", elapsed);
    };
  hooks.should_stop = [] { return StopSignals::isRequested(); };
  ConversionResult result;
  {
    StopSignals stop_signals;
    result = convertDemonstrations(registry, path, out, overrides, parseTrajectoryList(args), workers,
                                   info, hooks, args.options.count("keep-failed") > 0);
  }
  if (progress) std::cerr << "\n";
  for (const std::string& note : result.redone) std::cout << "redone: " << note << "\n";
  for (const std::string& failure : result.failed) std::cout << "not converted: " << failure << "\n";
  for (const std::string& drop : result.dropped) std::cout << "left out: " << drop << "\n";
  std::cout << "wrote " << result.converted << " trajectories";
  if (!result.dropped.empty())
    std::cout << " (" << result.dropped.size() << " left out: no longer successful; --keep-failed keeps them)";
  if (mode) std::cout << " in " << toString(*mode) << " mode";
  if (controller) std::cout << " for controller " << args.options.at("controller");
  std::cout << " to " << out << " in " << std::fixed << std::setprecision(2) << result.seconds << " s\n";
  std::cout.unsetf(std::ios::fixed);
  if (!result.failed.empty())
    std::cout << result.failed.size() << " of the input's trajectories not converted (listed above)\n";
  if (result.interrupted) return 130;
  return result.failed.empty() ? 0 : 1;
}

int info(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 3, {}, {"write-json"}, kDemosUsage);
  const std::string path = onePositional(args, "info");
  const DemoReader reader(path);
  const DemoFileInfo& info = reader.getInfo();
  std::cout << "file           " << path << "\n"
            << "format         manibench-demonstrations, version " << info.format_version << "\n"
            << "made by        manibench " << info.manibench_version << ", " << info.created << "\n"
            << "command        " << info.command << "\n"
            << "task           " << info.task << " (environment " << info.environment_id << ")\n"
            << "controller     " << info.controller << "\n";
  if (!info.converted_from.empty())
    std::cout << "converted from " << info.converted_from << " (" << info.conversion << ")\n";
  std::cout << "observations   " << toString(info.observation_mode) << "\n"
            << "policy         " << info.policy << "\n";
  std::cout << "conditions    ";
  for (const std::string& c : info.condition_names) std::cout << " " << c;
  std::cout << "\n";
  struct PerObject {
    std::size_t count = 0, successes = 0, steps = 0;
    uint32_t shortest = UINT32_MAX, longest = 0;
  };
  std::map<std::string, PerObject> objects;
  std::vector<Trajectory> summaries;
  std::vector<std::string> names;  // of the summaries
  uint64_t bytes = 0, steps = 0;
  std::size_t unreadable = 0;
  // A file cut short: only a trajectory that reads whole counts (its
  // attributes may lie before the cut and its data after).
  const bool cut = reader.getRecordedBytes() > reader.getFileBytes();
  for (const std::string& name : reader.getTrajectoryNames()) {
    try {
      if (cut) reader.read(name);
      const Trajectory t = reader.readSummary(name);
      bytes += reader.calcStorageBytes(name);
      steps += t.steps;
      PerObject& o = objects[t.object_id];
      ++o.count;
      o.successes += t.success;
      o.steps += t.steps;
      o.shortest = std::min(o.shortest, t.steps);
      o.longest = std::max(o.longest, t.steps);
      summaries.push_back(t);
      names.push_back(name);
    } catch (const DemoError& e) {
      ++unreadable;
      std::cout << "unreadable     " << e.what() << "\n";
    }
  }
  // A tracked conversion's: how closely its TCPs followed the recording.
  double tracking_error = -1;
  for (const Trajectory& t : summaries) tracking_error = std::max(tracking_error, t.tracking_error);
  if (tracking_error >= 0) std::cout << "tracking error largest " << tracking_error << " m (TCP to the recording's)\n";
  std::cout << "trajectories   " << summaries.size() << " of " << objects.size() << " object(s), "
            << steps << " steps";
  if (cut)
    std::cout << " (" << unreadable << " unreadable: the file is cut short, " << reader.getFileBytes()
              << " of the " << reader.getRecordedBytes() << " bytes its HDF5 superblock records)";
  else if (unreadable)
    std::cout << " (" << unreadable << " unreadable)";
  std::cout << "\n"
            << "storage        " << bytes << " bytes, " << std::fixed << std::setprecision(0)
            << (steps ? double(bytes) / double(steps) : 0.0) << " bytes per step\n\n";
  std::cout << "object         trajectories  successful  steps (mean, min-max)\n";
  for (const auto& [id, o] : objects)
    std::cout << std::left << std::setw(15) << id << std::right << std::setw(12) << o.count
              << std::setw(12) << o.successes << "  " << std::setprecision(1)
              << double(o.steps) / double(o.count) << ", " << o.shortest << "-" << o.longest << "\n";
  std::cout.unsetf(std::ios::fixed);
  if (args.options.count("write-json")) {
    const std::string json_path = getDemoJsonPath(path);
    std::ofstream out(json_path);
    out << formatDemoJson(info, names, summaries);
    if (!out) throw std::runtime_error("cannot write '" + json_path + "'");
    std::cout << "wrote " << json_path << "\n";
  }
  return unreadable ? 1 : 0;
}

}  // namespace

int commandDemos(int argc, char** argv) {
  const std::string sub = argc > 2 ? argv[2] : "";
  if (sub == "--help" || sub == "-h") {
    std::cout << kDemosUsage;
    return 0;
  }
  if (sub.empty()) throw UsageError("demos needs a command: generate, merge, replay, convert or info", kDemosUsage);
  for (int i = 3; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::cout << kDemosUsage;
      return 0;
    }
  if (sub == "generate") return generate(argc, argv);
  if (sub == "replay") return replay(argc, argv);
  if (sub == "merge") return merge(argc, argv);
  if (sub == "convert") return convert(argc, argv);
  if (sub == "info") return info(argc, argv);
  throw UsageError("unknown demos command '" + sub + "'", kDemosUsage);
}

}  // namespace manibench::cli
