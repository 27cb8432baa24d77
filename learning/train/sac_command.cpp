#include "sac_command.hpp"

#include <manibench/learning/sac_trainer.hpp>

#include <manibench/plugin_registry.hpp>

#include <yaml-cpp/yaml.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli.hpp"
#include "programs.hpp"
#include "sac_population.hpp"

namespace manibench::learning::programs {

namespace fs = std::filesystem;
namespace mb = manibench;
using mb::cli::UsageError;

namespace {

const char* kSacUsage = R"(usage: manibench train sac TASK_OR_FIXED_ID --out DIR [options]
       manibench train sac --resume DIR [--steps N]

Trains a SAC agent (automatic entropy tuning, tanh-squashed Gaussian actor,
twin Q-networks) online in the state mode on the task's dense reward, with
environment workers stepping in parallel while the learner updates
(supplement C.2, docs/learning.md). The defaults are Table 6's. Evaluate
the agent with  manibench eval ID --policy torch_policy --policy-config DIR/policy.yaml

Environment:
  --split S               train (default) or test: a task's objects
  --objects ID,...        only these objects (episodes go round them in turn)
  --config FILE  --set KEY=VALUE  --controller NAME   as for manibench run
  --early-done            end an episode at its success (C.2 trains without;
                          --no-early-done, the default)
Training:
  --steps N               env steps in all (default 2000000, C.2)
  --workers W             environment processes (default 4, C.2)
  --replay-size N         default 1000000 (Table 6)
  --batch-size N          default 1024 (Table 6)
  --lr X                  Adam's rate, default 3e-4 (Table 6)
  --gamma X               discount, default 0.95 (Table 6)
  --tau X                 target smoothing, default 0.005 (Table 6)
  --target-update-every N gradient steps between target updates (default 1)
  --updates-per-step X    gradient steps per env step (default 1, Table 6)
  --hidden N,N,...        hidden layers of every network (default 256,256,256)
  --init-temperature X    the entropy temperature's start (default 1, ManiSkill-Learn's
                          log alpha = 0; with --fixed-temperature 0.2, its alpha)
  --fixed-temperature     do not tune it
  --log-temperature-gradient  tune it by the gradient with respect to log alpha
                          (manibench before 2026-11-28) instead of alpha (ManiSkill-Learn)
  --target-entropy X      per action dimension (default -1: -|A| in all)
  --random-steps N        uniform random actions first (default 4000)
  --learning-starts N     transitions before the first gradient step (default 1024)
  --seed S                networks, exploration, episodes' seeds (default 0)
  --threads N             libtorch and OpenBLAS threads (default 1)
  --worker-timeout S      kill and replace a worker silent S seconds on one
                          request, dropping its episode (default 120; 0: none)
  --device cpu|cuda
Output:
  --out DIR               the training's directory (must not hold one)
  --checkpoint-every N    env steps between checkpoints (default 50000)
  --log-every N           env steps per log.csv row (default 2000)
  --eval-every N          evaluate the deterministic actor every N env steps
                          and at the end with `manibench eval` (DIR/eval.csv)
  --eval-episodes N       per object (default 10)
  --eval-seed S           the evaluation's base seed (default 1000)
  --no-progress           no progress line (shown only on a terminal)
  --resume DIR            continue the training in DIR from its newest checkpoint
)";

const char* kPopulationUsage = R"(usage: manibench train sac-population TASK --out DIR [options]

Supplement C.2's demonstration agents: one SAC agent per object of the
split, each trained from scratch on its fixed-object id by its own
`manibench train sac` (own directory, own seed from --seed and the object
id), evaluated, and retrained with the next seed while below --threshold.
Run the same command again to continue a stopped population.
  --split S               train (default) or test
  --objects ID,...        only these objects
  --seed S                base seed (default 0)
  --threshold X           success rate an agent needs (default 0.3, C.2)
  --max-attempts N        trainings per object at most (default 3)
  --eval-episodes N       evaluation episodes per agent (default 20)
  --eval-seed S           the evaluation's base seed (default 1000)
  --demos N               then N successful episodes per accepted object,
                          each from its own agent: DIR/demos/ID.h5
  --shard I/N             only the objects at positions I-1 modulo N (a job
                          array's task; the summary is population-I-of-N.yaml).
                          Under mpirun each rank takes its objects this way
                          (docs/distributed.md); DIR must be shared
Every `manibench train sac` option but --out, --objects, --split, --seed
and --resume goes to each object's training (--steps, --workers, ...).
)";

const std::vector<std::string> kValued = [] {
  std::vector<std::string> valued = listRunOptions();
  valued.insert(valued.end(), {"split", "objects", "config", "set", "controller", "steps", "workers", "replay-size",
                               "batch-size", "lr", "gamma", "tau", "target-update-every", "updates-per-step", "hidden",
                               "init-temperature", "target-entropy", "random-steps", "learning-starts",
                               "worker-timeout", "resume"});
  return valued;
}();
const std::vector<std::string> kFlags = {"early-done", "no-early-done", "fixed-temperature",
                                         "log-temperature-gradient", "no-progress"};

SacOptions parseSacOptions(const mb::cli::Arguments& args, int argc, char** argv, const char* usage) {
  auto has = [&](const std::string& key) { return args.options.count(key) > 0; };
  auto value = [&](const std::string& key) { return args.options.at(key); };
  auto integer = [&](const std::string& key, int64_t minimum) {
    return parseInteger(value(key), "--" + key, minimum, usage);
  };
  auto number = [&](const std::string& key) { return parseNumber(value(key), "--" + key, usage); };
  SacOptions o;
  parseRunOptions(args, argc, argv, o, usage);
  o.split = mb::cli::parseSplit(args, "train", usage);
  if (has("objects")) o.objects = splitList(value("objects"));
  const mb::ConfigSources sources = mb::cli::getConfigSources(args);
  for (const std::string& f : sources.files) o.config_files.push_back(fs::absolute(f).string());
  o.config_sets = sources.overrides;
  if (has("early-done") && has("no-early-done")) throw UsageError("--early-done or --no-early-done, not both", usage);
  o.early_done = has("early-done");
  if (has("steps")) o.steps = integer("steps", 1);
  if (has("workers")) o.workers = unsigned(integer("workers", 1));
  if (has("replay-size")) o.replay_size = integer("replay-size", 1);
  if (has("batch-size")) o.algorithm.batch_size = integer("batch-size", 1);
  if (has("lr")) o.algorithm.lr = number("lr");
  if (has("gamma")) o.algorithm.gamma = number("gamma");
  if (has("tau")) o.algorithm.tau = number("tau");
  if (has("target-update-every")) o.algorithm.target_update_every = integer("target-update-every", 1);
  if (has("updates-per-step")) o.updates_per_step = number("updates-per-step");
  if (has("hidden")) o.network.mlp_hidden = parseLayers(value("hidden"), "--hidden", usage);
  o.algorithm.tune_temperature = !has("fixed-temperature");
  if (!o.algorithm.tune_temperature) o.algorithm.init_temperature = 0.2;
  if (has("init-temperature")) o.algorithm.init_temperature = number("init-temperature");
  o.algorithm.temperature_gradient_log = has("log-temperature-gradient");
  if (has("target-entropy")) {
    try {
      o.algorithm.target_entropy_per_dim = std::stod(value("target-entropy"));
    } catch (const std::exception&) {
      throw UsageError("--target-entropy needs a number, got '" + value("target-entropy") + "'", usage);
    }
  }
  if (has("random-steps")) o.random_steps = integer("random-steps", 0);
  if (has("learning-starts")) o.learning_starts = integer("learning-starts", 0);
  if (has("worker-timeout")) o.worker_timeout = number("worker-timeout");
  return o;
}

void drawSacProgress(const SacProgress& p) {
  std::ostringstream line;
  line << "\r" << mb::cli::formatProgressBar(std::size_t(p.env_steps), std::size_t(p.total), 24) << " steps, "
       << std::fixed << std::setprecision(1)
       << p.env_steps_per_second << " steps/s, " << p.updates_per_second << " updates/s, return "
       << std::setprecision(2) << p.mean_return << ", success " << std::setprecision(0) << 100 * p.success_rate
       << "% (" << p.episodes << " episodes)";
  if (p.env_steps_per_second > 0 && p.total > p.env_steps)
    line << ", ~" << mb::cli::formatDuration(double(p.total - p.env_steps) / p.env_steps_per_second) << " left";
  line << "   ";
  std::cerr << line.str() << std::flush;
}

// The user's hooks: messages on stderr, the progress line on a terminal,
// Ctrl-C stops at the next round with a checkpoint.
SacHooks makeHooks(bool progress) {
  SacHooks hooks;
  hooks.on_message = [progress](const std::string& line) {
    if (progress) std::cerr << "\r\033[K";
    std::cerr << line << "\n";
  };
  hooks.should_stop = [] { return mb::cli::StopSignals::isRequested(); };
  // `manibench eval` in its own process, on the training's environment.
  hooks.evaluate = [](const SacOptions& o, const std::string& policy_config, const std::string& out_dir) {
    std::vector<std::string> extra = {"--split", o.split, "--episodes-per-object", std::to_string(o.eval_episodes),
                                      "--seed", std::to_string(o.eval_seed)};
    if (!o.objects.empty()) {
      std::string ids;
      for (const std::string& id : o.objects) ids += (ids.empty() ? "" : ",") + id;
      extra.insert(extra.end(), {"--objects", ids});
    }
    for (const std::string& file : o.config_files) extra.insert(extra.end(), {"--config", file});
    for (const std::string& set : o.config_sets) extra.insert(extra.end(), {"--set", set});
    return runPolicyEvaluation(o.environment_id, policy_config, extra, out_dir);
  };
  auto last_draw = std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now() -
                                                                         std::chrono::seconds(1));
  hooks.on_progress = [progress, last_draw](const SacProgress& p) {
    const auto now = std::chrono::steady_clock::now();
    if (!progress || (now - *last_draw < std::chrono::milliseconds(250) && p.env_steps < p.total)) return;
    *last_draw = now;
    drawSacProgress(p);
  };
  return hooks;
}

int runSacPopulation(int argc, char** argv) {
  std::vector<std::string> valued = kValued;
  valued.insert(valued.end(), {"threshold", "max-attempts", "eval-episodes", "eval-seed", "demos", "shard"});
  const mb::cli::Arguments args = mb::cli::parseArguments(argc, argv, 3, valued, kFlags, kPopulationUsage);
  if (args.help) {
    std::cout << kPopulationUsage;
    return 0;
  }
  auto has = [&](const std::string& key) { return args.options.count(key) > 0; };
  auto integer = [&](const std::string& key, int64_t minimum) {
    return parseInteger(args.options.at(key), "--" + key, minimum, kPopulationUsage);
  };
  if (args.positional.size() != 1) throw UsageError("name one task", kPopulationUsage);
  if (!has("out")) throw UsageError("no --out DIR", kPopulationUsage);
  if (has("resume")) throw UsageError("run the same command again to continue a population", kPopulationUsage);
  parseSacOptions(args, argc, argv, kPopulationUsage);  // the training's options, checked once here
  PopulationOptions o;
  o.task = args.positional.front();
  o.out_dir = args.options.at("out");
  o.split = mb::cli::parseSplit(args, "train", kPopulationUsage);
  if (has("objects")) o.objects = splitList(args.options.at("objects"));
  if (has("seed")) o.seed = uint64_t(integer("seed", 0));
  if (has("threshold")) o.threshold = parseNumber(args.options.at("threshold"), "--threshold", kPopulationUsage);
  if (has("max-attempts")) o.max_attempts = unsigned(integer("max-attempts", 1));
  if (has("eval-episodes")) o.eval_episodes = unsigned(integer("eval-episodes", 1));
  if (has("eval-seed")) o.eval_seed = uint64_t(integer("eval-seed", 0));
  if (has("demos")) o.demos_per_object = unsigned(integer("demos", 1));
  placeOnShard(has("shard") ? args.options.at("shard") : "", o.shard, o.shards);
  const std::vector<std::string> own = {"out", "objects", "split", "seed", "resume", "no-progress"};
  for (const auto& [key, value] : args.options)
    if (std::find(kValued.begin(), kValued.end(), key) != kValued.end() &&
        std::find(own.begin(), own.end(), key) == own.end())
      o.sac_args.insert(o.sac_args.end(), {"--" + key, value});
  for (const auto& [key, values] : args.repeated)
    for (const std::string& value : values) o.sac_args.insert(o.sac_args.end(), {"--" + key, value});
  for (const std::string& flag : kFlags)
    if (has(flag) && flag != "no-progress") o.sac_args.push_back("--" + flag);
  mb::cli::StopSignals stop;
  return runPopulation(o);
}

bool holdsSacTraining(const std::string& dir) {
  try {
    const YAML::Node node = YAML::LoadFile((fs::path(dir) / "train.yaml").string());
    return node["algorithm"] && node["algorithm"]["name"].as<std::string>("") == "sac";
  } catch (const std::exception&) {
    return false;
  }
}

int runSac(int argc, char** argv) {
  const mb::cli::Arguments args = mb::cli::parseArguments(argc, argv, 2, kValued, kFlags, kSacUsage);
  if (args.help) {
    std::cout << kSacUsage;
    return 0;
  }
  std::vector<std::string> positional = args.positional;
  if (!positional.empty() && positional.front() == "sac") positional.erase(positional.begin());
  const bool resume = args.options.count("resume") > 0;
  if (resume ? !positional.empty() : positional.size() != 1)
    throw UsageError(resume ? "--resume DIR takes the options of DIR/train.yaml; only --steps may change"
                            : "name one task or fixed-object id",
                     kSacUsage);
  mb::PluginRegistry registry;
  registry.loadSearchPath();
  mb::cli::StopSignals stop;
  const bool progress = !args.options.count("no-progress") && isatty(STDERR_FILENO);
  const SacHooks hooks = makeHooks(progress);
  SacResult result;
  if (resume) {
    const int64_t steps =
        args.options.count("steps") ? parseInteger(args.options.at("steps"), "--steps", 1, kSacUsage) : 0;
    result = resumeSac(registry, args.options.at("resume"), steps, hooks);
  } else {
    SacOptions o = parseSacOptions(args, argc, argv, kSacUsage);
    if (o.out_dir.empty()) throw UsageError("no --out DIR", kSacUsage);
    o.environment_id = positional.front();
    result = trainSac(registry, o, hooks);
  }
  if (progress) std::cerr << "\n";
  std::cerr << (result.interrupted ? "stopped" : "done") << " at " << result.env_steps << " env steps ("
            << result.updates << " gradient steps, " << result.episodes << " episodes) in "
            << mb::cli::formatDuration(result.seconds) << "; newest checkpoint " << result.checkpoint << "\n";
  return result.interrupted ? 130 : 0;
}

}  // namespace

bool isSacCommand(int argc, char** argv) {
  if (argc > 2 && (std::string(argv[2]) == "sac" || std::string(argv[2]) == "sac-population")) return true;
  for (int i = 2; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--resume") return holdsSacTraining(argv[i + 1]);
  return false;
}

int runSacCommand(int argc, char** argv) {
  if (argc > 2 && std::string(argv[2]) == "sac-population") return runSacPopulation(argc, argv);
  return runSac(argc, argv);
}

}  // namespace manibench::learning::programs
