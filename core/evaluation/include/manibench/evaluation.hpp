// The evaluation kit (supplement B.5): a policy on a task's test (or train)
// objects, episodes as (object, level) pairs with seeds derived from one base
// seed, run in forked worker processes so that a policy that crashes, hangs
// or returns garbage fails only its episode. Results are aggregated per
// object (success rate, each success condition's satisfactory rate) and
// written as a terminal table, CSV and JSON (docs/evaluation.md).
#pragma once

#include <manibench/error.hpp>
#include <manibench/observation_mode.hpp>
#include <manibench/plugin_registry.hpp>

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench {

class Environment;  // environment.hpp
struct Trajectory;  // trajectory.hpp

// The evaluation could not start or could not go on (bad options, a worker
// that cannot build its environment or policy); names the cause.
class EvaluationError : public Error {
 public:
  using Error::Error;
};

// This build's version, as written into result files.
const char* getManibenchVersion();
// This build's identity: the GNU build id of the running program (40 hex
// digits, what `file` and `readelf -n` print), else the SHA-256 of its
// executable. Two builds of different sources differ in it.
const std::string& getManibenchBuildId();

// A file a result depends on, with its SHA-256 (the certificate,
// docs/evaluation.md): a plugin library (role "task", "controller",
// "policy", `name` the plugin) or one of the policy's own files (role
// "policy file").
struct FileDigest {
  std::string role;
  std::string name;
  std::string path;
  std::string sha256;
};

// What the policy's sandbox is made of on this machine: "seccomp, Landlock
// ABI 7, rlimits", or without Landlock "seccomp, rlimits; no file rules
// (this kernel has no Landlock)" (docs/evaluation.md, "Sandbox").
std::string describeSandbox();

// One episode to run: episode `level` of `object_id`.
struct EpisodeSpec {
  std::size_t index = 0;  // position in the episode list
  std::string object_id;
  uint64_t level = 0;  // episode index within the object
  uint64_t seed = 0;   // derived from the base seed, object and level
};

// Episode `level` of `object_id` under base seed `seed`: a 32-bit seed (easy
// to pass to `manibench run --seed`) that depends on all three.
uint64_t calcEpisodeSeed(uint64_t seed, const std::string& object_id, uint64_t level);
// "2/3" (1-based, as the command line says) -> shard 1 of 3; throws
// InvalidArgument naming the bad text.
void parseShard(const std::string& text, uint32_t& shard, uint32_t& shards);
// Every object, in the given order, times every level: object-major.
std::vector<EpisodeSpec> makeEpisodeList(const std::vector<std::string>& objects,
                                         const std::vector<uint64_t>& levels, uint64_t seed);
// "0-4" (inclusive), "1,3,7" or mixtures ("0-2,9"); sorted, duplicates
// dropped. Throws InvalidArgument naming the bad part.
std::vector<uint64_t> parseLevels(const std::string& text);
// "3,7" -> {"3", "7"}: ids separated by commas, duplicates dropped, order kept.
std::vector<std::string> parseIdList(const std::string& text);

// Why an episode did not run to its end (empty: it did).
namespace failure {
inline constexpr const char* kCrash = "crash";                   // the worker died (signal, exit)
inline constexpr const char* kTimeout = "timeout";               // a policy call hung
inline constexpr const char* kPolicyError = "policy_error";      // the policy reported an error
inline constexpr const char* kInvalidAction = "invalid_action";  // NaN, infinity, wrong size
inline constexpr const char* kEnvironmentError = "environment_error";  // task/physics failed
inline constexpr const char* kEnvironmentTimeout = "environment_timeout";
// The policy's sandbox refused a call (network, processes, signals out,
// other processes' memory), or the policy went past a limit (memory, CPU
// time, output).
inline constexpr const char* kSandbox = "sandbox";
}  // namespace failure

struct EpisodeRecord {
  EpisodeSpec spec;
  uint32_t steps = 0;  // environment steps completed
  double total_reward = 0;
  bool success = false;  // at the episode's last step: success_at_end
  // At any step of the episode (success_once). With the early done (the
  // default) an episode ends at its first success, so the two are equal;
  // without it (EvaluationOptions::early_done) success_once >= success.
  bool success_once = false;
  // The final step's flag per success condition; all 0 for a failed episode
  // (its conditions were never evaluated at a terminal step).
  std::vector<uint8_t> flags;
  // The most of its range the target opened at any point of the episode:
  // the task's `opened` progress signal (abi.h; doors and drawers), read
  // after the reset and after every step. NaN when the task has no such
  // signal, and for a failed episode (which counts as opening nothing, as
  // its success is 0). The opening curve's input (kOpeningFractions).
  double max_opened = std::numeric_limits<double>::quiet_NaN();
  std::string failure;        // empty, or one of failure::k*
  int64_t failure_step = -1;  // the step being taken when it failed
  std::string message;        // what went wrong, for people
  double seconds = 0;         // wall time of the episode (timing)
  // What the episode's scene was built from (Scene::getSourceDigests:
  // "<sha256>  <file>" lines, URDF and meshes); empty when its reset
  // failed. The certificate's objects (certificate.json).
  std::vector<std::string> sources;
  // The recorded episode, when EvaluationOptions::record_successes asked
  // for it and the episode succeeded; else empty.
  std::shared_ptr<const Trajectory> trajectory;
  bool failed() const { return !failure.empty(); }
};

// The opening curve's fractions (docs/evaluation.md, "Protocols"): the
// share of episodes whose target opened at least this much of its range
// at some step, beside B.4's success (90 % and static), as ARNOLD reports
// success at several goal states. Reported for tasks with an `opened`
// progress signal; episodes.csv's max_opened gives any other fraction.
inline constexpr double kOpeningFractions[] = {0.25, 0.5, 0.75, 0.9};

// Aggregate of a group of episodes (one object, or all).
struct EvaluationSummary {
  std::string object_id;  // "all" for the overall line; a category's name
  uint32_t objects = 0;   // a category's objects (0 for an object's line, the overall's)
  uint32_t episodes = 0;
  uint32_t successes = 0;
  uint32_t failures = 0;  // episodes that did not run to their end
  double success_rate = 0;
  // The success rate's 95 % interval: an object's, Wilson's score interval
  // over its episodes; the overall line's, a bootstrap that resamples the
  // objects (the split's objects are the population), widened to the
  // pooled Wilson interval where that is wider (calcOverallInterval);
  // docs/evaluation.md, "Intervals".
  double success_low = 0, success_high = 0;
  // The same for success_once (success at any step; success_rate is
  // success_at_end), with its interval computed the same way.
  uint32_t successes_once = 0;
  double success_once_rate = 0;
  double success_once_low = 0, success_once_high = 0;
  std::vector<double> condition_rates;  // per success condition
  // Per kOpeningFractions entry, the episodes whose max_opened reached it,
  // their rate and its interval (computed as the success rate's); empty
  // when no episode of the evaluation measured an opening.
  std::vector<uint32_t> opened_counts;
  std::vector<double> opened_rates, opened_low, opened_high;
  double mean_return = 0;
  double mean_steps = 0;
};

struct EvaluationOptions {
  std::string task;
  std::string policy;         // a registered policy name (resolved already)
  std::string policy_config;  // YAML handed to the policy's create
  std::string split = "test";
  std::vector<std::string> objects;  // empty: every object of the split
  std::vector<uint64_t> levels;      // episode indices run on every object
  uint64_t seed = 0;
  unsigned workers = 1;
  double step_timeout = 10;          // s, for each policy call (reset, act)
  double environment_timeout = 300;  // s, for each reset/step and a worker's setup
  // Written into the JSON as they are (the configuration sources, say).
  std::vector<std::string> config_notes;
  // Workers record every episode (observations, actions, a state per step)
  // and send back the successful ones in their EpisodeRecord (demos).
  bool record_successes = false;
  // Gaussian noise of this standard deviation added to every action the
  // policy gives before it is executed (0: none), drawn from the episode's
  // seed; recorded trajectories keep the policy's own actions beside the
  // executed ones (demos generate --action-noise).
  double action_noise = 0;
  // An episode ends at its first success (ManiSkill v1's B.4 protocol, the
  // default); false: it runs to the time limit (--no-early-done), and
  // success_once and success_at_end can differ (ManiSkill3's two metrics).
  // The environment factory must match (stop_on_success).
  bool early_done = true;
  // The policy runs in a sandboxed process of its own (policy_process.hpp,
  // docs/evaluation.md "Sandbox"); false: in the worker's process, beside
  // the environment (--trusted-policy), as fast as it gets but with the
  // worker's power over the results.
  bool sandbox_policy = true;
  // Files and folders the sandboxed policy may read (its library or
  // script folder, its configuration folder, --policy-read).
  std::vector<std::string> policy_read_paths;
  double policy_cpu_limit = 60;                       // s of CPU time per episode
  uint64_t policy_memory_limit = uint64_t(4) << 30;   // bytes of address space it may add
  uint64_t policy_output_limit = uint64_t(16) << 20;  // bytes: its log, each temporary file

  // --- beyond one machine (docs/distributed.md) ---
  // This run's share of the episode list (--shard I/N, 0-based here):
  // episodes whose index % shards == shard, with the seeds of the whole
  // list. `planned` holds the share.
  uint32_t shard = 0, shards = 1;
  // Of the share, this process runs the episodes at positions % ranks ==
  // rank (MPI); the others' records come through
  // EvaluationHooks::take_remote.
  uint32_t rank = 0, ranks = 1;
  // The run's journal (docs/distributed.md, "Journal"): a line per finished
  // episode, written as each arrives, so that a run killed outright keeps
  // them; "" for none.
  std::string journal_path;
  // Episodes finished by an earlier run of the same evaluation (--resume):
  // not run again, part of the result; `resumed_header` is that run's
  // journal header, which must describe this same run.
  std::vector<EpisodeRecord> resumed;
  std::string resumed_header;

  // --- the certificate's parts only the command knows (docs/evaluation.md,
  // "Certificate"); all of them go into the journal's header, so that a
  // resume or a merge of another build, plugin or configuration is refused.
  // The eval arguments that decide the result (without --out, --workers,
  // --shard, --resume and the progress flags): what `eval --verify` runs.
  std::vector<std::string> command;
  // The policy's own files (its configuration, script, checkpoint), hashed.
  std::vector<std::string> policy_files;
  // The merged configuration, as `manibench config` prints it.
  std::string configuration;
  // Where the command ran: its relative paths start there.
  std::string working_directory;
};

// What a worker reports after setting up: the task as configured.
struct EvaluationTaskInfo {
  ObservationMode observation_mode = ObservationMode::State;  // the environment's, as configured
  std::string controller;
  std::vector<std::string> condition_names;
  std::vector<std::string> split_objects;
  // Each split object's category (ABI 1.8, Environment::getObjectCategory),
  // in split_objects' order; "" for none.
  std::vector<std::string> split_categories;
  uint32_t max_episode_steps = 0;
  uint32_t action_dim = 0;
  uint32_t observation_dim = 0;
};

struct EvaluationResult {
  EvaluationOptions options;
  std::string policy_library;
  std::string policy_library_version;
  // The task's, the controller's and the policy's libraries, then the
  // policy's own files, each with its SHA-256 (calcInputDigests).
  std::vector<FileDigest> inputs;
  EvaluationTaskInfo task;
  std::vector<EpisodeSpec> planned;        // the whole episode list
  std::vector<EpisodeRecord> episodes;     // those that finished, by index
  std::vector<EvaluationSummary> objects;  // per object, in episode-list order
  EvaluationSummary overall;
  // Per category, by name, where the task names any (getObjectCategories).
  std::vector<EvaluationSummary> categories;
  bool interrupted = false;  // stopped before every planned episode ran
  std::string stop_reason;   // why, when interrupted ("interrupted by the user", ...)
  uint32_t worker_restarts = 0;
  double seconds = 0;  // wall time of the whole evaluation (timing)
};

struct EvaluationProgress {
  std::size_t done = 0;
  std::size_t total = 0;
  std::size_t successes = 0;
  std::size_t failures = 0;
  double elapsed = 0;  // s
};

// Builds the environment inside a worker (after the fork, so that anything
// it creates, EGL contexts included, belongs to that process).
using EnvironmentFactory = std::function<std::unique_ptr<Environment>()>;

struct EvaluationHooks {
  // Called from the coordinating process after each episode and a few times
  // a second; may be empty.
  std::function<void(const EvaluationProgress&)> on_progress;
  // Polled between events; true stops the run, kills the workers and
  // returns the episodes finished so far with `interrupted` set.
  std::function<bool()> should_stop;
  // Called from the coordinating process once the first worker has set up:
  // the task as configured. May be empty.
  std::function<void(const EvaluationTaskInfo&)> on_ready;
  // Called from the coordinating process with each episode's record as it
  // arrives (in the order episodes finish); it may take the record's
  // trajectory (the result keeps the rest). May be empty.
  std::function<void(EpisodeRecord&)> on_episode;
  // With options.ranks > 1 (MPI rank 0): polled between events for the
  // records the other ranks finished (moved out), and whether every other
  // rank has finished (or stopped); the run ends when its own episodes are
  // done and remote_done() says so. Records missing then (a rank died) are
  // named in the result's stop_reason.
  std::function<std::vector<EpisodeRecord>()> take_remote;
  std::function<bool()> remote_done;
};

// Runs the evaluation. `registry` must hold the policy (and the task); its
// libraries are inherited by the workers. Throws EvaluationError when the
// run cannot start (a worker cannot build the environment or the policy,
// unknown objects, empty selection) and PluginError for unknown names.
EvaluationResult evaluatePolicy(const PluginRegistry& registry, const EvaluationOptions& options,
                                const EnvironmentFactory& make_environment,
                                const EvaluationHooks& hooks = {});

// The libraries of the task `task_name` (a fixed-object id too), of the
// controller `controller` and of `options.policy`, then every file of
// `options.policy_files` (a folder: each regular file under it, in name
// order), with their SHA-256. Throws Error naming a file that cannot be
// read.
std::vector<FileDigest> calcInputDigests(const PluginRegistry& registry, const EvaluationOptions& options,
                                         const std::string& controller);

// Per-object and overall summaries of `result.episodes` (failed episodes
// count as unsuccessful, with every condition unsatisfied).
void summarizeEvaluation(EvaluationResult& result);
// The split objects' categories, by id, those with one only.
std::map<std::string, std::string> getObjectCategories(const EvaluationTaskInfo& task);

// Output. The CSV files and the JSON hold the same numbers; timings appear
// only in the JSON's "timing" object, so that two runs of the same
// evaluation give byte-identical CSV files.
void printEvaluationTable(std::ostream& out, const EvaluationResult& result);
void writeSummaryCsv(std::ostream& out, const EvaluationResult& result);
void writeEpisodesCsv(std::ostream& out, const EvaluationResult& result);
void writeEvaluationJson(std::ostream& out, const EvaluationResult& result);
// certificate.json: what the result came from (build, plugins, policy
// files, configuration, each object's files, the episodes) and the
// SHA-256 of episodes.csv and summary.csv (docs/evaluation.md,
// "Certificate").
void writeCertificateJson(std::ostream& out, const EvaluationResult& result);
// summary.csv, episodes.csv, summary.json and certificate.json in
// `directory` (created if needed); returns the paths written.
std::vector<std::string> writeEvaluationFiles(const std::string& directory,
                                              const EvaluationResult& result);

// --- journals, shards, merging (journal.cpp, docs/distributed.md) ---

// An evaluation's journal: its first line describes the run (everything
// that decides its episodes' outcomes, and its shard), then one line per
// finished episode with its exact numbers, then an end line per run. JSON,
// one object a line. A line cut short by a kill is ignored.
// The journal's name in an output folder.
inline constexpr const char* kJournalFileName = "journal.jsonl";
std::string formatJournalHeader(const EvaluationResult& result);
std::string formatJournalEpisode(const EpisodeRecord& record);
// "" when `a` and `b` (headers) describe the same evaluation, else the
// first difference, "task: 'Reach-v0' vs 'OpenCabinetDrawer-v0'".
// `with_shard`: the shard counts too.
std::string findJournalDifference(const std::string& a, const std::string& b, bool with_shard);
struct EvaluationJournal {
  std::string path;
  std::string header;             // the header line
  EvaluationResult result;        // options, task, planned (the share) and episodes
  double seconds = 0;             // of its runs, from their end lines
  uint32_t worker_restarts = 0;
};
// Writes `result` (a merge's) as a journal at `path`: its header, its
// episodes and an end line; through PATH.partial, renamed into place.
void writeJournal(const std::string& path, const EvaluationResult& result);
// Reads a journal; throws EvaluationError naming the file and line.
EvaluationJournal readJournal(const std::string& path);
// The whole evaluation from journals of the same run (shards, resumed
// parts): every episode once, in list order; those no journal has are in
// `missing` and the result is marked incomplete. Throws EvaluationError
// naming the difference when the journals are of different runs, and an
// episode found in two of them.
EvaluationResult mergeJournals(const std::vector<EvaluationJournal>& journals,
                               std::vector<EpisodeSpec>& missing);
// "object 8 seed 1234, object 11 seed 99 (and 3 more)".
std::string describeEpisodes(const std::vector<EpisodeSpec>& episodes, std::size_t at_most = 10);

// An episode's record (its trajectory too) as bytes and back: what MPI
// ranks send rank 0.
std::string packEpisodeRecord(const EpisodeRecord& record);
EpisodeRecord unpackEpisodeRecord(const std::string& bytes);

}  // namespace manibench
