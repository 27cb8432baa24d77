// The configuration's validation against its schema (the table, one row
// per key: config_schema_table.cpp): types, bounds, unknown keys with the
// nearest one suggested, relations between keys, list-item defaults.
#include <manibench/config.hpp>
#include <manibench/sdk/numbers.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <sstream>

namespace manibench {
namespace {

using T = ConfigType;

// ---- helpers ---------------------------------------------------------------

std::string getParentPath(const std::string& path) {
  const std::size_t dot = path.rfind('.');
  return dot == std::string::npos ? "" : path.substr(0, dot);
}

std::string getLastKey(const std::string& path) {
  const std::size_t dot = path.rfind('.');
  return dot == std::string::npos ? path : path.substr(dot + 1);
}

std::string joinPath(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

// Keys directly below `schema_path` ("" for the top level), "*" excluded.
std::vector<std::string> getChildKeys(const std::string& schema_path) {
  std::vector<std::string> children;
  for (const ConfigKey& key : getConfigSchema())
    if (getParentPath(key.path) == schema_path && getLastKey(key.path) != "*")
      children.push_back(getLastKey(key.path));
  return children;
}

// The schema row for key `name` below `schema_parent`, allowing "*".
const ConfigKey* findChildKey(const std::string& schema_parent, const std::string& name) {
  if (const ConfigKey* key = findConfigKey(joinPath(schema_parent, name))) return key;
  return findConfigKey(joinPath(schema_parent, "*"));
}

// Edit distance counting a swap of neighbours as one edit (optimal string
// alignment), since "widht" is as likely a typo as "widt".
std::size_t calcEditDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1,
                          d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// Close enough to be a typo: a third of the word, at least one edit.
bool isCloseEnough(const std::string& typed, std::size_t distance) {
  return distance <= std::max<std::size_t>(1, std::min<std::size_t>(3, typed.size() / 3));
}

// The nearest of `candidates` to `typed`, or "" when none is close.
std::string findNearest(const std::string& typed, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const std::string& candidate : candidates) {
    const std::size_t d = calcEditDistance(typed, candidate);
    if (d < best_distance) {
      best = candidate;
      best_distance = d;
    }
  }
  return !best.empty() && isCloseEnough(typed, best_distance) ? best : "";
}

// A display path ("cameras[2].pose") as a schema path ("cameras[].pose").
std::string toSchemaPath(const std::string& display_path) {
  std::string out;
  for (std::size_t i = 0; i < display_path.size(); ++i) {
    if (display_path[i] == '[') {
      const std::size_t close = display_path.find(']', i);
      if (close == std::string::npos) break;
      out += "[]";
      i = close;
    } else {
      out += display_path[i];
    }
  }
  return out;
}

// Suggestion for unknown key `name` below schema path `schema_parent`
// (displayed as `display_parent`): a sibling with a similar name, else the
// key of that name elsewhere in the schema (a key at the wrong level).
std::string calcSuggestion(const std::string& schema_parent, const std::string& display_parent,
                           const std::string& name) {
  const std::string sibling = findNearest(name, getChildKeys(schema_parent));
  if (!sibling.empty()) return joinPath(display_parent, sibling);
  std::vector<std::string> elsewhere;
  for (const ConfigKey& key : getConfigSchema())
    if (getLastKey(key.path) == name) elsewhere.push_back(key.path);
  if (!elsewhere.empty()) return elsewhere.front();
  // A misspelled key at the wrong level: compare with every key's name.
  std::string best;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const ConfigKey& key : getConfigSchema()) {
    const std::size_t d = calcEditDistance(name, getLastKey(key.path));
    if (d < best_distance) {
      best = key.path;
      best_distance = d;
    }
  }
  return isCloseEnough(name, best_distance) ? best : "";
}

std::string formatNumber(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

std::string describeBounds(const ConfigKey& key) {
  const bool has_lower = std::isfinite(key.lower);
  const bool has_upper = std::isfinite(key.upper);
  if (has_lower && has_upper)
    return std::string("in ") + (key.lower_open ? "(" : "[") + formatNumber(key.lower) + ", " +
           formatNumber(key.upper) + (key.upper_open ? ")" : "]");
  if (has_lower) return (key.lower_open ? "> " : ">= ") + formatNumber(key.lower);
  if (has_upper) return (key.upper_open ? "< " : "<= ") + formatNumber(key.upper);
  return "";
}

bool isWithinBounds(const ConfigKey& key, double value) {
  if (std::isnan(value)) return false;
  if (key.lower_open ? !(value > key.lower) : !(value >= key.lower)) return false;
  if (key.upper_open ? !(value < key.upper) : !(value <= key.upper)) return false;
  return true;
}

// How a value reads in an error: the scalar as written, or its kind.
std::string describeValue(const ConfigNode& node) {
  switch (node.kind) {
    case ConfigNode::Kind::Null:
      return "null";
    case ConfigNode::Kind::Scalar:
      return node.quoted ? "the string \"" + node.scalar + "\"" : node.scalar;
    case ConfigNode::Kind::Sequence:
      return "a list of " + std::to_string(node.items.size());
    case ConfigNode::Kind::Map:
      return "a map";
  }
  return "?";
}

[[noreturn]] void fail(const ConfigOrigin& origin, const std::string& path, const std::string& problem) {
  throw ConfigError(origin.describe() + ": " + path + ": " + problem);
}

std::string describeType(const ConfigKey& key) {
  switch (key.type) {
    case T::Bool:
      return "true or false";
    case T::Int:
      return "an integer";
    case T::Number:
      return "a number";
    case T::String:
      return "a string";
    case T::Enum:
      return "one of the names listed";
    case T::Vector3:
      return "a list of 3 numbers [x, y, z]";
    case T::Color:
      return "a list of 3 or 4 numbers [r, g, b(, a)]";
    case T::Range:
      return "a list of 2 numbers [min, max]";
    case T::Map:
    case T::FreeMap:
      return "a map";
    case T::List:
      return "a list of maps";
  }
  return "?";
}

void checkNumber(const ConfigKey& key, const ConfigNode& node, const std::string& path,
                 const std::string& what) {
  const std::optional<double> value = calcNumber(node);
  if (!value) fail(node.origin, path, "must be " + what + ", got " + describeValue(node));
  if (!isWithinBounds(key, *value))
    fail(node.origin, path, "must be " + describeBounds(key) + ", got " + node.scalar);
}

void checkNumberList(const ConfigKey& key, const ConfigNode& node, const std::string& path,
                     std::size_t min_size, std::size_t max_size) {
  if (!node.isSequence() || node.items.size() < min_size || node.items.size() > max_size)
    fail(node.origin, path, "must be " + describeType(key) + ", got " + describeValue(node));
  for (std::size_t i = 0; i < node.items.size(); ++i)
    checkNumber(key, node.items[i], path + "[" + std::to_string(i) + "]", "a number");
  if (key.type == T::Range && *calcNumber(node.items[0]) > *calcNumber(node.items[1]))
    fail(node.origin, path, "min must not exceed max, got [" + node.items[0].scalar + ", " +
                                node.items[1].scalar + "]");
}

void checkValue(const ConfigKey& key, const ConfigNode& node, const std::string& schema_path,
                const std::string& path);

// The entries of a map against the keys below `schema_path`.
void checkMap(const ConfigNode& node, const std::string& schema_path, const std::string& path,
              bool is_list_item) {
  for (const ConfigEntry& e : node.entries) {
    const std::string child_path = joinPath(path, e.key);
    const ConfigKey* child = findChildKey(schema_path, e.key);
    if (child == nullptr) {
      const std::string suggestion = calcSuggestion(schema_path, path, e.key);
      fail(e.key_origin, child_path,
           "unknown key" + (suggestion.empty() ? "" : " (did you mean " + suggestion + "?)"));
    }
    checkValue(*child, e.value, child->path, child_path);
  }
  // Lists replace as a whole, so an item must be complete in its own layer.
  if (is_list_item)
    for (const ConfigKey& key : getConfigSchema())
      if (key.required && getParentPath(key.path) == schema_path &&
          node.find(getLastKey(key.path)) == nullptr)
        fail(node.origin, path, "missing required key '" + getLastKey(key.path) + "' (" +
                                    key.description + ")");
}

void checkValue(const ConfigKey& key, const ConfigNode& node, const std::string& schema_path,
                const std::string& path) {
  if (node.isNull() && (key.nullable || key.type == T::FreeMap)) return;
  switch (key.type) {
    case T::Bool:
      if (!calcBool(node)) fail(node.origin, path, "must be true or false, got " + describeValue(node));
      break;
    case T::Int: {
      const std::optional<int64_t> value = calcInt(node);
      if (!value) fail(node.origin, path, "must be an integer, got " + describeValue(node));
      if (!isWithinBounds(key, double(*value)))
        fail(node.origin, path, "must be " + describeBounds(key) + ", got " + node.scalar);
      break;
    }
    case T::Number:
      checkNumber(key, node, path, "a number");
      break;
    case T::String:
      if (!node.isScalar()) fail(node.origin, path, "must be a string, got " + describeValue(node));
      break;
    case T::Enum: {
      const bool known = node.isScalar() &&
                         std::find(key.choices.begin(), key.choices.end(), node.scalar) != key.choices.end();
      if (!known) {
        std::string choices;
        for (const std::string& c : key.choices) choices += (choices.empty() ? "" : ", ") + c;
        const std::string nearest = node.isScalar() ? findNearest(node.scalar, key.choices) : "";
        fail(node.origin, path, "must be one of " + choices + ", got " + describeValue(node) +
                                    (nearest.empty() ? "" : " (did you mean " + nearest + "?)"));
      }
      break;
    }
    case T::Vector3:
      checkNumberList(key, node, path, 3, 3);
      break;
    case T::Color:
      checkNumberList(key, node, path, 3, 4);
      break;
    case T::Range:
      checkNumberList(key, node, path, 2, 2);
      break;
    case T::Map:
      if (!node.isMap()) fail(node.origin, path, "must be a map, got " + describeValue(node));
      checkMap(node, schema_path, path, false);
      break;
    case T::List:
      if (!node.isSequence())
        fail(node.origin, path, "must be a list of maps, got " + describeValue(node));
      for (std::size_t i = 0; i < node.items.size(); ++i) {
        const ConfigNode& item = node.items[i];
        const std::string item_path = path + "[" + std::to_string(i) + "]";
        if (!item.isMap()) fail(item.origin, item_path, "must be a map, got " + describeValue(item));
        checkMap(item, schema_path + "[]", item_path, true);
      }
      break;
    case T::FreeMap:
      if (!node.isMap()) fail(node.origin, path, "must be a map, got " + describeValue(node));
      break;
  }
}

// ---- relations between keys --------------------------------------------------

// The value of `key` in the map `node`, else in `fallback` (may be null).
const ConfigNode* findEither(const ConfigNode& node, const ConfigNode* fallback, const std::string& key) {
  if (const ConfigNode* value = node.find(key)) return value;
  return fallback ? fallback->find(key) : nullptr;
}

// Simbody's contact model requires dynamic <= static friction.
void checkFrictionOrder(const ConfigNode& material, const ConfigNode* fallback,
                        const std::string& path) {
  const ConfigNode* stat = findEither(material, fallback, "static_friction");
  const ConfigNode* dyn = findEither(material, fallback, "dynamic_friction");
  if (stat == nullptr || dyn == nullptr) return;
  if (*calcNumber(*dyn) <= *calcNumber(*stat)) return;
  // Blame the value set most recently: one in this material before one it
  // inherits, then the higher layer; the dynamic one on a tie.
  const bool dyn_here = material.find("dynamic_friction") != nullptr;
  const bool stat_here = material.find("static_friction") != nullptr;
  const bool blame_static = (stat_here && !dyn_here) ||
                            (stat_here == dyn_here && stat->origin.layer > dyn->origin.layer);
  if (blame_static)
    fail(stat->origin, path + ".static_friction",
         "must be at least dynamic_friction (" + dyn->scalar + ", from " + dyn->origin.describe() +
             "), got " + stat->scalar);
  fail(dyn->origin, path + ".dynamic_friction",
       "must not exceed static_friction (" + stat->scalar + ", from " + stat->origin.describe() +
           "), got " + dyn->scalar);
}

double getItemNumber(const ConfigNode& item, const std::string& key, const std::string& schema_parent) {
  if (const ConfigNode* value = item.find(key)) return *calcNumber(*value);
  const ConfigKey* row = findConfigKey(schema_parent + "." + key);
  assert(row && !row->item_default.empty());
  return *calcNumber(parseConfig(row->item_default, "schema"));
}

void checkRelations(const ConfigNode& config) {
  const ConfigNode* fallback = config.findPath("physics.contact.default");
  if (fallback) checkFrictionOrder(*fallback, nullptr, "physics.contact.default");
  if (const ConfigNode* ground = config.findPath("physics.contact.ground"))
    checkFrictionOrder(*ground, fallback, "physics.contact.ground");
  if (const ConfigNode* bodies = config.findPath("physics.contact.bodies"))
    for (std::size_t i = 0; i < bodies->items.size(); ++i)
      checkFrictionOrder(bodies->items[i], fallback,
                         "physics.contact.bodies[" + std::to_string(i) + "]");

  if (const ConfigNode* lights = config.findPath("lights.directional"))
    for (std::size_t i = 0; i < lights->items.size(); ++i) {
      const ConfigNode& direction = *lights->items[i].find("direction");
      bool all_zero = true;
      for (const ConfigNode& c : direction.items) all_zero = all_zero && *calcNumber(c) == 0;
      if (all_zero)
        fail(direction.origin, "lights.directional[" + std::to_string(i) + "].direction",
             "must not be [0, 0, 0]");
    }

  if (const ConfigNode* cameras = config.find("cameras")) {
    std::map<std::string, std::string> seen;  // name -> where
    for (std::size_t i = 0; i < cameras->items.size(); ++i) {
      const ConfigNode& camera = cameras->items[i];
      const std::string path = "cameras[" + std::to_string(i) + "]";
      const ConfigNode& name = *camera.find("name");
      const auto [it, inserted] = seen.emplace(name.scalar, name.origin.describe());
      if (!inserted)
        fail(name.origin, path + ".name", "duplicate camera name '" + name.scalar + "' (also at " +
                                              it->second + ")");
      const ConfigNode* link = camera.find("link");
      const ConfigNode* articulation = camera.find("articulation");
      if (link && !link->isNull() && (!articulation || articulation->isNull()))
        fail(link->origin, path + ".link", "a mount link needs the articulation it belongs to");
      const double near = getItemNumber(camera, "near", "cameras[]");
      const double far = getItemNumber(camera, "far", "cameras[]");
      if (!(near < far)) {
        const ConfigNode* blamed = camera.find("far") ? camera.find("far") : camera.find("near");
        fail(blamed->origin, path + (camera.find("far") ? ".far" : ".near"),
             "near (" + formatNumber(near) + ") must be less than far (" + formatNumber(far) + ")");
      }
    }
  }
}

// ---- completion --------------------------------------------------------------

void completeMap(ConfigNode& node, const std::string& schema_path) {
  const ConfigOrigin builtin{ConfigLayer::Builtin, "built-in defaults", 0};
  for (const ConfigKey& key : getConfigSchema()) {
    if (getParentPath(key.path) != schema_path || key.item_default.empty() ||
        getLastKey(key.path) == "*")
      continue;
    const std::string name = getLastKey(key.path);
    if (node.find(name) == nullptr) {
      ConfigNode value = parseConfig(key.item_default, builtin.source, ConfigLayer::Builtin);
      // The default's origin is the schema, with no line to point at.
      ConfigNode& slot = node.updEntry(name, builtin);
      slot = std::move(value);
      std::vector<ConfigNode*> stack{&slot};
      while (!stack.empty()) {
        ConfigNode* n = stack.back();
        stack.pop_back();
        n->origin = builtin;
        for (ConfigNode& item : n->items) stack.push_back(&item);
        for (ConfigEntry& e : n->entries) {
          e.key_origin = builtin;
          stack.push_back(&e.value);
        }
      }
    }
  }
  for (ConfigEntry& e : node.entries) {
    const ConfigKey* key = findChildKey(schema_path, e.key);
    if (key == nullptr) continue;
    if (key->type == T::Map && e.value.isMap()) completeMap(e.value, key->path);
    if (key->type == T::List && e.value.isSequence())
      for (ConfigNode& item : e.value.items)
        if (item.isMap()) completeMap(item, key->path + "[]");
  }
}

}  // namespace

const ConfigKey* findConfigKey(const std::string& schema_path) {
  static const std::map<std::string, const ConfigKey*> index = [] {
    std::map<std::string, const ConfigKey*> m;
    for (const ConfigKey& key : getConfigSchema()) {
      const bool added = m.emplace(key.path, &key).second;
      assert(added && "duplicate key in the configuration schema");
      (void)added;
    }
    return m;
  }();
  const auto it = index.find(schema_path);
  return it == index.end() ? nullptr : it->second;
}

std::string findNearestConfigKey(const std::string& key_path) {
  const std::string schema_path = toSchemaPath(key_path);
  if (findConfigKey(schema_path)) return key_path;
  const std::size_t dot = key_path.rfind('.');
  const std::string display_parent = dot == std::string::npos ? "" : key_path.substr(0, dot);
  return calcSuggestion(toSchemaPath(display_parent), display_parent, getLastKey(key_path));
}

void validateConfig(const ConfigNode& config) {
  if (config.isNull()) return;  // an empty file
  if (!config.isMap())
    fail(config.origin, "(top level)", "a configuration must be a map of keys, got " + describeValue(config));
  checkMap(config, "", "", false);
  checkRelations(config);
}

void completeConfig(ConfigNode& config) {
  if (config.isMap()) completeMap(config, "");
}

}  // namespace manibench
