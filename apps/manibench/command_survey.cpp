// manibench survey: a policy (by default the task's expert) on every object
// of one or more folders (a PartNet-Mobility download's categories), N
// levels each, every failure classified from the task's progress signals
// (manibench/outcome.hpp): what a user runs on their own download to see
// what the benchmark supports on it (docs/partnet.md, "Surveying a folder").
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <manibench/episode.hpp>
#include <manibench/outcome.hpp>
#include <manibench/stopwatch.hpp>

#include "cli.hpp"
#include "survey_report.hpp"

namespace manibench::cli {

namespace {

const std::string kSurveyUsageText = R"(usage: manibench survey TASK DIR... [options]

Runs a policy on every object of each DIR (a folder of PartNet-Mobility
objects, one sub-folder per object: one category of a download, e.g.
DATA/StorageFurniture DATA/Table), both splits, levels 0..N-1 of each, with
the evaluation's episode seeds (eval --seed S gives the same episodes).
Prints per object and per category (the folder's name) the success rate,
the first level that succeeded, and why each other episode failed, told
from the task's progress signals (abi.h, ABI 1.6): never_reached, blocked,
not_grasped, grasp_lost, not_moved, wrong_way, not_static, time_limit; an
object the task cannot load is `refused`, with its reason. Each object's
scene build time is measured the first time in this process and again.
Writes episodes.csv, objects.csv, survey.json and survey.svg into --out.

Options:
)" + std::string(kPolicyUsage) + R"(                          default: the first registered *_expert policy that
                          accepts TASK
  --episodes-per-object N levels 0..N-1 of every object (default 5)
  --levels LIST           these levels instead, e.g. 0-9 or 3,7
  --seed S                base seed of the episode seeds (default 0)
  --out DIR               where the files go (default survey)
  --no-progress           no progress bar (it is shown only on a terminal)
  --controller NAME       override the controller (default: the policy's)
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key; repeatable (task.partnet_dir is set per DIR)
The policy runs in this process: a policy that crashes ends the survey
(use eval's sandbox for untrusted policies).
)";
const char* const kSurveyUsage = kSurveyUsageText.c_str();

// What the task printed on stderr while it listed its objects: the kit's
// catalog names each object it skips there, one line each
// ("manibench: warning: TASK: skipping PartNet NOUN ID (PATH): REASON",
// sdk/kit/include/manibench/kit/catalog.hpp). The lines are passed on.
class StderrCapture {
 public:
  StderrCapture() {
    std::fflush(stderr);
    std::cerr.flush();
    file_ = std::tmpfile();
    saved_ = dup(STDERR_FILENO);
    if (file_ != nullptr && saved_ >= 0) dup2(fileno(file_), STDERR_FILENO);
  }
  // Restores stderr and returns what was written meanwhile (also echoed).
  std::string finish() {
    std::fflush(stderr);
    std::cerr.flush();
    std::string text;
    if (saved_ >= 0) {
      dup2(saved_, STDERR_FILENO);
      close(saved_);
      saved_ = -1;
    }
    if (file_ != nullptr) {
      std::rewind(file_);
      char buffer[4096];
      for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, file_)) > 0;) text.append(buffer, n);
      std::fclose(file_);
      file_ = nullptr;
    }
    std::cerr << text << std::flush;
    return text;
  }
  ~StderrCapture() {
    if (saved_ >= 0 || file_ != nullptr) finish();
  }

 private:
  std::FILE* file_ = nullptr;
  int saved_ = -1;
};

// What the catalog's warning lines say, by object id (kit/catalog.hpp):
// the objects it skipped with the reason, and the targets it left out of
// objects it kept ("link_0: it reaches 2.5 cm into the ground ...").
struct ListingWarnings {
  std::map<std::string, std::string> skipped;
  std::map<std::string, std::vector<std::string>> left_out;
};

ListingWarnings parseListingWarnings(const std::string& text) {
  ListingWarnings warnings;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    const bool skipping = line.find(": skipping PartNet ") != std::string::npos;
    const std::size_t at = line.find(skipping ? ": skipping PartNet " : ": PartNet ");
    const std::size_t reason = line.find("): ", at);
    if (at == std::string::npos || reason == std::string::npos) continue;
    std::istringstream words(line.substr(line.find("PartNet ", at) + 8));
    std::string noun, id;
    words >> noun >> id;
    if (id.empty()) continue;
    const std::string what = line.substr(reason + 3);
    if (skipping)
      warnings.skipped[id] = what;
    else if (what.rfind("leaving out ", 0) == 0)
      warnings.left_out[id].push_back(what.substr(12));
  }
  return warnings;
}

// The object an id belongs to: "40147_link_0" -> "40147".
std::string getGroup(const std::string& id) {
  const std::size_t at = id.rfind("_link_");
  return at == std::string::npos ? id : id.substr(0, at);
}

// --policy, or the first *_expert that accepts the task's layout.
PolicyChoice chooseSurveyPolicy(mb::PluginRegistry& registry, const Arguments& args, const std::string& task,
                                const mb::ConfigSources& sources) {
  if (args.options.count("policy")) return choosePolicy(registry, args, kSurveyUsage);
  for (const std::string& name : registry.getNames(mb::PluginKind::Policy)) {
    if (name.size() < 7 || name.compare(name.size() - 7, 7, "_expert") != 0) continue;
    try {
      Arguments with_policy = args;
      with_policy.options["policy"] = name;
      mb::ConfigSources own = sources;
      applyPolicyController(registry, name, with_policy, own, kSurveyUsage);
      const auto env = makeEnvironment(registry, task, own, true);
      mb::PolicyInstance probe(registry, name, "", env->calcPolicyLayout());
      PolicyChoice choice;
      choice.name = name;
      return choice;
    } catch (const std::exception&) {
      // not this task's expert
    }
  }
  throw UsageError("no registered *_expert policy accepts " + task + ": give --policy", kSurveyUsage);
}

struct SurveyRun {
  mb::PluginRegistry* registry = nullptr;
  std::string task;
  PolicyChoice policy;
  mb::ConfigSources sources;  // the user's, with the policy's controller
  std::vector<uint64_t> levels;
  uint64_t seed = 0;
  bool progress = false;
  std::size_t done = 0, total_guess = 0;
  mb::Clock::time_point start = mb::Clock::now();
};

// One episode, classified.
SurveyEpisode runSurveyEpisode(mb::Environment& env, mb::ActingPolicy& policy, const std::string& id, uint64_t level,
                               uint64_t seed) {
  SurveyEpisode e;
  e.object_id = id;
  e.level = level;
  e.seed = mb::calcEpisodeSeed(seed, id, level);
  mb::OutcomeTracker tracker(env.getTaskDescription().progress_signals);
  mb::EpisodeHooks hooks;
  hooks.on_step = [&](const mb::StepResult&, const mb::EpisodeResult&) {
    tracker.add(env.measureProgress());
    return true;
  };
  try {
    const mb::EpisodeResult r = mb::runEpisode(env, policy, id, e.seed, hooks);
    e.success = r.success;
    e.steps = r.steps;
    e.reward = r.total_reward;
    e.outcome = tracker.classify(r.success);
    // The task's own conditions left unmet at the end, for a failure the
    // signals cannot tell apart (a bucket on the platform with its ball
    // out is not_static by progress).
    if (!r.success) {
      std::string unmet;
      for (std::size_t c = 0; c + 1 < r.condition_names.size() && c < r.final_flags.size(); ++c)
        if (!r.final_flags[c]) unmet += (unmet.empty() ? "" : " ") + r.condition_names[c];
      if (!unmet.empty()) e.message = "unmet at the end: " + unmet;
    }
  } catch (const std::logic_error&) {
    throw;
  } catch (const std::exception& error) {
    e.outcome = mb::outcome::kError;
    e.message = error.what();
  }
  e.max_progress = tracker.getMaxProgress();
  e.final_progress = tracker.getFinalProgress();
  e.first_reached = tracker.getFirstReachedStep();
  e.first_held = tracker.getFirstHeldStep();
  return e;
}

// Every object of one folder.
void surveyCategory(SurveyRun& run, const std::string& dir, SurveyReport& report) {
  const std::string category = std::filesystem::path(dir).lexically_normal().filename().empty()
                                   ? std::filesystem::path(dir).lexically_normal().parent_path().filename().string()
                                   : std::filesystem::path(dir).lexically_normal().filename().string();
  mb::ConfigSources sources = run.sources;
  sources.overrides.push_back("task.partnet_dir=" + dir);
  std::cout << "== " << category << " (" << dir << ")\n" << std::flush;
  StderrCapture capture;
  const mb::Clock::time_point listing = mb::Clock::now();
  std::unique_ptr<mb::Environment> env;
  std::vector<std::string> ids;
  std::string build_error;
  try {
    env = makeEnvironment(*run.registry, run.task, sources, true);
    for (const char* split : {"train", "test"})
      for (const std::string& id : env->listObjects(split)) ids.push_back(id);
  } catch (const std::logic_error&) {
    throw;
  } catch (const std::exception& e) {
    build_error = e.what();  // no object of the folder loads
  }
  const double listing_s = mb::secondsSince(listing);
  ListingWarnings warnings = parseListingWarnings(capture.finish());
  std::map<std::string, std::string>& refused = warnings.skipped;
  if (env)
    for (const auto& [id, reason] : env->getSkippedObjects()) refused[getGroup(id)] = reason;
  // An object whose every target was left out has no id in the listing:
  // refused, with the reasons, rather than missing from the survey.
  for (const auto& [id, notes] : warnings.left_out) {
    const bool listed = std::any_of(ids.begin(), ids.end(), [&](const std::string& i) { return getGroup(i) == id; });
    if (listed || refused.count(id)) continue;
    std::string reason = "every target left out:";
    for (const std::string& note : notes) reason += (reason.back() == ':' ? " " : "; ") + note;
    refused[id] = reason;
  }
  report.addCategory(category, dir, listing_s, build_error);
  for (const auto& [id, reason] : refused) report.addRefused(category, id, reason);
  if (!env) return;
  mb::PolicyInstance policy(*run.registry, run.policy.name, run.policy.config, env->calcPolicyLayout());
  std::string previous_group;
  for (const std::string& id : ids) {
    const std::string group = getGroup(id);
    if (group != previous_group) {
      previous_group = group;
      SurveyObject object;
      object.category = category;
      object.object = group;
      if (warnings.left_out.count(group)) object.left_out = warnings.left_out.at(group);
      try {
        const mb::Clock::time_point cold = mb::Clock::now();
        env->loadObject(id);
        object.first_load_s = mb::secondsSince(cold);
        const mb::Clock::time_point warm = mb::Clock::now();
        env->loadObject(id);
        object.again_s = mb::secondsSince(warm);
      } catch (const std::logic_error&) {
        throw;
      } catch (const std::exception& e) {
        report.addRefused(category, group, e.what());
        continue;
      }
      report.addObject(object);
    }
    for (const uint64_t level : run.levels) {
      if (StopSignals::isRequested()) return;
      SurveyEpisode e = runSurveyEpisode(*env, policy, id, level, run.seed);
      e.category = category;
      e.object = group;
      report.addEpisode(e);
      ++run.done;
      if (run.progress)
        drawProgressBar(run.done, std::max(run.done, run.total_guess), "episodes",
                        " (" + category + " " + id + ")", mb::secondsSince(run.start));
    }
  }
  if (run.progress) std::cerr << "\n";
}

}  // namespace

int commandSurvey(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2,
                                        {"policy", "policy-config", "episodes-per-object", "levels", "seed", "out",
                                         "controller", "config", "set"},
                                        {"no-progress"}, kSurveyUsage);
  if (args.help) {
    std::cout << kSurveyUsage;
    return 0;
  }
  if (args.positional.size() < 2) throw UsageError("survey needs a TASK and at least one DIR", kSurveyUsage);
  SurveyRun run;
  run.task = args.positional[0];
  std::vector<std::string> dirs(args.positional.begin() + 1, args.positional.end());
  for (const std::string& dir : dirs)
    if (!std::filesystem::is_directory(dir)) throw UsageError("'" + dir + "' is not a folder", kSurveyUsage);
  try {
    if (args.options.count("levels")) {
      if (args.options.count("episodes-per-object"))
        throw UsageError("give --levels or --episodes-per-object, not both", kSurveyUsage);
      run.levels = mb::parseLevels(args.options.at("levels"));
    } else {
      const uint64_t n = parseSeed(valueOr(args, "episodes-per-object", "5"), kSurveyUsage, "--episodes-per-object");
      if (n == 0 || n > 100000) throw UsageError("--episodes-per-object must be 1 to 100000", kSurveyUsage);
      for (uint64_t level = 0; level < n; ++level) run.levels.push_back(level);
    }
  } catch (const mb::InvalidArgument& e) {
    throw UsageError(e.what(), kSurveyUsage);
  }
  run.seed = parseSeed(valueOr(args, "seed", "0"), kSurveyUsage);
  const std::string out_dir = valueOr(args, "out", "survey");
  run.progress = !args.options.count("no-progress") && isatty(STDERR_FILENO);

  mb::PluginRegistry registry;
  loadPlugins(registry);
  run.registry = &registry;
  run.sources = getConfigSources(args);
  // The policy's controller: probed on the first folder's objects.
  mb::ConfigSources first = run.sources;
  first.overrides.push_back("task.partnet_dir=" + dirs.front());
  run.policy = chooseSurveyPolicy(registry, args, run.task, first);
  Arguments with_policy = args;
  with_policy.options["policy"] = run.policy.name;
  applyPolicyController(registry, run.policy.name, with_policy, run.sources, kSurveyUsage);
  std::cout << "survey of " << run.task << " with policy " << run.policy.name << ": " << dirs.size()
            << " folder(s), levels " << run.levels.size() << " per object, seed " << run.seed << "\n";

  const StopSignals stop_signals;
  SurveyReport report(run.task, run.policy.name, run.levels, run.seed);
  for (const std::string& dir : dirs) {
    if (StopSignals::isRequested()) break;
    surveyCategory(run, dir, report);
  }
  report.print(std::cout);
  for (const std::string& path : report.write(out_dir)) std::cout << "wrote " << path << "\n";
  if (StopSignals::isRequested()) {
    std::cerr << "manibench: survey stopped: partial results written\n";
    return 130;
  }
  return 0;
}

}  // namespace manibench::cli
