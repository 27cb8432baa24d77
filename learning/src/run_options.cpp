#include <manibench/learning/run_options.hpp>

#include <yaml-cpp/yaml.h>

namespace manibench::learning {

RunOptions::RunOptions(const std::string& algorithm_name, int64_t checkpoint_every_default, int64_t log_every_default)
    : algorithm(AlgorithmOptions::makeDefaults(algorithm_name)), network(NetOptions::makeDefaults(algorithm_name)),
      checkpoint_every(checkpoint_every_default), log_every(log_every_default) {}

void RunOptions::checkRun() const {
  if (out_dir.empty()) throw LearningError("no output directory (--out DIR)");
  if (checkpoint_every <= 0 || log_every <= 0)
    throw LearningError("--checkpoint-every and --log-every must be positive");
  if (threads < 1) throw LearningError("--threads must be at least 1");
  if (eval_every < 0 || (eval_every > 0 && eval_episodes == 0))
    throw LearningError("--eval-every must be at least 0 and --eval-episodes at least 1");
}

void RunOptions::writeRun(YAML::Node& node) const {
  node["out_dir"] = out_dir;
  YAML::Node a, n, e;
  algorithm.writeYaml(a);
  network.writeYaml(n);
  node["algorithm"] = a;
  node["network"] = n;
  node["seed"] = seed;
  node["threads"] = threads;
  node["device"] = device;
  node["checkpoint_every"] = checkpoint_every;
  node["log_every"] = log_every;
  e["every"] = eval_every;
  e["episodes"] = eval_episodes;
  e["seed"] = eval_seed;
  node["evaluation"] = e;
  node["command"] = command;
}

void RunOptions::readRun(const YAML::Node& node) {
  out_dir = node["out_dir"].as<std::string>();
  algorithm = AlgorithmOptions::readYaml(node["algorithm"]);
  network = NetOptions::readYaml(node["network"]);
  seed = node["seed"].as<uint64_t>();
  threads = node["threads"].as<int>();
  device = node["device"].as<std::string>();
  checkpoint_every = node["checkpoint_every"].as<int64_t>();
  log_every = node["log_every"].as<int64_t>();
  const YAML::Node e = node["evaluation"];
  if (e.IsDefined() && e.IsMap()) {  // (IsMap alone throws on a missing key)
    eval_every = e["every"].as<int64_t>();
    eval_episodes = e["episodes"].as<uint32_t>();
    eval_seed = e["seed"].as<uint64_t>(eval_seed);  // absent before it was an option
  } else {
    // SAC's layout before RunOptions: flat, each key absent before it existed.
    eval_every = node["eval_every"].as<int64_t>(eval_every);
    eval_episodes = node["eval_episodes"].as<uint32_t>(eval_episodes);
    eval_seed = node["eval_seed"].as<uint64_t>(eval_seed);
  }
  command = node["command"].as<std::string>("");
}

}  // namespace manibench::learning
