// Demonstration files of one generation combined (docs/distributed.md):
// shards of a job array, or a run cut short and its resumed rest. Which
// trajectories an object keeps does not depend on the other objects (its
// first per_object successful levels), but the order the single run writes
// them in does: round by round, each round as long as the neediest object
// needs. The merge replays those rounds from the kept levels.
#include <manibench/demos.hpp>

#include <algorithm>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

namespace manibench {
namespace {

using Json = nlohmann::ordered_json;

// One input file: its reader, its generation, what it says of its objects.
struct Input {
  std::unique_ptr<DemoReader> reader;
  Json generation;
  Json result;  // null when the file was cut short
  // object -> (level, trajectory name), levels ascending
  std::map<std::string, std::vector<std::pair<uint64_t, std::string>>> kept;
};

std::string shorten(const std::string& text) {
  return text.size() > 80 ? text.substr(0, 77) + "..." : text;
}

// "" when the two describe the same generation (shards apart); the
// controller, observation mode and plugins only when `all`.
std::string findDifference(const DemoFileInfo& x, const Json& x_generation, const DemoFileInfo& y,
                           const Json& y_generation, bool all) {
  const std::vector<std::pair<const char*, std::pair<std::string, std::string>>> fields = {
      {"task", {x.environment_id, y.environment_id}},
      {"manibench_version", {x.manibench_version, y.manibench_version}},
      {"controller", {x.controller, y.controller}},
      {"obs_mode", {toString(x.observation_mode), toString(y.observation_mode)}},
      {"policy", {x.policy, y.policy}},
      {"config", {x.config, y.config}},
      {"plugins", {x.plugins, y.plugins}}};
  for (const auto& [name, values] : fields)
    if (values.first != values.second && (all || std::string(name) == "task" || std::string(name) == "policy" ||
                                          std::string(name) == "config"))
      return std::string(name) + ": '" + shorten(values.first) + "' vs '" + shorten(values.second) + "'";
  for (const auto& [key, value] : x_generation.items()) {
    if (all && (key == "shard" || key == "shards")) continue;
    if (!y_generation.contains(key) || y_generation.at(key) != value)
      return key + ": " + shorten(value.dump()) + " vs " +
             shorten(y_generation.contains(key) ? y_generation.at(key).dump() : "nothing");
  }
  return "";
}

Input openInput(const std::string& path) {
  Input in;
  in.reader = std::make_unique<DemoReader>(path);
  const DemoFileInfo& info = in.reader->getInfo();
  if (info.generation.empty())
    throw DemoError("'" + path + "' was not made by `demos generate` (no generation attribute)");
  in.generation = Json::parse(info.generation);
  if (!info.generation_result.empty()) in.result = Json::parse(info.generation_result);
  for (const std::string& name : in.reader->getTrajectoryNames()) {
    const Trajectory t = in.reader->readSummary(name);
    in.kept[t.object_id].emplace_back(t.level, name);
  }
  for (auto& [object, levels] : in.kept) std::sort(levels.begin(), levels.end());
  return in;
}

// Whether the file has all `object` can get: the run said so when it
// closed, or it has its trajectories.
bool isDone(const Input& in, const std::string& object, uint32_t per_object) {
  if (!in.result.is_null() && in.result.at("objects").contains(object))
    return in.result.at("objects").at(object).at("done").get<bool>();
  const auto at = in.kept.find(object);
  return at != in.kept.end() && at->second.size() >= per_object;
}

}  // namespace

DemoMergeResult mergeDemonstrations(const std::vector<std::string>& inputs, const std::string& out_path,
                                    const DemoFileInfo& out_info_base, uint32_t shard, uint32_t shards) {
  if (inputs.empty()) throw DemoError("nothing to merge");
  std::vector<Input> files;
  for (const std::string& path : inputs) files.push_back(openInput(path));
  for (std::size_t f = 1; f < files.size(); ++f) {
    const std::string difference = findDifference(files[0].reader->getInfo(), files[0].generation,
                                                  files[f].reader->getInfo(), files[f].generation, true);
    if (!difference.empty())
      throw DemoError("'" + inputs[f] + "' is of another generation than '" + inputs[0] + "': " + difference);
  }
  const Json& generation = files[0].generation;
  const uint32_t per_object = generation.at("per_object");
  const uint32_t max_attempts = generation.at("max_attempts");
  const std::vector<std::string> all = generation.at("objects").get<std::vector<std::string>>();
  std::vector<std::string> objects;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (i % shards == shard) objects.push_back(all[i]);

  // Each object's trajectories come from the file that has it done (a
  // partial copy elsewhere, from a run cut short, is dropped), else from
  // the file with the most of them.
  DemoMergeResult merged;
  std::map<std::string, std::pair<int, bool>> source;  // object -> (file, done)
  for (const std::string& object : objects) {
    int chosen = -1;
    bool done = false;
    for (std::size_t f = 0; f < files.size(); ++f) {
      const bool here = isDone(files[f], object, per_object);
      if (here && done)
        throw DemoError("object " + object + " is done in both '" + inputs[std::size_t(chosen)] + "' and '" +
                        inputs[f] + "'");
      const std::size_t count = files[f].kept.count(object) ? files[f].kept.at(object).size() : 0;
      const std::size_t best =
          chosen >= 0 && files[std::size_t(chosen)].kept.count(object) ? files[std::size_t(chosen)].kept.at(object).size() : 0;
      if (here || (!done && count > best)) chosen = int(f);
      done = done || here;
    }
    source[object] = {chosen, done};
    if (done) {
      merged.done_objects.push_back(object);
    } else {
      const std::size_t have = chosen >= 0 && files[std::size_t(chosen)].kept.count(object)
                                   ? files[std::size_t(chosen)].kept.at(object).size()
                                   : 0;
      merged.missing.push_back("object " + object + ": " + std::to_string(have) + " of " +
                               std::to_string(per_object) + " trajectories, not finished");
    }
  }
  auto keptOf = [&](const std::string& object) -> const std::vector<std::pair<uint64_t, std::string>>* {
    const int f = source.at(object).first;
    if (f < 0 || !files[std::size_t(f)].kept.count(object)) return nullptr;
    return &files[std::size_t(f)].kept.at(object);
  };

  // The single run's rounds: levels [next, next + count) of every object
  // still needing trajectories, count the most any of them needs.
  std::vector<std::pair<int, std::string>> order;  // (file, trajectory name)
  std::map<std::string, uint32_t> kept;
  std::vector<std::string> active = objects;
  uint64_t next = 0;
  uint64_t count = std::min<uint64_t>(per_object, max_attempts);
  while (!active.empty() && count > 0) {
    for (const std::string& object : active)
      if (const auto* levels = keptOf(object))
        for (const auto& [level, name] : *levels)
          if (level >= next && level < next + count && kept[object] < per_object) {
            order.emplace_back(source.at(object).first, name);
            ++kept[object];
          }
    next += count;
    std::vector<std::string> needy;
    uint64_t most_needed = 0;
    for (const std::string& object : active)
      if (kept[object] < per_object && next < max_attempts) {
        needy.push_back(object);
        most_needed = std::max<uint64_t>(most_needed, per_object - kept[object]);
      }
    active = std::move(needy);
    count = std::min<uint64_t>(most_needed, max_attempts - next);
  }

  DemoFileInfo info = files[0].reader->getInfo();
  info.created = out_info_base.created;
  info.command = out_info_base.command;
  Json out_generation = generation;
  out_generation["shard"] = shard;
  out_generation["shards"] = shards;
  info.generation = out_generation.dump();
  info.generation_result.clear();
  DemoWriter writer(out_path, info);
  for (const auto& [f, name] : order) writer.append(files[std::size_t(f)].reader->read(name));
  merged.trajectories = writer.getCount();
  Json result;
  result["interrupted"] = !merged.missing.empty();
  Json per = Json::object();
  for (const std::string& object : objects) {
    const auto [f, done] = source.at(object);
    Json o = {{"attempts", 0}, {"kept", kept[object]}, {"failures", 0}, {"done", done}};
    if (f >= 0 && !files[std::size_t(f)].result.is_null() && files[std::size_t(f)].result.at("objects").contains(object)) {
      o["attempts"] = files[std::size_t(f)].result.at("objects").at(object).at("attempts");
      o["failures"] = files[std::size_t(f)].result.at("objects").at(object).at("failures");
    }
    per[object] = o;
  }
  result["objects"] = per;
  writer.close(result.dump());
  return merged;
}

std::vector<std::string> findDoneObjects(const std::string& path) {
  const Input in = openInput(path);
  const uint32_t per_object = in.generation.at("per_object");
  std::vector<std::string> done;
  for (const std::string& object : in.generation.at("objects").get<std::vector<std::string>>())
    if (isDone(in, object, per_object)) done.push_back(object);
  return done;
}

std::string findGenerationDifference(const std::string& path, const DemoFileInfo& info) {
  const DemoReader reader(path);
  if (reader.getInfo().generation.empty())
    throw DemoError("'" + path + "' was not made by `demos generate` (no generation attribute)");
  return findDifference(reader.getInfo(), Json::parse(reader.getInfo().generation), info,
                        Json::parse(info.generation), false);
}

}  // namespace manibench
