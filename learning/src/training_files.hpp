// The files of a training's directory, shared by the demonstration trainer
// (trainer.cpp) and SAC's (sac_trainer.cpp): whole-file writes that a kill
// cannot leave half-written, checkpoint names that sort by number, and the
// CSV logs a resumed run cuts back to its checkpoint.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

namespace YAML {
class Node;
}

namespace manibench::learning {

struct CheckpointInfo;
struct ObservationSpec;
struct RunOptions;

std::string yamlText(const YAML::Node& node);
// Writes `text` to a temporary file renamed into place.
void writeText(const std::filesystem::path& path, const std::string& text);
// "iter_0001000.pt": names that sort as their numbers (findNewestCheckpoint).
std::string checkpointName(int64_t iteration);
// Nine significant digits.
std::string formatNumber(double value);
// Keeps the CSV's header and the rows whose first column is at most
// `iteration` (a resumed run rewrites what came after its checkpoint).
void truncateCsv(const std::filesystem::path& path, int64_t iteration);
// DIR/eval_pending: the checkpoint being evaluated (its iteration or env
// steps), written before the evaluation starts and removed once its row is
// in eval.csv, so that a training stopped or killed during an evaluation
// evaluates that checkpoint again when resumed.
void markEvaluationPending(const std::filesystem::path& dir, int64_t at);
void clearEvaluationPending(const std::filesystem::path& dir);
// The pending evaluation's checkpoint, or -1 if none.
int64_t findPendingEvaluation(const std::filesystem::path& dir);
// DIR/policy.yaml: the torch_policy configuration of `checkpoint` on
// `device` (what evaluation runs on; "cpu" unless the user asked), with a
// comment line showing how to evaluate it on `task`.
void writePolicyConfig(const std::filesystem::path& dir, const std::string& task, const std::string& checkpoint,
                       const std::string& device);
// A checkpoint's record of what made it: the iteration, the run's
// algorithm and network, the observation spec, this build's version and
// `options_yaml` (the run's options as train.yaml has them).
CheckpointInfo describeCheckpoint(int64_t iteration, const RunOptions& options, const ObservationSpec& spec,
                                  const YAML::Node& options_yaml);
// Calls `read` with DIR/train.yaml; a LearningError naming the file when
// it is missing or damaged (or `read` throws a YAML::Exception: a key
// missing or of the wrong type).
void readTrainingYaml(const std::string& dir, const std::function<void(const YAML::Node&)>& read);

// What --resume DIR runs with: the options of DIR/train.yaml (Options: a
// RunOptions, TrainOptions or SacOptions, whose readYaml reads its older
// layouts too), out_dir the directory as named now (it may have moved).
template <class Options>
Options readRunDirectory(const std::string& dir) {
  Options options;
  readTrainingYaml(dir, [&](const YAML::Node& node) { options = Options::readYaml(node); });
  options.out_dir = dir;
  return options;
}

}  // namespace manibench::learning
