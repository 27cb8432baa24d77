// The YAML configuration (supplement B.6): layers merged in order of
// precedence, a declarative schema that checks them, and the mapping of the
// result onto EnvironmentOptions.
//
//   built-in defaults < task description < task YAML (default_config)
//     < --config FILE (in the order given) < --set KEY=VALUE (in order)
//
// Maps merge key by key; scalars, sequences and null replace. Every value
// keeps its origin (file and line, "--set ...", "task X-v0 defaults", ...)
// so that an error or `manibench config --explain` can say where it came
// from. docs/configuration.md lists every key.
#pragma once

#include <manibench/environment_options.hpp>
#include <manibench/error.hpp>
#include <manibench/plugin_instances.hpp>
#include <manibench/plugin_registry.hpp>

#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench {

// The layers, lowest first.
enum class ConfigLayer { Builtin, TaskDescription, Task, File, Override };

// Where a configuration value was written.
struct ConfigOrigin {
  ConfigLayer layer = ConfigLayer::Builtin;
  std::string source;  // a file path, "--set KEY=VALUE", "built-in defaults", ...
  int line = 0;        // 1-based; 0 where the source has no lines
  // "source:line", or just "source".
  std::string describe() const;
};

// Bad configuration: unreadable file, malformed YAML, unknown key, wrong
// type, out-of-range value. The message starts with "origin: key.path: ".
class ConfigError : public Error {
 public:
  using Error::Error;
};

struct ConfigEntry;

// A YAML value that remembers where each of its parts came from.
struct ConfigNode {
  enum class Kind { Null, Scalar, Sequence, Map };
  Kind kind = Kind::Null;
  std::string scalar;    // Scalar: the text as written (without quotes)
  bool quoted = false;   // Scalar: written in quotes, hence always a string
  std::vector<ConfigNode> items;     // Sequence
  std::vector<ConfigEntry> entries;  // Map, in the order first written
  ConfigOrigin origin;

  bool isNull() const { return kind == Kind::Null; }
  bool isScalar() const { return kind == Kind::Scalar; }
  bool isSequence() const { return kind == Kind::Sequence; }
  bool isMap() const { return kind == Kind::Map; }
  // Map lookup; nullptr when absent or not a map.
  const ConfigNode* find(const std::string& key) const;
  ConfigNode* upd(const std::string& key);
  // Lookup by dotted path ("physics.accuracy"); nullptr when absent.
  const ConfigNode* findPath(const std::string& path) const;
  // Sets `key` (replacing an existing entry in place, else appending).
  ConfigNode& updEntry(const std::string& key, const ConfigOrigin& key_origin);
};

struct ConfigEntry {
  std::string key;
  ConfigOrigin key_origin;
  ConfigNode value;
};

// Parses YAML text; `source` names it in origins and errors. A syntax
// error, a duplicate key or a non-scalar key is a ConfigError "source:line: ...".
ConfigNode parseConfig(const std::string& yaml_text, const std::string& source,
                       ConfigLayer layer = ConfigLayer::File);
// Reads and parses a file; an unreadable file is a ConfigError.
ConfigNode loadConfigFile(const std::string& path);
// One command-line override "a.b.c=VALUE": VALUE is parsed as YAML (a
// scalar, or a flow sequence or map such as [0, 0, -9.81] or {k: v}); an
// empty VALUE is null. Returns the partial tree {a: {b: {c: VALUE}}}.
ConfigNode parseConfigOverride(const std::string& assignment);

// Deep merge of `layer` over `base`: maps merge key by key, anything else
// (scalar, sequence, null) replaces, origins included.
void mergeConfig(ConfigNode& base, const ConfigNode& layer);
// Same structure and scalar text (origins ignored).
bool isSameConfig(const ConfigNode& a, const ConfigNode& b);
// YAML text; with `with_origins`, each value carries a comment naming its origin.
std::string formatConfig(const ConfigNode& config, bool with_origins = false);

// Scalar conversions by the YAML 1.2 core schema; nullopt when the node is
// not a scalar of that type (quoted scalars are strings only).
std::optional<bool> calcBool(const ConfigNode& node);
std::optional<int64_t> calcInt(const ConfigNode& node);
std::optional<double> calcNumber(const ConfigNode& node);

// ---- schema --------------------------------------------------------------

enum class ConfigType {
  Bool,
  Int,
  Number,
  String,
  Enum,     // a string from `choices`
  Vector3,  // [x, y, z], each within the bounds
  Color,    // [r, g, b] or [r, g, b, a], each within the bounds
  Range,    // [low, high], low <= high, both within the bounds
  Map,      // keys described by entries below this path
  List,     // a sequence of maps, described by entries below "path[]"
  FreeMap,  // any map, passed through as YAML text (task, controller_config)
};

// One key of the schema.
struct ConfigKey {
  // Dotted path; "[]" stands for every item of a list, "*" for any map key
  // ("cameras[].width", "layouts.*.distance").
  std::string path;
  ConfigType type = ConfigType::String;
  std::string description;
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool lower_open = false;  // lower bound excluded
  bool upper_open = false;
  std::vector<std::string> choices;  // Enum
  bool nullable = false;             // null is a valid value
  bool required = false;             // must be present in its list item
  // Value filled into list items that omit the key (YAML text); empty: none.
  std::string item_default;
};

const std::vector<ConfigKey>& getConfigSchema();
// The key at `schema_path` ("cameras[].width"); nullptr when unknown.
const ConfigKey* findConfigKey(const std::string& schema_path);
// The known key nearest to `key_path` (a typo, or a key at the wrong
// level), as a full path; empty when nothing is close.
std::string findNearestConfigKey(const std::string& key_path);
// Checks a layer or a merged configuration against the schema, including
// relations between keys; throws ConfigError "origin: key.path: problem".
void validateConfig(const ConfigNode& config);
// Fills the keys that list items omitted with their schema defaults.
void completeConfig(ConfigNode& config);

// ---- layers --------------------------------------------------------------

// The lowest layer: every key with its default (source "built-in defaults").
const std::string& getBuiltinConfigText();
ConfigNode calcBuiltinConfig();
// The task's layer: its description (frequency, frame skip, episode length,
// controller and controller config; source "task NAME description"), under
// its default_config YAML (source "task NAME defaults").
ConfigNode makeTaskConfigLayer(const TaskDescription& task);

// The user's layers, in the order given on the command line.
struct ConfigSources {
  std::vector<std::string> files;      // --config FILE
  std::vector<std::string> overrides;  // --set KEY=VALUE
};

// Merges the built-in defaults, `task` (when not null) and `sources`,
// validating each layer as it comes and the result as a whole.
ConfigNode calcConfig(const TaskDescription* task, const ConfigSources& sources);
// calcConfig for the task registered as `task_name`, or the task of a
// fixed-object id (manibench/task_name.hpp). The task is created
// once with an empty configuration to read its description, so a task must
// accept an empty configuration and describe itself independently of it.
ConfigNode loadTaskConfig(const PluginRegistry& registry, const std::string& task_name,
                          const ConfigSources& sources);

// The environment a merged configuration (from calcConfig or loadTaskConfig)
// asks for. Values that only repeat the task's description stay unset, so
// that the task instance's own values apply. Throws ConfigError for values
// the scene cannot honour yet (sideways gravity, per-body materials).
EnvironmentOptions calcEnvironmentOptions(const ConfigNode& config);

// A plugin's error message, followed by where each key of the `task` or
// `control.controller_config` map that it names was set, since the line
// numbers a plugin reports refer to the text it was handed, not to any file.
std::string annotatePluginError(const ConfigNode& config, const std::string& message);

}  // namespace manibench
