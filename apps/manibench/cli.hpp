// Shared pieces of the manibench command-line program: argument parsing,
// usage errors, building a configured environment, printing. Each command
// lives in its own file (command_*.cpp) and is dispatched from main.cpp.
#pragma once

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>
#include <manibench/plugin_registry.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench::cli {

namespace mb = manibench;

// A usage error carries the usage text of the command it concerns.
class UsageError : public std::runtime_error {
 public:
  UsageError(const std::string& message, const char* usage)
      : std::runtime_error(message), usage_(usage) {}
  const char* usage() const { return usage_; }

 private:
  const char* usage_;
};

// Minimal argument reader: positional words and --key value / --flag.
// Repeatable options (--config, --set) keep every value in order.
struct Arguments {
  std::vector<std::string> positional;
  std::map<std::string, std::string> options;
  std::map<std::string, std::vector<std::string>> repeated;
  bool help = false;
};

// Parses argv[first..]: `valued` options take a value, `flags` do not;
// --config and --set repeat. Unknown options are a UsageError with `usage`.
Arguments parseArguments(int argc, char** argv, int first, const std::vector<std::string>& valued,
                         const std::vector<std::string>& flags, const char* usage);
// A non-negative integer, or a UsageError naming `option` with `usage`.
uint64_t parseSeed(const std::string& text, const char* usage, const std::string& option = "--seed");
std::string valueOr(const Arguments& args, const std::string& key, const std::string& fallback);
void loadPlugins(mb::PluginRegistry& registry);
// The user's configuration layers from --config, --set and --controller
// (which acts as the last --set control.controller=NAME).
mb::ConfigSources getConfigSources(const Arguments& args);
// An environment as configured; plugin errors are annotated with the file
// (or --set) that wrote the keys they name.
std::unique_ptr<mb::Environment> makeEnvironment(const mb::PluginRegistry& registry,
                                                 const std::string& task_name,
                                                 const mb::ConfigSources& sources,
                                                 bool stop_on_success);
void printSegments(const std::vector<mb::SegmentDescription>& segments);
// Resolves --policy: a registered name, or a library path to load first.
std::string resolvePolicy(mb::PluginRegistry& registry, const std::string& policy);
// A deterministic object of `objects` for `seed`.
std::string chooseObject(const std::vector<std::string>& objects, uint64_t seed,
                         const std::string& split);
void printEpisode(const mb::EpisodeResult& r);

}  // namespace manibench::cli
