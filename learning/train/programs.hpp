// What manibench-train's commands share (main.cpp: learning from
// demonstrations; sac_command.cpp: SAC and its populations): argument
// values, and running the `manibench` program beside this one.
#pragma once

#include <manibench/learning/trainer.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace manibench::cli {
struct Arguments;
}

namespace manibench::learning::programs {

std::vector<std::string> splitList(const std::string& text);
// Usage errors name the option and carry `usage`.
int64_t parseInteger(const std::string& text, const std::string& option, int64_t minimum, const char* usage);
double parseNumber(const std::string& text, const std::string& option, const char* usage);
std::vector<int64_t> parseLayers(const std::string& text, const std::string& option, const char* usage);

// The options every training takes (RunOptions): the names of those with
// a value (--out, --seed, --threads, --device, --checkpoint-every,
// --log-every, --eval-every, --eval-episodes, --eval-seed), for the
// command's parseArguments; and their parse into `o` (what was not given
// keeps o's default), with `o.command` the command line.
const std::vector<std::string>& listRunOptions();
void parseRunOptions(const cli::Arguments& args, int argc, char** argv, RunOptions& o, const char* usage);

// `manibench eval ENVIRONMENT --policy torch_policy --policy-config POLICY
// ARGS... --no-progress --out OUT_DIR` in a child process (posix_spawn:
// nothing of this process's libtorch crosses into the evaluation's
// workers), its output in OUT_DIR/eval.log; the summary's overall numbers.
// The policy runs trusted (in the evaluation's workers, not sandboxed): it
// is the caller's own checkpoint.
// Throws LearningError (naming the log) when it fails.
EvaluationOutcome runPolicyEvaluation(const std::string& environment, const std::string& policy_config,
                                      const std::vector<std::string>& args, const std::string& out_dir);
// Runs `manibench ARGS...` with its output in `log_path`; its exit status
// (-1: it did not exit normally). Throws when it cannot start.
int runManibench(const std::vector<std::string>& args, const std::string& log_path);

}  // namespace manibench::learning::programs
