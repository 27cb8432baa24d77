#include "programs.hpp"

#include "cli.hpp"

#include <manibench/evaluation.hpp>
#include <manibench/worker_pool.hpp>

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

extern char** environ;

namespace manibench::learning::programs {

namespace fs = std::filesystem;
using manibench::cli::UsageError;

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

const std::vector<std::string>& listRunOptions() {
  static const std::vector<std::string> names = {"out",       "seed",       "threads",       "device",   "checkpoint-every",
                                                 "log-every", "eval-every", "eval-episodes", "eval-seed"};
  return names;
}

void parseRunOptions(const cli::Arguments& args, int argc, char** argv, RunOptions& o, const char* usage) {
  auto has = [&](const std::string& key) { return args.options.count(key) > 0; };
  auto integer = [&](const std::string& key, int64_t minimum) {
    return parseInteger(args.options.at(key), "--" + key, minimum, usage);
  };
  if (has("out")) o.out_dir = args.options.at("out");
  if (has("seed")) o.seed = uint64_t(integer("seed", 0));
  if (has("threads")) o.threads = int(integer("threads", 1));
  if (has("device")) o.device = args.options.at("device");
  if (has("checkpoint-every")) o.checkpoint_every = integer("checkpoint-every", 1);
  if (has("log-every")) o.log_every = integer("log-every", 1);
  if (has("eval-every")) o.eval_every = integer("eval-every", 0);
  if (has("eval-episodes")) o.eval_episodes = uint32_t(integer("eval-episodes", 1));
  if (has("eval-seed")) o.eval_seed = uint64_t(integer("eval-seed", 0));
  o.command = "manibench train";
  for (int i = 2; i < argc; ++i) o.command += std::string(" ") + argv[i];
}

int64_t parseInteger(const std::string& text, const std::string& option, int64_t minimum, const char* usage) {
  try {
    std::size_t used = 0;
    const long long value = std::stoll(text, &used);
    if (used == text.size() && value >= minimum) return value;
  } catch (const std::exception&) {
  }
  throw UsageError(option + " needs an integer of at least " + std::to_string(minimum) + ", got '" + text + "'",
                   usage);
}

double parseNumber(const std::string& text, const std::string& option, const char* usage) {
  try {
    std::size_t used = 0;
    const double value = std::stod(text, &used);
    if (used == text.size() && std::isfinite(value) && value >= 0) return value;
  } catch (const std::exception&) {
  }
  throw UsageError(option + " needs a non-negative number, got '" + text + "'", usage);
}

std::vector<int64_t> parseLayers(const std::string& text, const std::string& option, const char* usage) {
  std::vector<int64_t> out;
  for (const std::string& item : splitList(text)) out.push_back(parseInteger(item, option, 1, usage));
  if (out.empty()) throw UsageError(option + " needs at least one layer size", usage);
  return out;
}

namespace {

std::string getProgramDir() {
  char path[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n <= 0) return ".";
  path[n] = 0;
  return fs::path(path).parent_path().string();
}

}  // namespace

int runManibench(const std::vector<std::string>& arguments, const std::string& log_path) {
  const std::string program = getProgramDir() + "/manibench";
  std::vector<std::string> args = arguments;
  args.insert(args.begin(), program);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw LearningError("cannot start " + program + ": " + std::strerror(error));
  const int status = waitForChild(pid);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

EvaluationOutcome runPolicyEvaluation(const std::string& environment, const std::string& policy_config,
                                      const std::vector<std::string>& extra, const std::string& out_dir) {
  // Trusted: the policy is this training's own checkpoint run by manibench's
  // torch_policy plugin, not a submission; the sandbox's default 60 s of CPU
  // per episode is sized for submissions. BCQ with PointNet + Transformer
  // chooses each action among 100 samples through the decoder and a critic
  // (Table 7): about 1.8 s of CPU per step on the 2-core VM, so sandboxed
  // every episode was killed at step 33 and the training logged 0 success
  // for a policy that had not run.
  std::vector<std::string> args = {"eval", environment, "--policy", "torch_policy", "--policy-config", policy_config,
                                   "--trusted-policy"};
  args.insert(args.end(), extra.begin(), extra.end());
  args.insert(args.end(), {"--no-progress", "--out", out_dir});
  // Each evaluation has a folder of its own (its checkpoint's), so a
  // journal there is this evaluation's, stopped before it finished: what it
  // finished is kept.
  if (fs::exists(fs::path(out_dir) / kJournalFileName)) args.push_back("--resume");
  fs::create_directories(out_dir);
  const std::string log_path = out_dir + "/eval.log";
  const bool resumed = args.back() == "--resume";
  const int code = runManibench(args, log_path);
  // 130: stopped (a Ctrl-C reaches the whole process group, the evaluation
  // too), its partial results written: the training stops as interrupted.
  if (code == 130 || (code != 0 && manibench::cli::StopSignals::isRequested())) {
    EvaluationOutcome stopped;
    stopped.interrupted = true;
    return stopped;
  }
  if (code != 0)
    throw LearningError("the evaluation of " + policy_config + (resumed ? " (resumed)" : "") + " failed (" +
                        log_path + " says why)");
  std::ifstream in(out_dir + "/summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  EvaluationOutcome outcome;
  outcome.episodes = summary["overall"]["episodes"].get<uint32_t>();
  outcome.successes = summary["overall"]["successes"].get<uint32_t>();
  outcome.failures = summary["overall"]["failures"].get<uint32_t>();
  outcome.success_rate = summary["overall"]["success_rate"].get<double>();
  return outcome;
}

}  // namespace manibench::learning::programs
