#include <manibench/learning/checkpoint.hpp>

#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <filesystem>
#include <sstream>

namespace manibench::learning {

namespace {

const char* kMetaKey = "manibench_checkpoint";

std::string formatInfo(const CheckpointInfo& info) {
  YAML::Node root;
  root["format"] = "manibench-checkpoint";
  root["format_version"] = kCheckpointFormatVersion;
  root["manibench_version"] = info.manibench_version;
  root["iteration"] = info.iteration;
  YAML::Node algorithm, network, spec;
  info.algorithm.writeYaml(algorithm);
  info.network.writeYaml(network);
  info.spec.writeYaml(spec);
  root["algorithm"] = algorithm;
  root["network"] = network;
  root["spec"] = spec;
  root["training"] = info.training_yaml.empty() ? YAML::Node() : YAML::Load(info.training_yaml);
  YAML::Emitter out;
  out << root;
  return out.c_str();
}

CheckpointInfo parseInfo(const std::string& text, const std::string& path) {
  try {
    const YAML::Node root = YAML::Load(text);
    if (root["format"].as<std::string>("") != "manibench-checkpoint")
      throw LearningError("'" + path + "' is not a manibench checkpoint");
    const int version = root["format_version"].as<int>();
    if (version != kCheckpointFormatVersion)
      throw LearningError("'" + path + "' is a checkpoint of format version " + std::to_string(version) +
                          "; this build reads version " + std::to_string(kCheckpointFormatVersion));
    CheckpointInfo info;
    info.path = path;
    info.manibench_version = root["manibench_version"].as<std::string>("");
    info.iteration = root["iteration"].as<int64_t>();
    info.algorithm = AlgorithmOptions::readYaml(root["algorithm"]);
    info.network = NetOptions::readYaml(root["network"]);
    info.spec = ObservationSpec::readYaml(root["spec"]);
    if (root["training"] && !root["training"].IsNull()) {
      YAML::Emitter out;
      out << root["training"];
      info.training_yaml = out.c_str();
    }
    return info;
  } catch (const YAML::Exception& e) {
    throw LearningError("'" + path + "': a damaged checkpoint description: " + e.what());
  }
}

// Every tensor comes back on `device` (libtorch maps the storages as it
// reads them), whichever device it was saved from: without the map, a
// checkpoint trained on CUDA kept its parameters there (InputArchive::read
// hands a tensor of another device to set_data), beside CPU inputs, and
// could not be read at all on a machine without CUDA.
torch::serialize::InputArchive openArchive(const std::string& path, const torch::Device& device) {
  if (!std::filesystem::exists(path)) throw LearningError("no such checkpoint '" + path + "'");
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path, device);
  } catch (const c10::Error& e) {
    throw LearningError("'" + path + "' is not a checkpoint libtorch can read (" +
                        std::string(e.what_without_backtrace()) + ")");
  }
  return archive;
}

std::string readMeta(torch::serialize::InputArchive& archive, const std::string& path) {
  c10::IValue meta;
  if (!archive.try_read(kMetaKey, meta) || !meta.isString())
    throw LearningError("'" + path + "' is not a manibench checkpoint (a TorchScript file goes in "
                        "the policy configuration's `torchscript:` key, not `checkpoint:`)");
  return meta.toStringRef();
}

}  // namespace

void saveCheckpoint(const std::string& path, const CheckpointInfo& info, const Algorithm& algorithm,
                    const std::map<std::string, torch::Tensor>& extras) {
  torch::serialize::OutputArchive archive;
  archive.write(kMetaKey, c10::IValue(formatInfo(info)));
  algorithm.save(archive, true);
  for (const auto& [name, tensor] : extras) archive.write("extra." + name, tensor);
  const std::string temporary = path + ".tmp";
  try {
    archive.save_to(temporary);
  } catch (const c10::Error& e) {
    std::remove(temporary.c_str());
    throw LearningError("cannot write the checkpoint '" + path + "': " + e.what_without_backtrace());
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) throw LearningError("cannot write the checkpoint '" + path + "': " + error.message());
}

CheckpointInfo readCheckpointInfo(const std::string& path) {
  torch::serialize::InputArchive archive = openArchive(path, torch::kCPU);
  return parseInfo(readMeta(archive, path), path);
}

LoadedCheckpoint loadCheckpoint(const std::string& path, const torch::Device& device, bool with_optimizers,
                                const std::vector<std::string>& extras) {
  torch::serialize::InputArchive archive = openArchive(path, device);
  LoadedCheckpoint out;
  out.info = parseInfo(readMeta(archive, path), path);
  out.algorithm = makeAlgorithm(out.info.algorithm, out.info.network, out.info.spec, device);
  try {
    out.algorithm->load(archive, with_optimizers);
    for (const std::string& name : extras) {
      torch::Tensor t;
      if (!archive.try_read("extra." + name, t)) {
        if (name == kCudaGeneratorExtra) continue;  // trained on the CPU
        throw LearningError("'" + path + "' has no '" + name + "' to resume from");
      }
      out.extras[name] = t.to(torch::kCPU);  // generator states and counters: read on the CPU
    }
  } catch (const c10::Error& e) {
    throw LearningError("'" + path + "': " + e.what_without_backtrace());
  }
  return out;
}

void addGeneratorStates(std::map<std::string, torch::Tensor>& extras, const torch::Device& device) {
  extras[kCpuGeneratorExtra] = at::detail::getDefaultCPUGenerator().get_state();
  if (device.is_cuda()) extras[kCudaGeneratorExtra] = at::globalContext().defaultGenerator(device).get_state();
}

void restoreGeneratorStates(const std::map<std::string, torch::Tensor>& extras, const torch::Device& device) {
  at::Generator cpu = at::detail::getDefaultCPUGenerator();  // shares the default's state
  cpu.set_state(extras.at(kCpuGeneratorExtra));
  const auto cuda = extras.find(kCudaGeneratorExtra);
  if (device.is_cuda() && cuda != extras.end()) {
    at::Generator generator = at::globalContext().defaultGenerator(device);
    generator.set_state(cuda->second);
  }
}

}  // namespace manibench::learning
