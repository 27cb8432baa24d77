#include "training_files.hpp"

#include <manibench/evaluation.hpp>
#include <manibench/learning/checkpoint.hpp>
#include <manibench/learning/run_options.hpp>
#include <manibench/learning/spec.hpp>

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <iomanip>
#include <sstream>

namespace manibench::learning {

namespace fs = std::filesystem;

std::string yamlText(const YAML::Node& node) {
  YAML::Emitter out;
  out << node;
  return std::string(out.c_str()) + "\n";
}

void writeText(const fs::path& path, const std::string& text) {
  const fs::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary);
    out << text;
    if (!out) throw LearningError("cannot write '" + path.string() + "'");
  }
  fs::rename(temporary, path);
}

void writePolicyConfig(const fs::path& dir, const std::string& task, const std::string& checkpoint,
                       const std::string& device) {
  const fs::path path = fs::absolute(dir / "policy.yaml");
  writeText(path, "# manibench eval " + task + " --policy torch_policy --policy-config " + path.string() +
                      "\ncheckpoint: '" + checkpoint + "'\ndevice: " + device + "\n");
}

std::string checkpointName(int64_t iteration) {
  std::ostringstream name;
  name << "iter_" << std::setw(7) << std::setfill('0') << iteration << ".pt";
  return name.str();
}

std::string formatNumber(double value) {
  std::ostringstream out;
  out << std::setprecision(9) << value;
  return out.str();
}

void truncateCsv(const fs::path& path, int64_t iteration) {
  std::ifstream in(path);
  if (!in) return;
  std::string line, kept;
  bool header = true;
  while (std::getline(in, line)) {
    if (header || std::stoll(line.substr(0, line.find(','))) <= iteration) kept += line + "\n";
    header = false;
  }
  in.close();
  writeText(path, kept);
}

void markEvaluationPending(const fs::path& dir, int64_t at) { writeText(dir / "eval_pending", std::to_string(at) + "\n"); }

void clearEvaluationPending(const fs::path& dir) { fs::remove(dir / "eval_pending"); }

int64_t findPendingEvaluation(const fs::path& dir) {
  std::ifstream in(dir / "eval_pending");
  int64_t at = -1;
  if (!(in >> at) || at < 0) return -1;
  return at;
}

void readTrainingYaml(const std::string& dir, const std::function<void(const YAML::Node&)>& read) {
  const fs::path file = fs::path(dir) / "train.yaml";
  if (!fs::exists(file)) throw LearningError("'" + dir + "' holds no training (no train.yaml)");
  try {
    read(YAML::LoadFile(file.string()));
  } catch (const YAML::Exception& e) {
    throw LearningError("'" + file.string() + "': " + e.what());
  }
}

CheckpointInfo describeCheckpoint(int64_t iteration, const RunOptions& options, const ObservationSpec& spec,
                                  const YAML::Node& options_yaml) {
  CheckpointInfo info;
  info.iteration = iteration;
  info.algorithm = options.algorithm;
  info.network = options.network;
  info.spec = spec;
  info.manibench_version = getManibenchVersion();
  info.training_yaml = yamlText(options_yaml);
  return info;
}

}  // namespace manibench::learning
