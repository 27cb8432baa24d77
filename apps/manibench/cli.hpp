// Shared pieces of the manibench command-line program: the commands (one
// file each, command_*.cpp, dispatched from main.cpp), argument parsing and
// the options several commands share, usage errors, building a configured
// environment, printing.
#pragma once

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/observation.hpp>
#include <manibench/plugin_registry.hpp>

#include <signal.h>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace manibench::cli {

namespace mb = manibench;

// The commands: argv[1] is the command's name; each returns the exit code.
int commandList(int argc, char** argv);     // command_list.cpp
int commandInfo(int argc, char** argv);     // command_info.cpp
int commandRun(int argc, char** argv);      // command_run.cpp
int commandBench(int argc, char** argv);    // command_bench.cpp
int commandConfig(int argc, char** argv);   // command_config.cpp
int commandRender(int argc, char** argv);   // command_render.cpp
int commandObjects(int argc, char** argv);  // command_objects.cpp
int commandEval(int argc, char** argv);     // command_eval.cpp
int commandDemo(int argc, char** argv);     // command_demo.cpp
int commandDemos(int argc, char** argv);    // command_demos.cpp
int commandSurvey(int argc, char** argv);   // command_survey.cpp
int commandCompare(int argc, char** argv);  // command_compare.cpp

// A usage error carries the usage text of the command it concerns.
class UsageError : public Error {
 public:
  UsageError(const std::string& message, const char* usage)
      : Error(message), usage_(usage) {}
  const char* usage() const { return usage_; }

 private:
  const char* usage_;
};

// A program's main around `body`: a UsageError prints "<program>: message"
// and the usage (exit 2), any other exception "<program>: error: message"
// (exit 1, after a line break when `break_line_first`: a progress line may
// still be open). Shared by manibench, manibench-view and manibench-train.
int runMain(const std::string& program, const std::function<int()>& body, bool break_line_first = false);

// Minimal argument reader: positional words and --key value / --flag.
// Repeatable options (--config, --set) keep every value in order.
struct Arguments {
  std::vector<std::string> positional;
  std::map<std::string, std::string> options;
  std::map<std::string, std::vector<std::string>> repeated;
  bool help = false;
};

// Parses argv[first..]: `valued` options take a value, `flags` do not;
// those named in `repeatable` (--config and --set unless told otherwise)
// keep every value. Unknown options are a UsageError with `usage`.
Arguments parseArguments(int argc, char** argv, int first, const std::vector<std::string>& valued,
                         const std::vector<std::string>& flags, const char* usage,
                         const std::vector<std::string>& repeatable = {"config", "set"});
// A non-negative integer, or a UsageError naming `option` with `usage`.
uint64_t parseSeed(const std::string& text, const char* usage, const std::string& option = "--seed");
std::string valueOr(const Arguments& args, const std::string& key, const std::string& fallback);
// --split: train or test; `fallback` when not given.
std::string parseSplit(const Arguments& args, const std::string& fallback, const char* usage);
// --obs MODE: one of `allowed` (every mode when empty); nullopt when not given.
std::optional<mb::ObservationMode> parseObservationMode(
    const Arguments& args, const char* usage, const std::vector<mb::ObservationMode>& allowed = {});
void loadPlugins(mb::PluginRegistry& registry);
// The user's configuration layers from --config, --set and --controller
// (which acts as the last --set control.controller=NAME), then `mode`
// (--obs) as the last --set observation.mode=MODE.
mb::ConfigSources getConfigSources(const Arguments& args,
                                   std::optional<mb::ObservationMode> mode = std::nullopt);
// An environment as configured; plugin errors are annotated with the file
// (or --set) that wrote the keys they name.
std::unique_ptr<mb::Environment> makeEnvironment(const mb::PluginRegistry& registry,
                                                 const std::string& task_name,
                                                 const mb::ConfigSources& sources,
                                                 bool stop_on_success);
void printSegments(const std::vector<mb::sdk::Segment>& segments);
// The controller `policy` names (ABI 1.4's mb_policy_descriptor.controller)
// becomes the first --set control.controller=NAME, unless --controller or a
// --set of that key is given; a --controller, or a --config file's
// control.controller, other than the policy's is a UsageError naming both
// (and the file:line). Nothing for a policy that names none.
void applyPolicyController(const mb::PluginRegistry& registry, const std::string& policy, const Arguments& args,
                           mb::ConfigSources& sources, const char* usage);
// --video-size WxH (even, 16 to 8192), default 640x480; a UsageError with
// `usage` otherwise. Shared by run, render and demos replay.
std::pair<int, int> parseVideoSize(const Arguments& args, const char* usage);
// Resolves a policy name or a library path to load first (its one policy).
std::string resolvePolicy(mb::PluginRegistry& registry, const std::string& policy);

// --policy and --policy-config: the one resolution of every command that
// runs a policy on a task (run, eval, bench, render, demos generate, view).
// --policy is a registered NAME, a library PATH.so (or any path with a /)
// to load, a Python file PATH.py: a policy class run by the `python`
// policy plugin (docs/python.md), or a `manibench train` checkpoint
// PATH.pt run by `torch_policy` (docs/learning.md; where the learning
// module is built). A file of those two takes no --policy-config.
struct PolicyChoice {
  std::string name;                // the registered policy
  std::string config;              // the YAML its create gets ("" when none)
  std::vector<std::string> notes;  // where that YAML came from: "--policy-config FILE", "--policy FILE.py"
  std::vector<std::string> files;  // its own files (configuration, script, library): readable from the sandbox
};
// `fallback` is the policy without --policy (bench's random); none is a
// UsageError. Unreadable files, unknown names and libraries that do not
// load are errors before anything is built.
PolicyChoice choosePolicy(mb::PluginRegistry& registry, const Arguments& args, const char* usage,
                          const std::string& fallback = "");
// The --policy and --policy-config lines of the commands' help.
inline constexpr const char* kPolicyUsage =
    R"(  --policy NAME|PATH.so   policy plugin by name, or a library file to load
  --policy PATH.py        a Python policy class (act(obs), optional reset()),
                          run by the `python` policy plugin (docs/python.md)
  --policy PATH.pt        a `manibench train` checkpoint, run by the
                          `torch_policy` plugin (docs/learning.md; give the
                          training's --config DIR/environment.yaml too)
  --policy-config FILE    YAML handed to the policy's create (not with PATH.py
                          or PATH.pt)
)";

// The policy sandbox's options, shared by eval and demos generate
// (docs/evaluation.md, "Sandbox"): the flag and the help text.
inline constexpr const char* kTrustedPolicyFlag = "trusted-policy";
// eval's: episodes run to their time limit (EvaluationOptions::early_done).
inline constexpr const char* kNoEarlyDoneFlag = "no-early-done";
inline constexpr const char* kSandboxUsage =
    R"(  --trusted-policy        run the policy in the worker's process, beside the
                          environment (faster; for your own code only): by
                          default it runs in a sandboxed process of its own
  --policy-cpu-limit SEC  CPU seconds a sandboxed policy may use per episode
                          (default 60)
  --policy-memory-limit MIB  address space it may add (default 4096)
  --policy-output-limit MIB  its stdout/stderr log and each file it writes in
                          its temporary folder (default 16)
  --policy-read PATH      a file or folder it may read (repeatable); its
                          library or script folder and its --policy-config
                          folder are readable anyway
)";
// Fills `options`' sandbox fields from the arguments; `policy_files` are the
// policy's own files (library, script, configuration), readable from the
// sandbox with their folders.
void applySandboxOptions(const Arguments& args, mb::EvaluationOptions& options,
                         const std::vector<std::string>& policy_files, const char* usage);
// For the descriptions files carry (demonstrations): the command line,
// the time now as ISO 8601 UTC, and the loaded libraries as JSON.
std::string joinCommand(int argc, char** argv);
std::string formatUtcNow();
std::string describePlugins(const mb::PluginRegistry& registry);
// A deterministic object of `objects` for `seed`.
std::string chooseObject(const std::vector<std::string>& objects, uint64_t seed,
                         const std::string& split);
void printEpisode(const mb::EpisodeResult& r);

// "mm:ss" or "h:mm:ss".
std::string formatDuration(double seconds);
// "[#####.....] done/total", a bar of `width` characters.
std::string formatProgressBar(std::size_t done, std::size_t total, int width = 30);
// One progress line on stderr, redrawn in place: a bar of done/total, the
// unit, `details` (", 3 successful"), and the time left (or elapsed).
void drawProgressBar(std::size_t done, std::size_t total, const std::string& unit,
                     const std::string& details, double elapsed);

// While one lives, SIGINT, SIGTERM and SIGHUP only set a flag (the long
// commands stop cleanly and keep what they finished); the previous
// handlers come back when it goes.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  static bool isRequested();

 private:
  struct sigaction previous_[3];
};

}  // namespace manibench::cli
