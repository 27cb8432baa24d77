// What `manibench eval` and `eval --verify` share (command_eval.cpp,
// eval_verify.cpp): the arguments, and the run they describe set up as far
// as it can be before any worker starts.
#pragma once

#include <manibench/evaluation.hpp>
#include <manibench/plugin_registry.hpp>

#include <memory>
#include <string>
#include <vector>

#include "cli.hpp"
#include "policy_run.hpp"

namespace manibench::cli {

extern const char* const kEvalUsage;

// eval's options from argv[first..].
Arguments parseEvalArguments(int argc, char** argv, int first);
// The arguments that decide an evaluation's result, as --verify runs them
// again: the task, then every option but --out, --workers, --shard,
// --resume, --no-progress and --benchmark, as --key=value (certificate.json's
// "command").
std::vector<std::string> describeEvalCommand(const Arguments& args);

// The plugins loaded, the policy chosen, the configuration checked, the
// options filled (the certificate's command, policy files and merged
// configuration too). Not movable: the run's factory refers to the registry.
struct EvalSetup {
  PluginRegistry registry;
  EvaluationOptions options;
  PolicyRun run;
};
std::unique_ptr<EvalSetup> prepareEval(const Arguments& args);

// eval --verify DIR [--sample N] [--workers N] (eval_verify.cpp).
int verifyEvaluation(int argc, char** argv);

}  // namespace manibench::cli
