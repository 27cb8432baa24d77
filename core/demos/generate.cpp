// Demonstrations from a policy (supplement C.2): rounds of the evaluation
// kit's episodes in worker processes, keeping the successful ones (each
// ends at its first success: the environment stops on success) until every
// object has its share.
#include <manibench/demos.hpp>

#include <algorithm>
#include <chrono>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

namespace manibench {
namespace {

// Takes the records of one round as they arrive and writes the successful
// trajectories in episode-list order (object-major, levels ascending), so
// that which trajectories are kept does not depend on which worker finished
// first.
class RoundWriter {
 public:
  RoundWriter(DemoWriter& writer, std::map<std::string, GenerationObjectResult*>& objects,
              uint32_t per_object, const std::function<void(const Trajectory&)>& on_kept)
      : writer_(writer), objects_(objects), per_object_(per_object), on_kept_(on_kept) {}

  void take(EpisodeRecord& record) {
    pending_.emplace(record.spec.index, Pending{record.spec.object_id, record.failed(),
                                                record.success, std::move(record.trajectory)});
    while (!pending_.empty() && pending_.begin()->first == next_) {
      write(pending_.begin()->second);
      pending_.erase(pending_.begin());
      ++next_;
    }
  }
  // The rest, in order (a stopped round leaves gaps).
  void finish() {
    for (auto& [index, p] : pending_) write(p);
    pending_.clear();
  }

 private:
  struct Pending {
    std::string object_id;
    bool failed = false, success = false;
    std::shared_ptr<const Trajectory> trajectory;
  };

  void write(const Pending& p) {
    GenerationObjectResult& object = *objects_.at(p.object_id);
    ++object.attempts;
    if (p.failed) ++object.failures;
    if (p.success && p.trajectory && object.kept < per_object_) {
      writer_.append(*p.trajectory);
      if (on_kept_) on_kept_(*p.trajectory);
      ++object.kept;
    }
  }

  DemoWriter& writer_;
  std::map<std::string, GenerationObjectResult*>& objects_;
  const uint32_t per_object_;
  const std::function<void(const Trajectory&)>& on_kept_;
  std::map<std::size_t, Pending> pending_;
  std::size_t next_ = 0;
};

// This run's objects: its shard of the list, without those done before.
// (MPI) the ranks share the objects left, so that a resumed run spreads the
// rest.
std::vector<std::string> findOwnObjects(const GenerationOptions& options) {
  std::vector<std::string> own;
  std::size_t position = 0;  // among the shard's objects left
  for (std::size_t i = 0; i < options.evaluation.objects.size(); ++i) {
    if (i % options.shards != options.shard || options.done_objects.count(options.evaluation.objects[i]))
      continue;
    if (position++ % options.ranks == options.rank) own.push_back(options.evaluation.objects[i]);
  }
  return own;
}

// The next round: the objects that still need trajectories and may still
// try (the first round: `own`, or the workers' split where it is null),
// each on as many new levels from `next_level` as the neediest lacks.
// Nothing once no object needs more.
std::optional<EvaluationOptions> planRound(const GenerationOptions& options, const GenerationResult& result,
                                           const std::vector<std::string>* own, uint32_t max_attempts,
                                           uint64_t& next_level) {
  std::vector<std::string> needy;
  uint32_t most_needed = options.per_object;
  if (result.rounds > 0) {
    most_needed = 0;
    for (const GenerationObjectResult& o : result.objects)
      if (o.kept < options.per_object && o.attempts < max_attempts) {
        needy.push_back(o.object_id);
        most_needed = std::max(most_needed, options.per_object - o.kept);
      }
    if (needy.empty()) return std::nullopt;
  }
  EvaluationOptions round = options.evaluation;
  round.record_successes = true;
  if (own != nullptr) round.objects = *own;
  if (!needy.empty()) round.objects = needy;
  round.levels.clear();
  const uint64_t count = std::min<uint64_t>(most_needed, max_attempts - next_level);
  for (uint64_t level = next_level; level < next_level + count; ++level) round.levels.push_back(level);
  next_level += count;
  return round;
}

}  // namespace

std::string formatGeneration(const GenerationOptions& options, const std::vector<std::string>& objects,
                             uint32_t max_attempts) {
  nlohmann::ordered_json g;
  g["split"] = options.evaluation.split;
  g["seed"] = options.evaluation.seed;
  g["objects"] = objects;
  g["per_object"] = options.per_object;
  g["max_attempts"] = max_attempts;
  g["action_noise"] = options.evaluation.action_noise;
  g["shard"] = options.shard;
  g["shards"] = options.shards;
  return g.dump();
}

std::string formatGenerationResult(const GenerationResult& result, uint32_t per_object, uint32_t max_attempts) {
  nlohmann::ordered_json r;
  r["interrupted"] = result.interrupted;
  nlohmann::ordered_json objects = nlohmann::ordered_json::object();
  for (const GenerationObjectResult& o : result.objects) {
    // Done: it has its trajectories, or it tried as often as it may.
    const bool done = o.kept >= per_object || o.attempts >= max_attempts;
    objects[o.object_id] = {{"attempts", o.attempts}, {"kept", o.kept}, {"failures", o.failures}, {"done", done}};
  }
  r["objects"] = objects;
  return r.dump();
}

bool GenerationResult::isComplete(uint32_t per_object) const {
  return !interrupted && std::all_of(objects.begin(), objects.end(), [&](const GenerationObjectResult& o) {
           return o.kept >= per_object;
         });
}

GenerationResult generateDemonstrations(const PluginRegistry& registry,
                                        const GenerationOptions& options,
                                        const EnvironmentFactory& make_environment,
                                        const std::string& path, const DemoFileInfo& info,
                                        const GenerationHooks& hooks) {
  if (options.per_object == 0) throw EvaluationError("the number of trajectories per object must be at least 1");
  const uint32_t max_attempts = options.max_attempts ? options.max_attempts : 10 * options.per_object;
  if (max_attempts < options.per_object)
    throw EvaluationError("at most " + std::to_string(max_attempts) + " attempts per object cannot give " +
                          std::to_string(options.per_object) + " trajectories");
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };

  if (options.shards < 1 || options.shard >= options.shards)
    throw EvaluationError("a shard outside its count");
  if (options.shards > 1 && options.evaluation.objects.empty())
    throw EvaluationError("a shard needs the run's whole object list");
  const std::vector<std::string> own = findOwnObjects(options);
  const bool own_list = options.shards > 1 || options.ranks > 1 || !options.done_objects.empty();
  if (own_list && own.empty() && options.ranks > 1 && options.rank > 0) return {};  // more ranks than objects
  if (own_list && own.empty()) throw EvaluationError("no objects left to run");

  GenerationResult result;
  result.path = path;
  std::unique_ptr<DemoWriter> writer;
  std::map<std::string, GenerationObjectResult*> by_id;
  std::size_t failures = 0, remote_kept = 0;
  uint64_t next_level = 0;
  // Other ranks' trajectories, appended as they come once the file exists.
  auto takeRemote = [&] {
    if (!hooks.take_remote || !writer) return;
    for (const Trajectory& t : hooks.take_remote()) {
      writer->append(t);
      ++remote_kept;
    }
  };
  auto shouldStop = [&] {
    takeRemote();
    return hooks.should_stop && hooks.should_stop();
  };
  for (;;) {
    std::optional<EvaluationOptions> planned =
        planRound(options, result, own_list ? &own : nullptr, max_attempts, next_level);
    if (!planned) break;
    const EvaluationOptions& round = *planned;

    std::unique_ptr<RoundWriter> round_writer;
    EvaluationHooks round_hooks;
    round_hooks.should_stop = shouldStop;
    round_hooks.on_ready = [&](const EvaluationTaskInfo& task) {
      if (!writer) {
        DemoFileInfo complete = info;
        complete.controller = task.controller;
        complete.observation_mode = task.observation_mode;
        complete.condition_names = task.condition_names;
        const std::vector<std::string> objects =
            options.evaluation.objects.empty() ? task.split_objects : options.evaluation.objects;
        complete.generation = formatGeneration(options, objects, max_attempts);
        // At most per_object of each: the root's header is sized for them.
        writer = std::make_unique<DemoWriter>(path, complete, objects.size() * options.per_object);
        for (const std::string& id : own_list ? own : objects) result.objects.push_back({id, 0, 0, 0});
        for (GenerationObjectResult& o : result.objects) by_id[o.object_id] = &o;
      }
      round_writer = std::make_unique<RoundWriter>(*writer, by_id, options.per_object, hooks.on_kept);
    };
    round_hooks.on_episode = [&](EpisodeRecord& record) {
      ++result.episodes;
      if (record.failed()) ++failures;
      round_writer->take(record);
    };
    round_hooks.on_progress = [&](const EvaluationProgress&) {
      if (!hooks.on_progress) return;
      GenerationProgress p;
      for (const GenerationObjectResult& o : result.objects) p.kept += std::min(o.kept, options.per_object);
      p.kept += remote_kept;
      std::size_t objects = result.objects.empty() ? 1 : result.objects.size();
      if (options.ranks > 1) objects = (options.evaluation.objects.size() + options.shards - 1 - options.shard) / options.shards;
      p.wanted = std::size_t(options.per_object) * objects;
      p.episodes = result.episodes;
      p.failures = failures;
      p.elapsed = elapsed();
      hooks.on_progress(p);
    };
    const EvaluationResult evaluation = evaluatePolicy(registry, round, make_environment, round_hooks);
    if (round_writer) round_writer->finish();
    ++result.rounds;
    result.worker_restarts += evaluation.worker_restarts;
    if (evaluation.interrupted) {
      result.interrupted = true;
      result.stop_reason = evaluation.stop_reason;
      break;
    }
  }
  // MPI rank 0: the other ranks' trajectories until they are all done.
  while (hooks.remote_done && writer && !hooks.remote_done()) {
    if (shouldStop()) {
      result.interrupted = true;
      result.stop_reason = "interrupted";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  takeRemote();
  if (hooks.take_remote_results)
    for (GenerationObjectResult& o : hooks.take_remote_results()) result.objects.push_back(std::move(o));
  if (writer) {
    result.trajectories = writer->getCount();
    writer->close(formatGenerationResult(result, options.per_object, max_attempts));
  }
  result.seconds = elapsed();
  return result;
}

}  // namespace manibench
