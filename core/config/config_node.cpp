// ConfigNode: parsing YAML with origins, command-line overrides, deep
// merge, scalar conversions and printing.
#include <manibench/config.hpp>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

namespace manibench {

std::string ConfigOrigin::describe() const {
  return line > 0 ? source + ":" + std::to_string(line) : source;
}

const ConfigNode* ConfigNode::find(const std::string& key) const {
  if (!isMap()) return nullptr;
  for (const ConfigEntry& e : entries)
    if (e.key == key) return &e.value;
  return nullptr;
}

ConfigNode* ConfigNode::upd(const std::string& key) {
  return const_cast<ConfigNode*>(static_cast<const ConfigNode*>(this)->find(key));
}

const ConfigNode* ConfigNode::findPath(const std::string& path) const {
  const ConfigNode* node = this;
  std::size_t begin = 0;
  while (node != nullptr) {
    const std::size_t dot = path.find('.', begin);
    node = node->find(path.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin));
    if (dot == std::string::npos) return node;
    begin = dot + 1;
  }
  return nullptr;
}

ConfigNode& ConfigNode::updEntry(const std::string& key, const ConfigOrigin& key_origin) {
  assert(isMap() && "updEntry on a node that is not a map");
  if (ConfigNode* existing = upd(key)) return *existing;
  entries.push_back({key, key_origin, ConfigNode{}});
  return entries.back().value;
}

namespace {

// yaml-cpp marks implicit nulls ("key:" with nothing after it) with no
// position; they belong to the line of their key.
int getLine(const YAML::Mark& mark, int fallback) {
  return mark.line >= 0 ? mark.line + 1 : fallback;
}

// What a configuration may hold: no real one comes near, and an alias
// bomb ("billion laughs": aliases repeating aliases) would otherwise expand
// for minutes.
constexpr std::size_t kMaxValues = 100000;
constexpr int kMaxDepth = 64;

struct Budget {
  std::size_t values = 0;
  int depth = 0;
};

ConfigNode convertNode(const YAML::Node& node, const ConfigOrigin& parent, Budget& budget) {
  ConfigNode out;
  out.origin = parent;
  out.origin.line = getLine(node.Mark(), parent.line);
  if (++budget.values > kMaxValues)
    throw ConfigError(out.origin.describe() + ": the configuration expands to more than " +
                      std::to_string(kMaxValues) + " values (aliases repeating aliases?)");
  if (budget.depth >= kMaxDepth)
    throw ConfigError(out.origin.describe() + ": nested deeper than " + std::to_string(kMaxDepth) + " levels");
  struct Deeper {
    Budget& b;
    explicit Deeper(Budget& budget) : b(budget) { ++b.depth; }
    ~Deeper() { --b.depth; }
  } deeper(budget);
  switch (node.Type()) {
    case YAML::NodeType::Undefined:
    case YAML::NodeType::Null:
      out.kind = ConfigNode::Kind::Null;
      break;
    case YAML::NodeType::Scalar:
      out.kind = ConfigNode::Kind::Scalar;
      out.scalar = node.Scalar();
      // "!" is yaml-cpp's tag for quoted scalars; an explicit !!str means the same.
      out.quoted = node.Tag() == "!" || node.Tag() == "tag:yaml.org,2002:str";
      break;
    case YAML::NodeType::Sequence:
      out.kind = ConfigNode::Kind::Sequence;
      for (const YAML::Node& item : node) out.items.push_back(convertNode(item, out.origin, budget));
      break;
    case YAML::NodeType::Map:
      out.kind = ConfigNode::Kind::Map;
      for (auto it = node.begin(); it != node.end(); ++it) {
        ConfigOrigin key_origin = out.origin;
        key_origin.line = getLine(it->first.Mark(), out.origin.line);
        if (!it->first.IsScalar())
          throw ConfigError(key_origin.describe() + ": keys must be plain words, not " +
                            (it->first.IsMap() ? "maps" : it->first.IsSequence() ? "sequences" : "null"));
        const std::string key = it->first.Scalar();
        if (out.find(key) != nullptr)
          throw ConfigError(key_origin.describe() + ": duplicate key '" + key + "'");
        out.entries.push_back({key, key_origin, convertNode(it->second, key_origin, budget)});
      }
      break;
  }
  return out;
}

// Every part of `node` gets `line` (0 for a --set value, whose "line 1" is noise).
void setLine(ConfigNode& node, int line) {
  node.origin.line = line;
  for (ConfigNode& item : node.items) setLine(item, line);
  for (ConfigEntry& e : node.entries) {
    e.key_origin.line = line;
    setLine(e.value, line);
  }
}

bool isKeyCharacter(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
}

// yaml-cpp 0.7 never returns from a document whose first token is ','
// (it allocates nodes until memory runs out; found by tests/fuzz): the line
// of such a document's start, or 0.
int findCommaStartingADocument(const std::string& text) {
  bool at_document_start = true;
  int line = 0;
  std::istringstream lines(text);
  std::string content;
  while (std::getline(lines, content)) {
    ++line;
    if (content.rfind("---", 0) == 0) {
      at_document_start = true;
      content = content.substr(3);
    }
    if (!at_document_start) continue;
    const std::size_t first = content.find_first_not_of(" \t\r");
    if (first == std::string::npos || content[first] == '#' || content[first] == '%') continue;
    if (content[first] == ',') return line;
    at_document_start = false;
  }
  return 0;
}

}  // namespace

ConfigNode parseConfig(const std::string& yaml_text, const std::string& source, ConfigLayer layer) {
  if (const int line = findCommaStartingADocument(yaml_text))
    throw ConfigError(ConfigOrigin{layer, source, line}.describe() +
                      ": malformed YAML: a document cannot start with ','");
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(yaml_text);
  } catch (const YAML::ParserException& e) {
    // yaml-cpp gives up on deep flow nesting with "bad file": say why.
    int depth = 0, deepest = 0;
    for (char c : yaml_text) {
      if (c == '[' || c == '{') deepest = std::max(deepest, ++depth);
      if (c == ']' || c == '}') --depth;
    }
    if (deepest > kMaxDepth)
      throw ConfigError(ConfigOrigin{layer, source, e.mark.line + 1}.describe() + ": nested deeper than " +
                        std::to_string(kMaxDepth) + " levels (" + std::to_string(deepest) + " brackets)");
    throw ConfigError(ConfigOrigin{layer, source, e.mark.line + 1}.describe() +
                      ": malformed YAML: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source + ": malformed YAML: " + e.msg);
  }
  ConfigOrigin origin{layer, source, 1};
  if (documents.size() > 1) {
    origin.line = getLine(documents[1].Mark(), 1);
    throw ConfigError(origin.describe() + ": a configuration is one YAML document, this is the second");
  }
  if (documents.empty()) return ConfigNode{ConfigNode::Kind::Null, "", false, {}, {}, origin};
  Budget budget;
  return convertNode(documents.front(), origin, budget);
}

ConfigNode loadConfigFile(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error))
    throw ConfigError("configuration file '" + path + "' is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError("cannot read configuration file '" + path + "': " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError("cannot read configuration file '" + path + "': read error");
  return parseConfig(text.str(), path, ConfigLayer::File);
}

ConfigNode parseConfigOverride(const std::string& assignment) {
  const std::string source = "--set " + assignment;
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos)
    throw ConfigError(source + ": expected KEY=VALUE, e.g. --set physics.accuracy=0.001");
  const std::string path = assignment.substr(0, eq);
  const std::string value_text = assignment.substr(eq + 1);
  // The key path: dot-separated words. List items cannot be addressed,
  // since lists replace as a whole.
  std::vector<std::string> keys;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t dot = path.find('.', begin);
    keys.push_back(path.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin));
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }
  for (const std::string& key : keys) {
    if (key.empty()) throw ConfigError(source + ": the key path '" + path + "' has an empty part");
    if (key.find('[') != std::string::npos)
      throw ConfigError(source + ": list items cannot be set one by one; give the whole list, "
                                 "e.g. --set cameras=[{name: a, width: 64, height: 64}]");
    for (char c : key)
      if (!isKeyCharacter(c))
        throw ConfigError(source + ": the key path '" + path + "' has the character '" +
                          std::string(1, c) + "' (keys are letters, digits, '_' and '-')");
  }
  ConfigNode value;
  try {
    value = parseConfig(value_text, source, ConfigLayer::Override);
  } catch (const ConfigError& e) {
    // parseConfig names "source:line"; a one-line value has no useful line.
    std::string message = e.what();
    const std::string prefix = source + ":1";
    if (message.rfind(prefix, 0) == 0) message = source + message.substr(prefix.size());
    throw ConfigError(message);
  }
  setLine(value, 0);
  const ConfigOrigin origin{ConfigLayer::Override, source, 0};
  value.origin = origin;
  for (auto key = keys.rbegin(); key != keys.rend(); ++key) {
    ConfigNode parent;
    parent.kind = ConfigNode::Kind::Map;
    parent.origin = origin;
    parent.entries.push_back({*key, origin, std::move(value)});
    value = std::move(parent);
  }
  return value;
}

void mergeConfig(ConfigNode& base, const ConfigNode& layer) {
  if (!base.isMap() || !layer.isMap()) {
    base = layer;
    return;
  }
  for (const ConfigEntry& e : layer.entries) {
    if (ConfigNode* existing = base.upd(e.key))
      mergeConfig(*existing, e.value);
    else
      base.entries.push_back(e);
  }
}

bool isSameConfig(const ConfigNode& a, const ConfigNode& b) {
  if (a.kind != b.kind) return false;
  switch (a.kind) {
    case ConfigNode::Kind::Null:
      return true;
    case ConfigNode::Kind::Scalar:
      return a.scalar == b.scalar && a.quoted == b.quoted;
    case ConfigNode::Kind::Sequence:
      if (a.items.size() != b.items.size()) return false;
      for (std::size_t i = 0; i < a.items.size(); ++i)
        if (!isSameConfig(a.items[i], b.items[i])) return false;
      return true;
    case ConfigNode::Kind::Map:
      if (a.entries.size() != b.entries.size()) return false;
      for (const ConfigEntry& e : a.entries) {
        const ConfigNode* other = b.find(e.key);
        if (other == nullptr || !isSameConfig(e.value, *other)) return false;
      }
      return true;
  }
  return false;
}

// ---- scalars -------------------------------------------------------------

std::optional<bool> calcBool(const ConfigNode& node) {
  if (!node.isScalar() || node.quoted) return std::nullopt;
  const std::string& s = node.scalar;
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  return std::nullopt;
}

std::optional<int64_t> calcInt(const ConfigNode& node) {
  if (!node.isScalar() || node.quoted || node.scalar.empty()) return std::nullopt;
  const std::string& s = node.scalar;
  int base = 10;
  std::size_t start = 0;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'o')) {
    base = s[1] == 'x' ? 16 : 8;
    start = 2;
  } else if (s[0] == '+') {
    if (s.size() == 1 || s[1] == '-') return std::nullopt;
    start = 1;  // from_chars takes '-' but not '+'
  }
  int64_t value = 0;
  const char* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data() + start, end, value, base);
  if (ec != std::errc() || ptr != end || (base != 10 && s[start] == '-')) return std::nullopt;
  return value;
}

std::optional<double> calcNumber(const ConfigNode& node) {
  if (!node.isScalar() || node.quoted) return std::nullopt;
  if (const std::optional<int64_t> i = calcInt(node)) return double(*i);
  // YAML 1.2 core schema floats.
  static const std::regex kFloat(R"([-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?)");
  static const std::regex kInf(R"([-+]?\.(inf|Inf|INF))");
  static const std::regex kNan(R"(\.(nan|NaN|NAN))");
  const std::string& s = node.scalar;
  if (std::regex_match(s, kFloat)) return std::strtod(s.c_str(), nullptr);
  if (std::regex_match(s, kInf))
    return s[0] == '-' ? -std::numeric_limits<double>::infinity()
                       : std::numeric_limits<double>::infinity();
  if (std::regex_match(s, kNan)) return std::numeric_limits<double>::quiet_NaN();
  return std::nullopt;
}

// ---- printing ------------------------------------------------------------

namespace {

bool isScalarSequence(const ConfigNode& node) {
  for (const ConfigNode& item : node.items)
    if (!item.isScalar() && !item.isNull()) return false;
  return true;
}

void emitNode(YAML::Emitter& out, const ConfigNode& node, bool with_origins);

void emitOrigin(YAML::Emitter& out, const ConfigNode& node, bool with_origins) {
  if (with_origins) out << YAML::Comment(node.origin.describe());
}

void emitNode(YAML::Emitter& out, const ConfigNode& node, bool with_origins) {
  switch (node.kind) {
    case ConfigNode::Kind::Null:
      out << YAML::Null;
      emitOrigin(out, node, with_origins);
      break;
    case ConfigNode::Kind::Scalar:
      if (node.quoted) out << YAML::DoubleQuoted;
      out << node.scalar;
      emitOrigin(out, node, with_origins);
      break;
    case ConfigNode::Kind::Sequence:
      // Short vectors ([x, y, z], colors, ranges) read best on one line.
      if (isScalarSequence(node)) {
        out << YAML::Flow << YAML::BeginSeq;
        for (const ConfigNode& item : node.items) emitNode(out, item, false);
        out << YAML::EndSeq;
        emitOrigin(out, node, with_origins);
      } else {
        out << YAML::Block << YAML::BeginSeq;
        for (const ConfigNode& item : node.items) emitNode(out, item, with_origins);
        out << YAML::EndSeq;
      }
      break;
    case ConfigNode::Kind::Map:
      if (node.entries.empty()) {
        out << YAML::Flow << YAML::BeginMap << YAML::EndMap;
        emitOrigin(out, node, with_origins);
        break;
      }
      out << YAML::Block << YAML::BeginMap;
      for (const ConfigEntry& e : node.entries) {
        out << YAML::Key << e.key << YAML::Value;
        emitNode(out, e.value, with_origins);
      }
      out << YAML::EndMap;
      break;
  }
}

}  // namespace

std::string formatConfig(const ConfigNode& config, bool with_origins) {
  YAML::Emitter out;
  out.SetIndent(2);
  out.SetNullFormat(YAML::LowerNull);  // "null" reads better than "~"
  emitNode(out, config, with_origins);
  assert(out.good() && "the emitter refused a configuration tree");
  std::string text = out.c_str();
  if (!text.empty() && text.back() != '\n') text += '\n';
  return text;
}

}  // namespace manibench
