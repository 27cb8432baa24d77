// manibench-train: `manibench train` (the host program runs this one,
// found beside it, as git runs git-<command>: the host never loads
// libtorch). Learns a policy from demonstration files (docs/learning.md).
#include <manibench/learning/compute.hpp>
#include <manibench/learning/trainer.hpp>

#include <manibench/plugin_registry.hpp>

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli.hpp"
#include "programs.hpp"
#include "sac_command.hpp"

namespace mb = manibench;
namespace ml = manibench::learning;
namespace fs = std::filesystem;
using mb::cli::UsageError;

namespace {

const char* kUsage = R"(usage: manibench train bc|bcq|td3bc --demos FILE.h5 [--demos FILE.h5 ...] --out DIR [options]
       manibench train --resume DIR [--iterations N]
       manibench train sac ... (manibench train sac --help)

Learns a policy from demonstrations (supplement D.2-D.3, docs/learning.md):
Behavior Cloning, BCQ or TD3+BC, with an MLP on state demonstrations or
PointNet / PointNet + Transformer on point-cloud ones (`manibench demos
convert F.h5 --obs pointcloud`). Writes DIR/train.yaml, DIR/log.csv (losses),
DIR/eval.csv (success rates, with --eval-every), DIR/checkpoints/iter_N.pt and
DIR/policy.yaml, which evaluates the newest checkpoint:
  manibench eval TASK --policy torch_policy --policy-config DIR/policy.yaml
Ctrl-C writes a checkpoint and stops; --resume DIR continues exactly.

Data:
  --demos FILE            a demonstration file; repeatable, or comma-separated
  --objects ID,ID,...     only these objects' trajectories
  --per-object N          at most N trajectories per object (the first ones)
  --cache-gb G            tensors kept in memory at most (default 8); a larger
                          set streams in shuffled windows
  --executed-actions      learn the executed actions of files made with
                          `demos generate --action-noise`, not the policy's own
  --normalize-state       normalize each state feature by the demonstrations'
                          mean and standard deviation (stored in the network)
Network:
  --net NAME              mlp (state), pointnet or pn_transformer (pointcloud);
                          default mlp for state, pn_transformer for pointcloud
  --history N             the state input stacks the last N observations' state
                          (or agent) vectors (default 1: the current one)
  --action-history N      the state input includes the last N actions (default 0)
  --step-input            the state input includes the episode's step (t / 100)
  --robot-frame           the state input also holds its world-frame positions,
                          poses and velocities in the robot base's frame
  --hidden N,N,...        mlp hidden layers (default 256,256,256)
  --point-layers N,N      pointnet per-point layers (default 256,512)
  --width N               pn_transformer width (default 256; bcq, td3bc: 192)
  --layers N              pn_transformer blocks (default 6; bcq, td3bc: 2)
  --ff N                  pn_transformer feed-forward (default 1024; bcq, td3bc: 768)
  --heads N               attention heads (default 4, of 32 each)
  --dropout P             pn_transformer dropout (default 0.1)
  --transformer-masks     pn_transformer's PointNets also see the mask channels
                          (ManiSkill-Learn's do not)
Optimization:
  --iterations N          gradient steps (default 10000)
  --batch-size N          default 128 (bc), 64 (bcq: Table 7; td3bc)
  --lr X                  Adam's rate: default 3e-4 (bc on point clouds), 1e-3 (bc on
                          states), 5e-4 (bcq, td3bc)
  --weight-decay X        ManiSkill-Learn's: 5e-6 on point clouds; state: 5e-6 (bcq), 0 (bc, td3bc)
  --no-tanh               bc: the network's output as the action (default tanh of it)
  --seed S                initialization, batches, noise (default 0)
  --threads N             libtorch and OpenBLAS threads (default 1)
  --device cpu|cuda       cuda needs a libtorch built with it (default cpu)
  --prefetch              gather the next batch while this one trains (always on cuda)
Offline RL (bcq, td3bc; Tables 7 and 8):
  --gamma X  --tau X      discount (0.95), target smoothing (0.005)
  --alpha X               td3bc's BC weight alpha (0.02; 0 is BC)
  --action-noise X  --noise-clip X  --policy-delay N     td3bc (0.2, 0.5, 2)
  --phi X  --lambda X     bcq's perturbation limit (0) and double-Q weight (0.75)
  --train-samples N  --eval-samples N                    bcq (10, 100)
Output and evaluation:
  --out DIR               the training's directory (must not hold one)
  --checkpoint-every N    iterations between checkpoints (default 1000)
  --log-every N           iterations per log.csv row (default 100)
  --eval-every N          evaluate the policy every N iterations (and at the
                          end) with `manibench eval` in worker processes
  --eval-task ID          task or fixed-object id (default: the demos' env id)
  --eval-split S          train (default) or test
  --eval-objects ID,...   only these objects
  --eval-episodes N       episodes per object (default 10)
  --eval-workers N        evaluation workers (default 1)
  --eval-seed S           the evaluation's base seed (default 1000: not the
                          demonstrations' own episodes, made with seed 0)
  --eval-device cpu|cuda  what DIR/policy.yaml runs the checkpoints on (default
                          cpu, whatever --device trained them on)
  --no-progress           no progress line (shown only on a terminal)
  --resume DIR            continue the training in DIR from its newest checkpoint
)";

using ml::programs::splitList;

int64_t parseInteger(const std::string& text, const std::string& option, int64_t minimum) {
  return ml::programs::parseInteger(text, option, minimum, kUsage);
}
double parseNumber(const std::string& text, const std::string& option) {
  return ml::programs::parseNumber(text, option, kUsage);
}
std::vector<int64_t> parseLayers(const std::string& text, const std::string& option) {
  return ml::programs::parseLayers(text, option, kUsage);
}

// `manibench eval` of the newest checkpoint.
ml::EvaluationOutcome runEvaluation(const ml::EvaluationRequest& r) {
  const ml::TrainOptions& o = *r.options;
  std::vector<std::string> args = {"--config", r.environment_config, "--split", o.eval_split,
                                   "--episodes-per-object", std::to_string(o.eval_episodes),
                                   "--workers", std::to_string(o.eval_workers), "--seed",
                                   std::to_string(o.eval_seed)};
  if (!o.eval_objects.empty()) {
    std::string ids;
    for (const std::string& id : o.eval_objects) ids += (ids.empty() ? "" : ",") + id;
    args.push_back("--objects");
    args.push_back(ids);
  }
  try {
    return ml::programs::runPolicyEvaluation(o.eval_task.empty() ? r.environment_id : o.eval_task,
                                             r.policy_config, args, r.out_dir);
  } catch (const ml::LearningError& e) {
    throw ml::LearningError("the evaluation at iteration " + std::to_string(r.iteration) + ": " + e.what());
  }
}

void drawProgress(const ml::TrainProgress& p) {
  std::ostringstream line;
  line << "\r" << mb::cli::formatProgressBar(std::size_t(p.iteration), std::size_t(p.total)) << " it, "
       << std::fixed << std::setprecision(1)
       << p.iterations_per_second << " it/s";
  line << std::defaultfloat << std::setprecision(4);
  for (std::size_t i = 0; i < p.losses.size() && i < 2; ++i) line << ", " << p.loss_names[i] << " " << p.losses[i];
  if (p.iterations_per_second > 0 && p.total > p.iteration)
    line << ", ~" << mb::cli::formatDuration(double(p.total - p.iteration) / p.iterations_per_second) << " left";
  line << "   ";
  std::cerr << line.str() << std::flush;
}

// The options of a new training from the command line (usage errors name
// the option).
ml::TrainOptions parseTrainOptions(const mb::cli::Arguments& args, int argc, char** argv) {
  auto has = [&](const std::string& key) { return args.options.count(key) > 0; };
  auto value = [&](const std::string& key) { return args.options.at(key); };
  if (args.positional.size() != 1) throw UsageError("name one algorithm: bc, bcq or td3bc", kUsage);
  ml::TrainOptions o;
  o.algorithm = ml::AlgorithmOptions::makeDefaults(args.positional[0]);
  o.network = ml::NetOptions::makeDefaults(args.positional[0]);
  if (!args.options.count("out")) throw UsageError("no --out DIR", kUsage);
  ml::programs::parseRunOptions(args, argc, argv, o, kUsage);
  if (!args.repeated.count("demos")) throw UsageError("no --demos FILE.h5", kUsage);
  for (const std::string& d : args.repeated.at("demos"))
    for (const std::string& path : splitList(d)) o.data.paths.push_back(fs::absolute(path).string());
  if (has("objects")) o.data.objects = splitList(value("objects"));
  if (has("per-object")) o.data.per_object = uint32_t(parseInteger(value("per-object"), "--per-object", 1));
  if (has("cache-gb"))
    o.data.cache_bytes = uint64_t(parseNumber(value("cache-gb"), "--cache-gb") * double(uint64_t(1) << 30));
  o.normalize_state = has("normalize-state");
  o.prefetch = has("prefetch");
  o.data.executed_actions = has("executed-actions");
  if (has("net")) o.network.kind = ml::parseNetKind(value("net"));
  o.pick_network = !has("net");
  if (has("history")) o.network.history = parseInteger(value("history"), "--history", 1);
  if (has("action-history")) o.network.action_history = parseInteger(value("action-history"), "--action-history", 0);
  o.network.step_input = has("step-input");
  o.robot_frame = has("robot-frame");
  if (has("hidden")) o.network.mlp_hidden = parseLayers(value("hidden"), "--hidden");
  if (has("point-layers")) o.network.point_layers = parseLayers(value("point-layers"), "--point-layers");
  if (has("width")) o.network.width = parseInteger(value("width"), "--width", 1);
  if (has("layers")) o.network.layers = parseInteger(value("layers"), "--layers", 0);
  if (has("heads")) o.network.heads = parseInteger(value("heads"), "--heads", 1);
  if (has("ff")) o.network.ff = parseInteger(value("ff"), "--ff", 1);
  o.network.transformer_masks = has("transformer-masks");
  if (has("dropout")) o.network.dropout = parseNumber(value("dropout"), "--dropout");
  if (has("iterations")) o.iterations = parseInteger(value("iterations"), "--iterations", 1);
  if (has("batch-size")) o.algorithm.batch_size = parseInteger(value("batch-size"), "--batch-size", 1);
  if (has("lr")) o.algorithm.lr = parseNumber(value("lr"), "--lr");
  if (has("weight-decay")) o.algorithm.weight_decay = parseNumber(value("weight-decay"), "--weight-decay");
  o.pick_weight_decay = !has("weight-decay");
  o.pick_lr = !has("lr");
  o.algorithm.bc_tanh = !has("no-tanh");
  if (has("gamma")) o.algorithm.gamma = parseNumber(value("gamma"), "--gamma");
  if (has("tau")) o.algorithm.tau = parseNumber(value("tau"), "--tau");
  if (has("alpha")) o.algorithm.alpha = parseNumber(value("alpha"), "--alpha");
  if (has("action-noise")) o.algorithm.action_noise = parseNumber(value("action-noise"), "--action-noise");
  if (has("noise-clip")) o.algorithm.noise_clip = parseNumber(value("noise-clip"), "--noise-clip");
  if (has("policy-delay")) o.algorithm.policy_delay = parseInteger(value("policy-delay"), "--policy-delay", 1);
  if (has("phi")) o.algorithm.phi = parseNumber(value("phi"), "--phi");
  if (has("lambda")) o.algorithm.lambda = parseNumber(value("lambda"), "--lambda");
  if (has("train-samples")) o.algorithm.train_samples = parseInteger(value("train-samples"), "--train-samples", 1);
  if (has("eval-samples")) o.algorithm.eval_samples = parseInteger(value("eval-samples"), "--eval-samples", 1);
  if (has("eval-task")) o.eval_task = value("eval-task");
  if (has("eval-split")) o.eval_split = value("eval-split");
  if (o.eval_split != "train" && o.eval_split != "test")
    throw UsageError("--eval-split takes train or test", kUsage);
  if (has("eval-objects")) o.eval_objects = splitList(value("eval-objects"));
  if (has("eval-device")) o.eval_device = ml::parseDevice(value("eval-device")).str();
  if (has("eval-workers")) o.eval_workers = unsigned(parseInteger(value("eval-workers"), "--eval-workers", 1));
  return o;
}

int run(int argc, char** argv) {
  if (ml::programs::isSacCommand(argc, argv)) return ml::programs::runSacCommand(argc, argv);
  std::vector<std::string> valued = ml::programs::listRunOptions();
  valued.insert(valued.end(), {"demos", "objects", "per-object", "cache-gb", "net", "history", "action-history", "hidden",
                               "point-layers", "width", "layers", "heads", "ff", "dropout", "iterations", "batch-size",
                               "lr", "weight-decay", "gamma", "tau", "alpha", "action-noise", "noise-clip",
                               "policy-delay", "phi", "lambda", "train-samples", "eval-samples", "eval-task",
                               "eval-split", "eval-objects", "eval-workers", "eval-device", "resume"});
  const mb::cli::Arguments args =
      mb::cli::parseArguments(argc, argv, 2, valued, {"normalize-state", "step-input", "robot-frame", "executed-actions", "no-progress", "no-tanh", "transformer-masks", "prefetch"}, kUsage, {"demos"});
  if (args.help) {
    std::cout << kUsage;
    return 0;
  }
  auto has = [&](const std::string& key) { return args.options.count(key) > 0; };
  auto value = [&](const std::string& key) { return args.options.at(key); };

  mb::PluginRegistry registry;
  registry.loadSearchPath();
  mb::cli::StopSignals stop;
  const bool progress = !has("no-progress") && isatty(STDERR_FILENO);
  ml::TrainHooks hooks;
  hooks.on_message = [&](const std::string& line) {
    if (progress) std::cerr << "\r\033[K";
    std::cerr << line << "\n";
  };
  hooks.should_stop = [] { return mb::cli::StopSignals::isRequested(); };
  auto last_draw = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  hooks.on_progress = [&](const ml::TrainProgress& p) {
    const auto now = std::chrono::steady_clock::now();
    if (!progress || (now - last_draw < std::chrono::milliseconds(250) && p.iteration < p.total)) return;
    last_draw = now;
    drawProgress(p);
  };
  hooks.evaluate = runEvaluation;

  ml::TrainResult result;
  if (has("resume")) {
    if (!args.positional.empty() || has("demos") || has("out"))
      throw UsageError("--resume DIR takes the options of DIR/train.yaml; only --iterations may change", kUsage);
    const std::string dir = value("resume");
    const int64_t iterations = has("iterations") ? parseInteger(value("iterations"), "--iterations", 1) : 0;
    result = ml::resumeTraining(registry, dir, iterations, hooks);
  } else {
    const ml::TrainOptions o = parseTrainOptions(args, argc, argv);
    result = ml::train(registry, o, hooks);
  }
  if (progress) std::cerr << "\n";
  std::cerr << (result.interrupted ? "stopped" : "done") << " at iteration " << result.iteration << " in "
            << mb::cli::formatDuration(result.seconds) << "; newest checkpoint " << result.checkpoint << "\n";
  return result.interrupted ? 130 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  return mb::cli::runMain("manibench train", [&] { return run(argc, argv); }, /*break_line_first=*/true);
}
