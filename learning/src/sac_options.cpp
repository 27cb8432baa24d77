// SacOptions' YAML form: train.yaml of a SAC training (`--resume` reads it back).
#include <manibench/learning/sac_trainer.hpp>

#include <yaml-cpp/yaml.h>

namespace manibench::learning {

void SacOptions::writeYaml(YAML::Node& node) const {
  node["out_dir"] = out_dir;
  node["environment"] = environment_id;
  node["split"] = split;
  node["objects"] = objects;
  node["config_files"] = config_files;
  node["config_sets"] = config_sets;
  YAML::Node a, n;
  algorithm.writeYaml(a);
  network.writeYaml(n);
  node["algorithm"] = a;
  node["network"] = n;
  node["steps"] = steps;
  node["workers"] = workers;
  node["replay_size"] = replay_size;
  node["updates_per_step"] = updates_per_step;
  node["random_steps"] = random_steps;
  node["learning_starts"] = learning_starts;
  node["early_done"] = early_done;
  node["seed"] = seed;
  node["threads"] = threads;
  node["device"] = device;
  node["checkpoint_every"] = checkpoint_every;
  node["log_every"] = log_every;
  node["worker_timeout"] = worker_timeout;
  node["eval_every"] = eval_every;
  node["eval_episodes"] = eval_episodes;
  node["eval_seed"] = eval_seed;
  node["command"] = command;
}

SacOptions SacOptions::readYaml(const YAML::Node& node) {
  SacOptions o;
  const std::vector<std::string> none;
  o.out_dir = node["out_dir"].as<std::string>();
  o.environment_id = node["environment"].as<std::string>();
  o.split = node["split"].as<std::string>();
  o.objects = node["objects"].as<std::vector<std::string>>(none);
  o.config_files = node["config_files"].as<std::vector<std::string>>(none);
  o.config_sets = node["config_sets"].as<std::vector<std::string>>(none);
  o.algorithm = AlgorithmOptions::readYaml(node["algorithm"]);
  o.network = NetOptions::readYaml(node["network"]);
  o.steps = node["steps"].as<int64_t>();
  o.workers = node["workers"].as<unsigned>();
  o.replay_size = node["replay_size"].as<int64_t>();
  o.updates_per_step = node["updates_per_step"].as<double>();
  o.random_steps = node["random_steps"].as<int64_t>();
  o.learning_starts = node["learning_starts"].as<int64_t>();
  o.early_done = node["early_done"].as<bool>();
  o.seed = node["seed"].as<uint64_t>();
  o.threads = node["threads"].as<int>();
  o.device = node["device"].as<std::string>();
  o.checkpoint_every = node["checkpoint_every"].as<int64_t>();
  o.log_every = node["log_every"].as<int64_t>();
  o.worker_timeout = node["worker_timeout"].as<double>(o.worker_timeout);  // absent before it existed
  o.eval_every = node["eval_every"].as<int64_t>(o.eval_every);                // (as these)
  o.eval_episodes = node["eval_episodes"].as<uint32_t>(o.eval_episodes);
  o.eval_seed = node["eval_seed"].as<uint64_t>(o.eval_seed);
  o.command = node["command"].as<std::string>("");
  return o;
}

}  // namespace manibench::learning
