// SacOptions' YAML form: train.yaml of a SAC training (`--resume` reads it
// back): RunOptions' layout, then SAC's own keys.
#include <manibench/learning/sac_trainer.hpp>

#include <yaml-cpp/yaml.h>

namespace manibench::learning {

void SacOptions::check() const {
  checkRun();
  if (steps <= 0 || replay_size <= 0)
    throw LearningError("--steps, --replay-size, --checkpoint-every and --log-every must be positive");
  if (workers == 0) throw LearningError("--workers must be at least 1");
  if (!(worker_timeout >= 0)) throw LearningError("--worker-timeout must be at least 0 (0: none)");
  if (network.kind != NetKind::Mlp) throw LearningError("SAC trains in the state mode: --net mlp");
}

void SacOptions::writeYaml(YAML::Node& node) const {
  writeRun(node);
  node["environment"] = environment_id;
  node["split"] = split;
  node["objects"] = objects;
  node["config_files"] = config_files;
  node["config_sets"] = config_sets;
  node["steps"] = steps;
  node["workers"] = workers;
  node["replay_size"] = replay_size;
  node["updates_per_step"] = updates_per_step;
  node["random_steps"] = random_steps;
  node["learning_starts"] = learning_starts;
  node["early_done"] = early_done;
  node["worker_timeout"] = worker_timeout;
}

SacOptions SacOptions::readYaml(const YAML::Node& node) {
  SacOptions o;
  const std::vector<std::string> none;
  o.readRun(node);
  o.environment_id = node["environment"].as<std::string>();
  o.split = node["split"].as<std::string>();
  o.objects = node["objects"].as<std::vector<std::string>>(none);
  o.config_files = node["config_files"].as<std::vector<std::string>>(none);
  o.config_sets = node["config_sets"].as<std::vector<std::string>>(none);
  o.steps = node["steps"].as<int64_t>();
  o.workers = node["workers"].as<unsigned>();
  o.replay_size = node["replay_size"].as<int64_t>();
  o.updates_per_step = node["updates_per_step"].as<double>();
  o.random_steps = node["random_steps"].as<int64_t>();
  o.learning_starts = node["learning_starts"].as<int64_t>();
  o.early_done = node["early_done"].as<bool>();
  o.worker_timeout = node["worker_timeout"].as<double>(o.worker_timeout);  // absent before it existed
  return o;
}

}  // namespace manibench::learning
