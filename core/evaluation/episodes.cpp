// The episode list of an evaluation: which (object, level) pairs run, and
// each one's seed.
#include <algorithm>
#include <cctype>
#include <manibench/evaluation.hpp>
#include <stdexcept>

#ifndef MANIBENCH_VERSION
#define MANIBENCH_VERSION "unknown"
#endif

namespace manibench {

const char* getManibenchVersion() { return MANIBENCH_VERSION; }

namespace {

uint64_t mixSplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// FNV-1a: the same on every platform, unlike std::hash.
uint64_t hashString(const std::string& text) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : text) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

uint64_t parseLevel(const std::string& text, const std::string& whole) {
  if (text.empty() ||
      !std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c); }))
    throw InvalidArgument("levels '" + whole + "': '" + text +
                                "' is not a non-negative integer");
  try {
    return std::stoull(text);
  } catch (const std::exception&) {
    throw InvalidArgument("levels '" + whole + "': '" + text + "' is too large");
  }
}

std::vector<std::string> splitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    // Surrounding blanks are forgiven ("3, 7").
    const auto first = part.find_first_not_of(" \t");
    const auto last = part.find_last_not_of(" \t");
    parts.push_back(first == std::string::npos ? "" : part.substr(first, last - first + 1));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return parts;
}

}  // namespace

uint64_t calcEpisodeSeed(uint64_t seed, const std::string& object_id, uint64_t level) {
  const uint64_t h = mixSplitMix64(mixSplitMix64(seed ^ hashString(object_id)) + level);
  return h >> 32;
}

std::vector<EpisodeSpec> makeEpisodeList(const std::vector<std::string>& objects,
                                         const std::vector<uint64_t>& levels, uint64_t seed) {
  std::vector<EpisodeSpec> list;
  list.reserve(objects.size() * levels.size());
  for (const std::string& object : objects)
    for (uint64_t level : levels) {
      EpisodeSpec spec;
      spec.index = list.size();
      spec.object_id = object;
      spec.level = level;
      spec.seed = calcEpisodeSeed(seed, object, level);
      list.push_back(spec);
    }
  return list;
}

std::vector<uint64_t> parseLevels(const std::string& text) {
  std::vector<uint64_t> levels;
  for (const std::string& part : splitCommas(text)) {
    if (part.empty()) throw InvalidArgument("levels '" + text + "': empty entry");
    const std::size_t dash = part.find('-');
    if (dash == std::string::npos) {
      levels.push_back(parseLevel(part, text));
      continue;
    }
    const uint64_t first = parseLevel(part.substr(0, dash), text);
    const uint64_t last = parseLevel(part.substr(dash + 1), text);
    if (last < first)
      throw InvalidArgument("levels '" + text + "': range '" + part + "' is backwards");
    if (last - first >= 1000000)
      throw InvalidArgument("levels '" + text + "': range '" + part + "' is too long");
    for (uint64_t level = first; level <= last; ++level) levels.push_back(level);
  }
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  return levels;
}

void parseShard(const std::string& text, uint32_t& shard, uint32_t& shards) {
  const std::size_t slash = text.find('/');
  const std::string bad = "shard '" + text + "': ";
  if (slash == std::string::npos) throw InvalidArgument(bad + "not I/N (e.g. 2/3)");
  auto number = [&](const std::string& part) -> uint64_t {
    if (part.empty() || part.size() > 6 ||
        !std::all_of(part.begin(), part.end(), [](unsigned char c) { return std::isdigit(c); }))
      throw InvalidArgument(bad + "'" + part + "' is not a number (I/N, e.g. 2/3)");
    return std::stoull(part);
  };
  const uint64_t i = number(text.substr(0, slash));
  const uint64_t n = number(text.substr(slash + 1));
  if (n < 1 || n > 100000) throw InvalidArgument(bad + "N must be 1 to 100000");
  if (i < 1 || i > n) throw InvalidArgument(bad + "I must be 1 to N");
  shard = uint32_t(i - 1);
  shards = uint32_t(n);
}

std::vector<std::string> parseIdList(const std::string& text) {
  std::vector<std::string> ids;
  for (const std::string& part : splitCommas(text)) {
    if (part.empty()) throw InvalidArgument("object list '" + text + "': empty entry");
    if (std::find(ids.begin(), ids.end(), part) == ids.end()) ids.push_back(part);
  }
  return ids;
}

}  // namespace manibench
