#include "sac_population.hpp"

#include <manibench/learning/trainer.hpp>

#include <manibench/environment.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/task_name.hpp>

#include <yaml-cpp/yaml.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

#include "cli.hpp"
#include "programs.hpp"

namespace manibench::learning::programs {

namespace fs = std::filesystem;
namespace mb = manibench;

namespace {

struct ObjectResult {
  unsigned attempts = 0;
  double success_rate = 0;
  std::string policy_config;  // the best attempt's policy.yaml
  bool accepted = false;
};

void writeYamlFile(const fs::path& path, const YAML::Node& node) {
  YAML::Emitter out;
  out << node;
  const fs::path temporary = path.string() + ".tmp";
  std::ofstream(temporary) << out.c_str() << "\n";
  fs::rename(temporary, path);
}

std::string formatRate(double rate) { return std::to_string(int(rate * 100 + 0.5)) + "%"; }

class Population {
 public:
  explicit Population(const PopulationOptions& options) : o_(options), dir_(options.out_dir) {}

  int run() {
    mb::PluginRegistry registry;
    registry.loadSearchPath();
    const mb::Environment probe(registry, o_.task);
    objects_ = o_.objects.empty() ? probe.listObjects(o_.split) : o_.objects;
    if (objects_.empty()) throw LearningError(o_.task + " has no " + o_.split + " objects");
    // Each object's agent depends on its id alone: a shard (or MPI rank)
    // takes every shards-th object, in its own object directories.
    std::vector<std::string> share;
    for (std::size_t i = o_.shard; i < objects_.size(); i += o_.shards) share.push_back(objects_[i]);
    objects_ = std::move(share);
    if (objects_.empty()) {
      std::cerr << "shard " << o_.shard + 1 << "/" << o_.shards << ": no objects\n";
      return 0;
    }
    fs::create_directories(dir_ / "objects");
    writeSummary();
    for (const std::string& object : objects_) {
      ObjectResult result;
      if (!trainObject(object, result)) {
        std::cerr << "stopped; run the same command again to continue\n";
        return 130;
      }
      results_[object] = result;
      writeSummary();
    }
    if (o_.demos_per_object > 0)
      for (const std::string& object : objects_) generateDemos(object);
    unsigned accepted = 0;
    for (const auto& [object, r] : results_) accepted += r.accepted ? 1 : 0;
    std::cerr << accepted << " of " << objects_.size() << " objects have an agent at or above "
              << formatRate(o_.threshold) << " success; " << (dir_ / getSummaryName()).string() << "\n";
    return 0;
  }

 private:
  std::string fixedId(const std::string& object) const {
    const std::string id = mb::makeFixedObjectId(o_.task, object);
    if (id.empty()) throw LearningError("'" + o_.task + "' has no fixed-object ids (its name does not end in -vN)");
    return id;
  }

  // Trains (or resumes, or reads back) the object's attempts until one
  // reaches the threshold or none is left; false when a training stopped.
  bool trainObject(const std::string& object, ObjectResult& result) {
    const fs::path object_dir = dir_ / "objects" / object;
    if (fs::exists(object_dir / "result.yaml")) {
      const YAML::Node node = YAML::LoadFile((object_dir / "result.yaml").string());
      result.attempts = node["attempts"].as<unsigned>();
      result.success_rate = node["success_rate"].as<double>();
      result.policy_config = node["policy_config"].as<std::string>();
      result.accepted = node["accepted"].as<bool>();
      std::cerr << "object " << object << ": done before (" << formatRate(result.success_rate) << ")\n";
      return true;
    }
    double best = -1;
    for (unsigned k = 0; k < o_.max_attempts; ++k) {
      const fs::path attempt = object_dir / ("attempt_" + std::to_string(k));
      if (!trainAttempt(object, k, attempt)) return false;
      const EvaluationOutcome outcome =
          runPolicyEvaluation(fixedId(object), (attempt / "policy.yaml").string(),
                              {"--episodes-per-object", std::to_string(o_.eval_episodes), "--seed",
                               std::to_string(o_.eval_seed)},
                              (attempt / "eval").string());
      if (outcome.interrupted) return false;  // resumed, it evaluates on from its journal
      std::cerr << "object " << object << ", attempt " << k << ": success " << formatRate(outcome.success_rate)
                << " (" << outcome.successes << "/" << outcome.episodes << ")"
                << describeFailures(outcome, (attempt / "eval").string()) << "\n";
      result.attempts = k + 1;
      if (outcome.success_rate > best) {
        best = outcome.success_rate;
        result.success_rate = outcome.success_rate;
        result.policy_config = fs::absolute(attempt / "policy.yaml").string();
      }
      if (outcome.success_rate >= o_.threshold) break;
    }
    result.accepted = result.success_rate >= o_.threshold;
    fs::copy_file(result.policy_config, object_dir / "policy.yaml", fs::copy_options::overwrite_existing);
    YAML::Node node;
    node["attempts"] = result.attempts;
    node["success_rate"] = result.success_rate;
    node["policy_config"] = result.policy_config;
    node["accepted"] = result.accepted;
    writeYamlFile(object_dir / "result.yaml", node);
    return true;
  }

  // Attempt k: seed from (base seed, object, k) only; started, resumed, or
  // already done.
  bool trainAttempt(const std::string& object, unsigned k, const fs::path& attempt) {
    const uint64_t seed = calcEpisodeSeed(o_.seed, object, k);
    std::vector<std::string> args;
    std::string log = (attempt / "train.log").string();
    if (fs::exists(attempt / "train.yaml")) {
      const std::string newest = findNewestCheckpoint(attempt.string());
      const int64_t target = YAML::LoadFile((attempt / "train.yaml").string())["steps"].as<int64_t>();
      // iter_N.pt: N env steps.
      if (!newest.empty() && std::stoll(fs::path(newest).stem().string().substr(5)) >= target) return true;
      if (newest.empty()) {
        fs::remove_all(attempt);  // stopped before its first checkpoint: start it again
      } else {
        args = {"train", "--resume", attempt.string(), "--no-progress"};
        log = (attempt / "resume.log").string();
      }
    }
    if (args.empty()) {
      fs::create_directories(attempt);
      args = {"train", "sac", fixedId(object), "--out", attempt.string(), "--seed", std::to_string(seed),
              "--no-progress"};
      args.insert(args.end(), o_.sac_args.begin(), o_.sac_args.end());
    }
    std::cerr << "object " << object << ", attempt " << k << ": " << (args[1] == "sac" ? "training" : "resuming")
              << " (seed " << seed << "; " << log << ")\n";
    const int status = runManibench(args, log);
    if (status == 130) return false;
    if (status != 0) throw LearningError("the training of object " + object + " failed (" + log + " says why)");
    return true;
  }

  void generateDemos(const std::string& object) {
    const ObjectResult& r = results_.at(object);
    if (!r.accepted) {
      std::cerr << "object " << object << ": no demonstrations (its agent is below the threshold)\n";
      return;
    }
    fs::create_directories(dir_ / "demos");
    const fs::path file = dir_ / "demos" / (object + ".h5");
    if (fs::exists(file)) return;
    const std::string log = (dir_ / "demos" / (object + ".log")).string();
    const int status = runManibench({"demos", "generate", fixedId(object), "--policy", "torch_policy",
                                     "--policy-config", (dir_ / "objects" / object / "policy.yaml").string(),
                                     "--per-object", std::to_string(o_.demos_per_object), "--no-progress",
                                     "--out", file.string()},
                                    log);
    if (status != 0) throw LearningError("the demonstrations of object " + object + " failed (" + log + " says why)");
    std::cerr << "object " << object << ": " << file.string() << "\n";
  }

  void writeSummary() {
    YAML::Node node;
    node["task"] = o_.task;
    node["split"] = o_.split;
    node["seed"] = o_.seed;
    node["threshold"] = o_.threshold;
    node["max_attempts"] = o_.max_attempts;
    node["eval_episodes"] = o_.eval_episodes;
    node["sac_args"] = o_.sac_args;
    YAML::Node objects;
    for (const std::string& object : objects_) {
      const auto r = results_.find(object);
      YAML::Node entry;
      if (r == results_.end()) {
        entry["state"] = "pending";
      } else {
        entry["state"] = r->second.accepted ? "accepted" : "below_threshold";
        entry["attempts"] = r->second.attempts;
        entry["success_rate"] = r->second.success_rate;
        entry["policy_config"] = fs::absolute(dir_ / "objects" / object / "policy.yaml").string();
      }
      objects[object] = entry;
    }
    node["objects"] = objects;
    writeYamlFile(dir_ / getSummaryName(), node);
  }

  std::string getSummaryName() const {
    if (o_.shards == 1) return "population.yaml";
    return "population-" + std::to_string(o_.shard + 1) + "-of-" + std::to_string(o_.shards) + ".yaml";
  }

  PopulationOptions o_;
  fs::path dir_;
  std::vector<std::string> objects_;
  std::map<std::string, ObjectResult> results_;
};

}  // namespace

int runPopulation(const PopulationOptions& options) { return Population(options).run(); }

void placeOnShard(const std::string& text, uint32_t& shard, uint32_t& shards) {
  const char* rank = std::getenv("OMPI_COMM_WORLD_RANK");
  const char* size = std::getenv("OMPI_COMM_WORLD_SIZE");
  if (!text.empty()) {
    try {
      mb::parseShard(text, shard, shards);
    } catch (const mb::InvalidArgument& e) {
      throw LearningError(std::string("--shard: ") + e.what());
    }
  } else if (rank && size) {
    shard = uint32_t(std::stoul(rank));
    shards = uint32_t(std::stoul(size));
  }
  // The trainings and evaluations this process starts are not ranks.
  std::vector<std::string> names;
  for (char** e = environ; *e; ++e) {
    const std::string entry = *e;
    if (entry.rfind("OMPI_", 0) == 0 || entry.rfind("PMIX_", 0) == 0 || entry.rfind("PMI_", 0) == 0)
      names.push_back(entry.substr(0, entry.find('=')));
  }
  for (const std::string& name : names) unsetenv(name.c_str());
}

}  // namespace manibench::learning::programs
