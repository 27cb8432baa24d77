#include "cli.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>

namespace manibench::cli {

int runMain(const std::string& program, const std::function<int()>& body, bool break_line_first) {
  try {
    return body();
  } catch (const UsageError& e) {
    std::cerr << program << ": " << e.what() << "\n\n" << e.usage();
    return 2;
  } catch (const std::exception& e) {
    std::cerr << (break_line_first ? "\n" : "") << program << ": error: " << e.what() << "\n";
    return 1;
  }
}

Arguments parseArguments(int argc, char** argv, int first, const std::vector<std::string>& valued,
                         const std::vector<std::string>& flags, const char* usage,
                         const std::vector<std::string>& repeatable) {
  Arguments args;
  for (int i = first; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--help" || word == "-h") {
      args.help = true;
    } else if (word.rfind("--", 0) == 0) {
      std::string key = word.substr(2);
      std::string value;
      const std::size_t eq = key.find('=');
      if (eq != std::string::npos) {
        value = key.substr(eq + 1);
        key = key.substr(0, eq);
      }
      const bool is_valued = std::find(valued.begin(), valued.end(), key) != valued.end();
      const bool is_flag = std::find(flags.begin(), flags.end(), key) != flags.end();
      if (!is_valued && !is_flag) throw UsageError("unknown option '" + word + "'", usage);
      if (is_valued && eq == std::string::npos) {
        if (i + 1 >= argc) throw UsageError("option '--" + key + "' needs a value", usage);
        value = argv[++i];
      }
      if (is_flag && eq != std::string::npos)
        throw UsageError("option '--" + key + "' takes no value", usage);
      if (std::find(repeatable.begin(), repeatable.end(), key) != repeatable.end())
        args.repeated[key].push_back(value);
      else
        args.options[key] = value;
    } else {
      args.positional.push_back(word);
    }
  }
  return args;
}

uint64_t parseSeed(const std::string& text, const char* usage, const std::string& option) {
  try {
    std::size_t used = 0;
    const unsigned long long value = std::stoull(text, &used);
    if (used != text.size() || text.find('-') != std::string::npos) throw InvalidArgument(text);
    return value;
  } catch (const std::exception&) {
    throw UsageError(option + " needs a non-negative integer, got '" + text + "'", usage);
  }
}

std::string valueOr(const Arguments& args, const std::string& key, const std::string& fallback) {
  const auto it = args.options.find(key);
  return it == args.options.end() ? fallback : it->second;
}

std::string parseSplit(const Arguments& args, const std::string& fallback, const char* usage) {
  const std::string split = valueOr(args, "split", fallback);
  if (split != "train" && split != "test")
    throw UsageError("--split must be train or test, got '" + split + "'", usage);
  return split;
}

std::optional<mb::ObservationMode> parseObservationMode(
    const Arguments& args, const char* usage, const std::vector<mb::ObservationMode>& allowed) {
  const auto given = args.options.find("obs");
  if (given == args.options.end()) return std::nullopt;
  const std::optional<mb::ObservationMode> mode = mb::findObservationMode(given->second);
  const bool ok =
      mode && (allowed.empty() || std::find(allowed.begin(), allowed.end(), *mode) != allowed.end());
  if (ok) return mode;
  std::vector<std::string> names;
  if (allowed.empty()) names = mb::getObservationModeNames();
  for (mb::ObservationMode m : allowed) names.push_back(mb::toString(m));
  std::string list;
  for (std::size_t i = 0; i < names.size(); ++i)
    list += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  throw UsageError("--obs must be " + list + ", got '" + given->second + "'", usage);
}

void loadPlugins(mb::PluginRegistry& registry) { registry.loadSearchPath(); }

mb::ConfigSources getConfigSources(const Arguments& args, std::optional<mb::ObservationMode> mode) {
  mb::ConfigSources sources;
  const auto files = args.repeated.find("config");
  if (files != args.repeated.end()) sources.files = files->second;
  const auto sets = args.repeated.find("set");
  if (sets != args.repeated.end()) sources.overrides = sets->second;
  const auto controller = args.options.find("controller");
  if (controller != args.options.end())
    sources.overrides.push_back("control.controller=" + controller->second);
  if (mode) sources.overrides.push_back(std::string("observation.mode=") + mb::toString(*mode));
  return sources;
}

// An environment as configured. A plugin that rejects its configuration
// reports lines of the text it was handed; the note added here says in
// which file (or --set) the keys it names were written.
std::unique_ptr<mb::Environment> makeEnvironment(const mb::PluginRegistry& registry,
                                                 const std::string& task_name,
                                                 const mb::ConfigSources& sources,
                                                 bool stop_on_success) {
  const mb::ConfigNode config = mb::loadTaskConfig(registry, task_name, sources);
  mb::EnvironmentOptions options = mb::calcEnvironmentOptions(config);
  options.stop_on_success = stop_on_success;
  try {
    return std::make_unique<mb::Environment>(registry, task_name, options);
  } catch (const mb::PluginCallError& e) {
    throw mb::PluginCallError(mb::annotatePluginError(config, e.what()), e.status());
  }
}

void printSegments(const std::vector<mb::sdk::Segment>& segments) {
  for (const auto& s : segments) {
    std::ostringstream range;
    range << "[" << s.offset << ", " << s.offset + s.size << ")";
    std::cout << "  " << std::left << std::setw(12) << range.str() << std::setw(22) << s.name
              << s.description << "\n";
  }
}

std::pair<int, int> parseVideoSize(const Arguments& args, const char* usage) {
  const auto given = args.options.find("video-size");
  if (given == args.options.end()) return {640, 480};
  char x = 0;
  int w = 0, h = 0;
  if (std::sscanf(given->second.c_str(), "%d%c%d", &w, &x, &h) != 3 || x != 'x' || w < 16 || h < 16 || w > 8192 ||
      h > 8192 || w % 2 || h % 2)
    throw UsageError("--video-size must be WxH, even numbers from 16 to 8192, got '" + given->second + "'", usage);
  return {w, h};
}

void applyPolicyController(const mb::PluginRegistry& registry, const std::string& policy, const Arguments& args,
                           mb::ConfigSources& sources, const char* usage) {
  const mb::PluginEntry* entry = registry.findEntry(mb::PluginKind::Policy, policy);
  if (entry == nullptr) return;  // the caller's getEntry reports it
  const std::string wanted =
      mb::getPolicyController(*reinterpret_cast<const mb_policy_descriptor*>(entry->descriptor));
  if (wanted.empty()) return;
  const auto given = args.options.find("controller");
  if (given != args.options.end()) {
    if (given->second != wanted)
      throw UsageError("--policy " + policy + " drives the " + wanted + " controller, but --controller " +
                           given->second + " was given (leave --controller out, or give --controller " + wanted + ")",
                       usage);
    return;
  }
  for (const std::string& set : sources.overrides)
    if (set.rfind("control.controller=", 0) == 0) return;  // the user's --set decides
  // The policy's controller goes in as an override, above every --config
  // file: a file naming another one would be overridden without a word.
  for (const std::string& file : sources.files) {
    const mb::ConfigNode layer = mb::loadConfigFile(file);
    const mb::ConfigNode* named = layer.findPath("control.controller");
    if (named != nullptr && named->isScalar() && named->scalar != wanted)
      throw UsageError(named->origin.describe() + ": control.controller is " + named->scalar + ", but --policy " +
                           policy + " drives the " + wanted + " controller (remove the key, or set it to " + wanted +
                           ")",
                       usage);
  }
  sources.overrides.insert(sources.overrides.begin(), "control.controller=" + wanted);
}

std::string resolvePolicy(mb::PluginRegistry& registry, const std::string& policy) {
  const bool is_path = policy.find('/') != std::string::npos ||
                       (policy.size() > 3 && policy.compare(policy.size() - 3, 3, ".so") == 0);
  if (!is_path) return policy;
  const std::size_t library = registry.loadLibrary(policy);
  std::vector<std::string> policies;
  for (const mb::PluginEntry& e : registry.getEntries())
    if (e.kind == mb::PluginKind::Policy && e.library == library) policies.push_back(e.name);
  if (policies.size() != 1)
    throw std::runtime_error("library " + policy + " registers " + std::to_string(policies.size()) +
                             " policies; give one by name with MANIBENCH_PLUGIN_PATH instead");
  return policies.front();
}

namespace {

std::string readTextFile(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the " + what + " '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool hasExtension(const std::string& path, const std::string& extension) {
  return path.size() > extension.size() &&
         path.compare(path.size() - extension.size(), extension.size(), extension) == 0;
}

// `key: 'PATH'` (absolute, YAML single-quoted): the configuration of the
// plugin that runs the file, which must be readable.
std::string makeFileConfig(const std::string& key, const std::string& path) {
  readTextFile(path, "policy file");
  std::string quoted;
  for (char c : std::filesystem::absolute(path).string())
    quoted += c == '\'' ? std::string("''") : std::string(1, c);
  return key + ": '" + quoted + "'\n";
}

}  // namespace

PolicyChoice choosePolicy(mb::PluginRegistry& registry, const Arguments& args, const char* usage,
                          const std::string& fallback) {
  std::string policy = valueOr(args, "policy", fallback);
  if (policy.empty()) throw UsageError("--policy NAME|PATH.so|PATH.py|PATH.pt is needed", usage);
  PolicyChoice choice;
  const auto config_file = args.options.find("policy-config");
  if (config_file != args.options.end()) {
    choice.config = readTextFile(config_file->second, "policy configuration");
    choice.notes.push_back("--policy-config " + config_file->second);
    choice.files.push_back(config_file->second);
  }
  // A file another plugin runs: a Python policy class (the `python`
  // plugin's embedded interpreter starts where the policy runs: in an
  // evaluation, each worker, after the fork), or a `manibench train`
  // checkpoint (torch_policy, the learning module's).
  const bool python = hasExtension(policy, ".py"), checkpoint = hasExtension(policy, ".pt");
  if (python || checkpoint) {
    const std::string plugin = python ? "python" : "torch_policy";
    if (config_file != args.options.end())
      throw UsageError("--policy " + policy + " takes no --policy-config (name the file in a configuration for "
                       "--policy " + plugin + " instead)", usage);
    if (registry.findEntry(mb::PluginKind::Policy, plugin) == nullptr)
      throw std::runtime_error("--policy " + policy + " runs through the `" + plugin + "` policy plugin, which " +
                               (python ? "this build lacks (libpython)" : "this build lacks (the learning module, libtorch)"));
    choice.config = makeFileConfig(python ? "file" : "checkpoint", policy);
    choice.notes.push_back("--policy " + policy);
    choice.files.push_back(policy);
    policy = plugin;
  }
  choice.name = resolvePolicy(registry, policy);
  const mb::PluginEntry& entry = registry.getEntry(mb::PluginKind::Policy, choice.name);
  choice.files.push_back(registry.getLibraries()[entry.library].path);
  return choice;
}

void applySandboxOptions(const Arguments& args, mb::EvaluationOptions& options,
                         const std::vector<std::string>& policy_files, const char* usage) {
  options.sandbox_policy = !args.options.count(kTrustedPolicyFlag);
  auto number = [&](const char* key, double fallback) {
    const auto it = args.options.find(key);
    if (it == args.options.end()) return fallback;
    char* end = nullptr;
    const double value = std::strtod(it->second.c_str(), &end);
    if (*end || !(value > 0) || !std::isfinite(value))
      throw UsageError(std::string("--") + key + " needs a positive number, got '" + it->second + "'",
                       usage);
    return value;
  };
  options.policy_cpu_limit = number("policy-cpu-limit", options.policy_cpu_limit);
  options.policy_memory_limit =
      uint64_t(number("policy-memory-limit", double(options.policy_memory_limit >> 20)) * 1048576.0);
  options.policy_output_limit =
      uint64_t(number("policy-output-limit", double(options.policy_output_limit >> 20)) * 1048576.0);
  std::vector<std::string> paths;
  for (const std::string& file : policy_files) {
    if (file.empty()) continue;
    const std::filesystem::path absolute = std::filesystem::absolute(file);
    paths.push_back(absolute.string());
    paths.push_back(absolute.parent_path().string());
  }
  const auto reads = args.repeated.find("policy-read");
  if (reads != args.repeated.end())
    for (const std::string& path : reads->second) paths.push_back(std::filesystem::absolute(path).string());
  options.policy_read_paths = paths;
}

std::string joinCommand(int argc, char** argv) {
  std::string text;
  for (int i = 0; i < argc; ++i) text += (i ? " " : "") + std::string(argv[i]);
  return text;
}

std::string formatUtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buffer;
}

std::string describePlugins(const mb::PluginRegistry& registry) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const mb::LoadedLibrary& library : registry.getLibraries())
    list.push_back({{"name", library.name},
                    {"version", library.version},
                    {"abi", std::to_string(library.abi_major) + "." + std::to_string(library.abi_minor)},
                    {"library", library.path}});
  return list.dump();
}

std::string chooseObject(const std::vector<std::string>& objects, uint64_t seed,
                         const std::string& split) {
  if (objects.empty()) throw std::runtime_error("the " + split + " split has no objects");
  std::mt19937_64 rng(seed);
  return objects[rng() % objects.size()];
}

void printEpisode(const mb::EpisodeResult& r) {
  std::cout << "object " << r.object_id << ", seed " << r.seed << ": " << r.steps << " steps, return "
            << std::fixed << std::setprecision(3) << r.total_reward << "\n";
  for (std::size_t i = 0; i < r.condition_names.size(); ++i)
    std::cout << "  " << std::left << std::setw(16) << r.condition_names[i]
              << (r.final_flags[i] ? "yes" : "no ") << "  (" << std::setprecision(4)
              << r.final_values[i] << ")\n";
  std::cout.unsetf(std::ios::fixed);
}


std::string formatDuration(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buffer[32];
  if (s >= 3600)
    std::snprintf(buffer, sizeof(buffer), "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  else
    std::snprintf(buffer, sizeof(buffer), "%02ld:%02ld", s / 60, s % 60);
  return buffer;
}

std::string formatProgressBar(std::size_t done, std::size_t total, int width) {
  const int filled = total ? int(std::size_t(width) * std::min(done, total) / total) : 0;
  std::string bar(std::size_t(filled), '#');
  bar.resize(std::size_t(width), '.');
  return "[" + bar + "] " + std::to_string(done) + "/" + std::to_string(total);
}

void drawProgressBar(std::size_t done, std::size_t total, const std::string& unit,
                     const std::string& details, double elapsed) {
  std::ostringstream line;
  line << "\r" << formatProgressBar(done, total) << " " << unit << details;
  if (done > 0 && total > done)
    line << ", ~" << formatDuration(elapsed / double(done) * double(total - done)) << " left";
  else
    line << ", " << formatDuration(elapsed) << " elapsed";
  line << "   ";
  std::cerr << line.str() << std::flush;
}

namespace {
volatile sig_atomic_t g_stop_requested = 0;
void onStopSignal(int) { g_stop_requested = 1; }
constexpr int kStopSignals[3] = {SIGINT, SIGTERM, SIGHUP};
}  // namespace

StopSignals::StopSignals() {
  g_stop_requested = 0;
  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: poll() and waits return at once
  for (int k = 0; k < 3; ++k) sigaction(kStopSignals[k], &action, &previous_[k]);
}

StopSignals::~StopSignals() {
  for (int k = 0; k < 3; ++k) sigaction(kStopSignals[k], &previous_[k], nullptr);
}

bool StopSignals::isRequested() { return g_stop_requested != 0; }

}  // namespace manibench::cli
