// An evaluation's journal (docs/distributed.md, "Journal"): JSON lines, the
// run's description first, then every finished episode with its exact
// numbers (doubles round-trip through nlohmann's shortest representation).
// Shards and resumed runs are merged from journals, not from the CSV files,
// whose rounded returns would not give the single run's means bit for bit.
#include <cmath>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <manibench/evaluation.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "journal_writer.hpp"
#include "messages.hpp"

namespace manibench {
namespace {

using Json = nlohmann::ordered_json;
constexpr int kJournalFormat = 1;

// The whole list's objects: those given, or the split's.
std::vector<std::string> getPlannedObjects(const EvaluationResult& result) {
  return result.options.objects.empty() ? result.task.split_objects : result.options.objects;
}

// Messages come from policies: bytes that are not UTF-8 go as hex, so that
// the merge writes them back as they were.
void putText(Json& json, const char* key, const std::string& text) {
  try {
    (void)Json(text).dump();
    json[key] = text;
  } catch (const nlohmann::json::exception&) {
    static const char* digits = "0123456789abcdef";
    std::string hex;
    for (unsigned char c : text) {
      hex += digits[c >> 4];
      hex += digits[c & 15];
    }
    json[std::string(key) + "_hex"] = hex;
  }
}

std::string getText(const Json& json, const char* key) {
  if (json.contains(key)) return json.at(key).get<std::string>();
  const std::string hex = json.value(std::string(key) + "_hex", std::string());
  std::string text;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2) text += char(std::stoi(hex.substr(i, 2), nullptr, 16));
  return text;
}

Json parseLine(const std::string& path, std::size_t number, const std::string& line) {
  try {
    return Json::parse(line);
  } catch (const nlohmann::json::exception& e) {
    throw EvaluationError(path + ":" + std::to_string(number) + ": not a journal line (" + e.what() + ")");
  }
}

// The run a header describes: options, task, the share's episode list.
EvaluationResult parseHeader(const Json& h) {
  EvaluationResult r;
  EvaluationOptions& o = r.options;
  o.task = h.at("task");
  o.policy = h.at("policy");
  o.policy_config = h.at("policy_config");
  o.split = h.at("split");
  o.seed = h.at("seed");
  o.objects = h.at("objects").get<std::vector<std::string>>();
  o.levels = h.at("levels").get<std::vector<uint64_t>>();
  o.step_timeout = h.at("step_timeout");
  o.environment_timeout = h.at("env_timeout");
  o.sandbox_policy = h.at("sandbox");
  o.policy_cpu_limit = h.at("policy_cpu_limit");
  o.policy_memory_limit = h.at("policy_memory_limit");
  o.policy_output_limit = h.at("policy_output_limit");
  o.config_notes = h.at("configuration").get<std::vector<std::string>>();
  o.action_noise = h.at("action_noise");
  o.record_successes = h.at("record_successes");
  // Journals from before the option ran with the early done.
  o.early_done = h.value("early_done", true);
  o.shard = h.at("shard");
  o.shards = h.at("shards");
  o.workers = h.at("workers");
  o.command = h.value("command", std::vector<std::string>());
  o.configuration = h.value("merged_configuration", std::string());
  o.working_directory = h.value("working_directory", std::string());
  for (const Json& d : h.value("inputs", Json::array()))
    r.inputs.push_back({d.at(0), d.at(1), d.at(2), d.at(3)});
  r.policy_library = h.at("policy_library");
  r.policy_library_version = h.at("policy_version");
  const auto mode = findObservationMode(h.at("observation_mode").get<std::string>());
  if (!mode) throw EvaluationError("unknown observation mode " + h.at("observation_mode").dump());
  r.task.observation_mode = *mode;
  r.task.controller = h.at("controller");
  r.task.condition_names = h.at("success_conditions").get<std::vector<std::string>>();
  r.task.max_episode_steps = h.at("max_episode_steps");
  // The planned objects with their categories (journals from before
  // categories, and tasks without them, have none).
  const Json categories = h.value("categories", Json::object());
  for (const std::string& id : o.objects) {
    r.task.split_objects.push_back(id);
    r.task.split_categories.push_back(categories.value(id, std::string()));
  }
  for (const EpisodeSpec& spec : makeEpisodeList(o.objects, o.levels, o.seed))
    if (spec.index % o.shards == o.shard) r.planned.push_back(spec);
  return r;
}

std::string describeValue(const Json& value) {
  std::string text = value.dump();
  return text.size() > 120 ? text.substr(0, 117) + "..." : text;
}

}  // namespace

std::string formatJournalHeader(const EvaluationResult& result) {
  const EvaluationOptions& o = result.options;
  Json h;
  h["manibench_journal"] = "evaluation";
  h["format"] = kJournalFormat;
  h["manibench_version"] = getManibenchVersion();
  h["task"] = o.task;
  h["observation_mode"] = toString(result.task.observation_mode);
  h["controller"] = result.task.controller;
  h["policy"] = o.policy;
  h["policy_library"] = result.policy_library;
  h["policy_version"] = result.policy_library_version;
  h["policy_config"] = o.policy_config;
  h["split"] = o.split;
  h["seed"] = o.seed;
  h["objects"] = getPlannedObjects(result);
  h["levels"] = o.levels;
  h["step_timeout"] = o.step_timeout;
  h["env_timeout"] = o.environment_timeout;
  h["sandbox"] = o.sandbox_policy;
  h["policy_cpu_limit"] = o.policy_cpu_limit;
  h["policy_memory_limit"] = o.policy_memory_limit;
  h["policy_output_limit"] = o.policy_output_limit;
  h["configuration"] = o.config_notes;
  h["max_episode_steps"] = result.task.max_episode_steps;
  h["success_conditions"] = result.task.condition_names;
  // Only where the task names categories: other headers stay as they were.
  const std::map<std::string, std::string> categories = getObjectCategories(result.task);
  Json planned_categories = Json::object();
  for (const std::string& id : getPlannedObjects(result))
    if (categories.count(id)) planned_categories[id] = categories.at(id);
  if (!planned_categories.empty()) h["categories"] = planned_categories;
  h["action_noise"] = o.action_noise;
  h["record_successes"] = o.record_successes;
  // Only when off: the headers of default runs stay as they were, so
  // that journals written before the option still resume and merge.
  if (!o.early_done) h["early_done"] = false;
  h["shard"] = o.shard;
  h["shards"] = o.shards;
  h["workers"] = o.workers;
  // The certificate's (certificate.cpp): compared by merges and resumes
  // like everything above.
  h["build_id"] = getManibenchBuildId();
  h["command"] = o.command;
  Json inputs = Json::array();
  for (const FileDigest& d : result.inputs) inputs.push_back({d.role, d.name, d.path, d.sha256});
  h["inputs"] = inputs;
  h["merged_configuration"] = o.configuration;
  h["working_directory"] = o.working_directory;
  return h.dump();
}

std::string formatJournalEpisode(const EpisodeRecord& r) {
  Json e;
  e["episode"] = r.spec.index;
  e["object"] = r.spec.object_id;
  e["level"] = r.spec.level;
  e["seed"] = r.spec.seed;
  e["steps"] = r.steps;
  e["return"] = r.total_reward;
  e["success"] = r.success;
  e["flags"] = r.flags;
  e["success_once"] = r.success_once;
  // Only where the task measures an opening (NaN has no JSON form).
  if (std::isfinite(r.max_opened)) e["max_opened"] = r.max_opened;
  e["failure"] = r.failure;
  e["failure_step"] = r.failure_step;
  putText(e, "message", r.message);
  e["seconds"] = r.seconds;
  e["sources"] = r.sources;
  return e.dump();
}

std::string findJournalDifference(const std::string& a, const std::string& b, bool with_shard) {
  const Json x = Json::parse(a), y = Json::parse(b);
  for (const auto& [key, value] : x.items()) {
    if (key == "workers" || key == "working_directory" || (!with_shard && (key == "shard" || key == "shards"))) continue;
    if (!y.contains(key)) return key + ": " + describeValue(value) + " vs nothing";
    if (y.at(key) != value) {
      if (key == "shard") return "shard: " + std::to_string(value.get<uint32_t>() + 1) + " vs " +
                                 std::to_string(y.at(key).get<uint32_t>() + 1);
      return key + ": " + describeValue(value) + " vs " + describeValue(y.at(key));
    }
  }
  return "";
}

EvaluationJournal readJournal(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw EvaluationError("cannot read the journal '" + path + "': " + std::strerror(errno));
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  EvaluationJournal journal;
  journal.path = path;
  std::map<std::size_t, EpisodeRecord> records;
  std::size_t start = 0, number = 0;
  // A last line without its line break was cut by a kill: ignored.
  for (std::size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
    const std::string line = text.substr(start, end - start);
    ++number;
    const Json json = parseLine(path, number, line);
    try {
      if (number == 1) {
        if (json.value("manibench_journal", "") != "evaluation")
          throw EvaluationError("not a manibench evaluation journal");
        if (json.value("format", 0) != kJournalFormat)
          throw EvaluationError("journal format " + json.value("format", Json()).dump() + ", this build reads " +
                                std::to_string(kJournalFormat));
        journal.header = line;
        journal.result = parseHeader(json);
        continue;
      }
      if (json.contains("end")) {
        journal.seconds += json.at("seconds").get<double>();
        journal.worker_restarts += json.at("worker_restarts").get<uint32_t>();
        continue;
      }
      EpisodeRecord r;
      const std::size_t index = json.at("episode");
      const EvaluationOptions& o = journal.result.options;
      const std::size_t levels = o.levels.size();
      if (levels == 0 || index >= o.objects.size() * levels || index % o.shards != o.shard)
        throw EvaluationError("episode " + std::to_string(index) + " is not in this run's list");
      r.spec.index = index;
      r.spec.object_id = o.objects[index / levels];
      r.spec.level = o.levels[index % levels];
      r.spec.seed = calcEpisodeSeed(o.seed, r.spec.object_id, r.spec.level);
      if (json.at("object") != r.spec.object_id || json.at("seed") != r.spec.seed)
        throw EvaluationError("episode " + std::to_string(index) + " names another object or seed than the list");
      r.steps = json.at("steps");
      r.total_reward = json.at("return");
      r.success = json.at("success");
      // Journals from before the field: the early done made them equal.
      r.success_once = json.value("success_once", r.success);
      r.flags = json.at("flags").get<std::vector<uint8_t>>();
      if (json.contains("max_opened")) r.max_opened = json.at("max_opened").get<double>();
      r.failure = json.at("failure");
      r.failure_step = json.at("failure_step");
      r.message = getText(json, "message");
      r.seconds = json.at("seconds");
      r.sources = json.value("sources", std::vector<std::string>());
      records.emplace(index, std::move(r));  // a second record of one episode: the first counts
    } catch (const EvaluationError& e) {
      throw EvaluationError(path + ":" + std::to_string(number) + ": " + e.what());
    } catch (const nlohmann::json::exception& e) {
      throw EvaluationError(path + ":" + std::to_string(number) + ": " + e.what());
    }
  }
  if (journal.header.empty()) throw EvaluationError(path + ": an empty journal (no header line)");
  for (auto& [index, r] : records) journal.result.episodes.push_back(std::move(r));
  journal.result.interrupted = journal.result.episodes.size() < journal.result.planned.size();
  journal.result.seconds = journal.seconds;
  journal.result.worker_restarts = journal.worker_restarts;
  summarizeEvaluation(journal.result);
  return journal;
}

void writeJournal(const std::string& path, const EvaluationResult& result) {
  const std::string partial = path + ".partial";
  {
    evaluation_detail::JournalWriter writer;
    writer.open(partial, formatJournalHeader(result), false);
    for (const EpisodeRecord& r : result.episodes) writer.write(formatJournalEpisode(r));
    writer.write(evaluation_detail::formatJournalEnd(result, result.seconds));
  }
  std::error_code error;
  std::filesystem::rename(partial, path, error);
  if (error) throw EvaluationError("cannot rename '" + partial + "': " + error.message());
}

EvaluationResult mergeJournals(const std::vector<EvaluationJournal>& journals,
                               std::vector<EpisodeSpec>& missing) {
  missing.clear();
  if (journals.empty()) throw EvaluationError("nothing to merge");
  const EvaluationJournal& first = journals.front();
  for (const EvaluationJournal& j : journals) {
    const std::string difference = findJournalDifference(first.header, j.header, false);
    if (!difference.empty())
      throw EvaluationError(j.path + " is of another evaluation than " + first.path + ": " + difference);
  }
  EvaluationResult merged = first.result;
  merged.options.shard = 0;
  merged.options.shards = 1;
  merged.planned = makeEpisodeList(merged.options.objects, merged.options.levels, merged.options.seed);
  merged.episodes.clear();
  merged.seconds = 0;
  merged.worker_restarts = 0;
  std::map<std::size_t, std::pair<const EpisodeRecord*, const std::string*>> found;
  for (const EvaluationJournal& j : journals) {
    merged.seconds = std::max(merged.seconds, j.seconds);  // shards run side by side
    merged.worker_restarts += j.worker_restarts;
    for (const EpisodeRecord& r : j.result.episodes) {
      const auto [at, added] = found.emplace(r.spec.index, std::make_pair(&r, &j.path));
      if (!added)
        throw EvaluationError("episode " + std::to_string(r.spec.index) + " (object " + r.spec.object_id +
                              ", seed " + std::to_string(r.spec.seed) + ") is in both " + *at->second.second +
                              " and " + j.path);
    }
  }
  for (const EpisodeSpec& spec : merged.planned) {
    const auto at = found.find(spec.index);
    if (at == found.end())
      missing.push_back(spec);
    else
      merged.episodes.push_back(*at->second.first);
  }
  merged.interrupted = !missing.empty();
  merged.stop_reason = missing.empty() ? "" : std::to_string(missing.size()) + " episode(s) missing";
  summarizeEvaluation(merged);
  return merged;
}

std::string describeEpisodes(const std::vector<EpisodeSpec>& episodes, std::size_t at_most) {
  std::string text;
  for (std::size_t i = 0; i < episodes.size() && i < at_most; ++i)
    text += (i ? ", " : "") + std::string("object ") + episodes[i].object_id + " seed " +
            std::to_string(episodes[i].seed);
  if (episodes.size() > at_most) text += " (and " + std::to_string(episodes.size() - at_most) + " more)";
  return text;
}

std::string packEpisodeRecord(const EpisodeRecord& record) {
  using namespace evaluation_detail;
  Writer w;
  transferRun(w, record.spec);
  transferResult(w, record);
  w.u8(record.trajectory ? 1 : 0);
  if (record.trajectory) transferTrajectory(w, *record.trajectory);
  return w.data();
}

EpisodeRecord unpackEpisodeRecord(const std::string& bytes) {
  using namespace evaluation_detail;
  Reader in(bytes);
  EpisodeRecord r;
  transferRun(in, r.spec);
  transferResult(in, r);
  if (in.u8()) {
    auto trajectory = std::make_shared<Trajectory>();
    transferTrajectory(in, *trajectory);
    r.trajectory = std::move(trajectory);
  }
  return r;
}

namespace evaluation_detail {

std::string formatJournalEnd(const EvaluationResult& result, double seconds) {
  Json e;
  e["end"] = true;
  e["complete"] = !result.interrupted;
  e["stop_reason"] = result.stop_reason;
  e["seconds"] = seconds;
  e["worker_restarts"] = result.worker_restarts;
  return e.dump();
}

JournalWriter::~JournalWriter() {
  if (fd_ >= 0) ::close(fd_);
}

void JournalWriter::open(const std::string& path, const std::string& header, bool append) {
  std::error_code error;
  const auto folder = std::filesystem::path(path).parent_path();
  if (!folder.empty()) std::filesystem::create_directories(folder, error);
  if (error) throw EvaluationError("cannot create the folder of the journal '" + path + "': " + error.message());
  fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC | (append ? 0 : O_CREAT | O_TRUNC), 0644);
  if (fd_ < 0) throw EvaluationError("cannot open the journal '" + path + "': " + std::strerror(errno));
  path_ = path;
  if (append) {
    // Cut a line a kill left unfinished, so that the next one starts clean.
    std::ifstream in(path, std::ios::binary);
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string text = buffer.str();
    const std::size_t keep = text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1;
    if (ftruncate(fd_, off_t(keep)) != 0 || lseek(fd_, 0, SEEK_END) < 0)
      throw EvaluationError("cannot append to the journal '" + path + "': " + std::strerror(errno));
    return;
  }
  write(header + "\n");
}

void JournalWriter::write(const std::string& line) {
  if (fd_ < 0) return;
  const std::string text = line.back() == '\n' ? line : line + "\n";
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw EvaluationError("cannot write the journal '" + path_ + "': " + std::strerror(errno));
    done += std::size_t(n);
  }
}

}  // namespace evaluation_detail
}  // namespace manibench
