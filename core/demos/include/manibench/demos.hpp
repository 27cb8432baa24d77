// Demonstrations (supplement C.2): episodes recorded with every step's
// environment state, stored in HDF5 (libhdf5), replayed bit for bit and
// converted to other observation modes. The file layout is in
// docs/demonstrations.md; `manibench demos` is the command line.
#pragma once

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/trajectory.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench {

// What a file holds about the whole set (root attributes).
struct DemoFileInfo {
  uint64_t format_version = 1;
  std::string manibench_version;
  std::string task;            // the registered task
  std::string environment_id;  // as made (a fixed-object id, or the task)
  std::string controller;
  ObservationMode observation_mode = ObservationMode::State;
  std::vector<std::string> condition_names;
  std::string config;   // the merged YAML configuration, `--config`-able
  std::string plugins;  // JSON: [{"kind", "name", "library", "version"}]
  std::string policy;   // "name (library, version)"
  std::string created;  // ISO 8601, UTC
  std::string command;  // the command line that made it
  // How `demos generate` made it (JSON: split, seed, every object of the
  // run, per_object, max_attempts, action_noise, its shard), "" otherwise;
  // and, once it closed, each object's attempts, kept and failures and
  // whether the run was complete ("" in a file cut short). What `demos
  // merge` and --resume go by (docs/distributed.md).
  std::string generation;
  std::string generation_result;
  // `demos convert`: the input file and how its trajectories became these
  // ("observations": the same actions, another observation mode;
  // "exact": the actions of the controller the input's is a layer over,
  // replaying the same physics bit for bit; "tracked": another
  // controller's, following the recorded states); "" for a file not
  // converted.
  std::string converted_from;
  std::string conversion;
};

// Writes a demonstration file: root attributes, then one group per
// trajectory, each flushed as it is appended (a run killed, or a file cut
// anywhere, keeps every trajectory appended before). close() also writes
// the JSON sidecar (<file without .h5>.json). `expected_trajectories` sizes
// the root group's header: a file with more (or more than 60000) still
// reads whole, but a cut may then lose them all (docs/demonstrations.md).
class DemoWriter {
 public:
  DemoWriter(const std::string& path, const DemoFileInfo& info, std::size_t expected_trajectories = 0);
  ~DemoWriter();
  DemoWriter(const DemoWriter&) = delete;
  DemoWriter& operator=(const DemoWriter&) = delete;
  // Appends as traj_<count>; returns the name.
  std::string append(const Trajectory& trajectory);
  // `generation_result`: DemoFileInfo::generation_result ("" for none).
  void close(const std::string& generation_result = "");
  std::size_t getCount() const;
  const std::string& getPath() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Reads one. A file cut short opens: the trajectories written before the
// cut read, those after fail with a DemoError naming them and the cut; a
// file cut before its first trajectory was complete is a DemoError saying
// where the cut fell.
class DemoReader {
 public:
  explicit DemoReader(const std::string& path);
  ~DemoReader();
  DemoReader(const DemoReader&) = delete;
  DemoReader& operator=(const DemoReader&) = delete;
  const std::string& getPath() const;
  const DemoFileInfo& getInfo() const;
  // traj_0, traj_1, ... in order.
  const std::vector<std::string>& getTrajectoryNames() const;
  // Without `with_env_states`, the environment states (most of a state-mode
  // file) are not read: what learning needs is the rest.
  Trajectory read(const std::string& name, bool with_env_states = true) const;
  // The attributes only (object, level, seed, steps, success, reward).
  Trajectory readSummary(const std::string& name) const;
  // Bytes the trajectory's datasets take in the file.
  uint64_t calcStorageBytes(const std::string& name) const;
  // The file's size, and the size its HDF5 superblock records (larger
  // when the file was cut short or is still being written; 0 if unknown).
  uint64_t getFileBytes() const;
  uint64_t getRecordedBytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The JSON sidecar of `info` and the trajectories' summaries, as
// DemoWriter::close() writes it.
std::string formatDemoJson(const DemoFileInfo& info, const std::vector<std::string>& names,
                           const std::vector<Trajectory>& summaries);
// <path without .h5/.hdf5>.json
std::string getDemoJsonPath(const std::string& h5_path);

// Replays `trajectory` in `env` (built as the file says): restores its
// first state, then steps its actions. With `check`, compares every step's
// state blob, observation, reward and flags with the recorded ones, bit for
// bit, and stops at the first difference. `on_step` (may be empty) sees
// the first state (0) and each step after it is taken (1, 2, ...).
struct ReplayResult {
  uint32_t steps = 0;
  bool matches = true;
  std::string divergence;  // "step 17: observation[3] (segment 'tcp'): 0.1 vs 0.2"
};
ReplayResult replayTrajectory(Environment& env, const Trajectory& trajectory, bool check,
                              const std::function<void(uint32_t step)>& on_step = {});

// The observations of `env`'s observation mode at every recorded state
// (reached by stepping the recorded actions from the first state, any
// state that differs restored from the recording; D.1 sampling by the same
// (seed, step) as a live episode): `trajectory` with its observations
// replaced.
Trajectory convertTrajectory(Environment& env, const Trajectory& trajectory);

// The configuration a demonstration file was made with (its merged YAML
// over the task's layers), `overrides` (KEY=VALUE, as --set) on top.
ConfigNode calcDemoConfig(const PluginRegistry& registry, const DemoFileInfo& info,
                          const std::vector<std::string>& overrides = {});
// An environment as that configuration makes it, stopping on success as the
// generation's did.
std::unique_ptr<Environment> makeDemoEnvironment(const PluginRegistry& registry,
                                                 const DemoFileInfo& info,
                                                 const std::vector<std::string>& overrides = {});

// Converts the trajectories `names` (empty: all) of the file at `in_path`
// into a new file at `out_path` whose observations are those of `env`'s
// configuration with `overrides` (observation.mode=pointcloud, say), in
// `workers` forked processes (each with its own environment and EGL
// context). The output is described by `out_info_base` with the
// configuration and observation mode the overrides make. A trajectory that
// cannot be read or converted is reported in `failed` and skipped; a stop
// keeps what was converted.
struct ConversionResult {
  std::size_t converted = 0;
  // Tracked conversion: trajectories that no longer succeed and were left
  // out ("traj_3: ..."; kept, and not listed, with keep_failed).
  std::vector<std::string> dropped;
  // "traj_3: why": a conversion that failed, one whose workers died twice,
  // and, after an interruption, every trajectory not finished.
  std::vector<std::string> failed;
  // Converted, after the worker first converting it died: "traj_3: the
  // worker converting it was killed by signal 9 (SIGKILL); ...".
  std::vector<std::string> redone;
  std::size_t worker_restarts = 0;  // workers started in place of dead ones
  bool interrupted = false;
  double seconds = 0;
};
struct ConversionHooks {
  std::function<void(std::size_t done, std::size_t total, double elapsed)> on_progress;
  std::function<bool()> should_stop;
};
// --- controller conversion (convert_controller.cpp) ------------------------------------

// How `demos convert --controller` (overrides with control.controller)
// turns a file's trajectories into another controller's: "exact" where the
// file's controller is a layer over the target (ABI 1.7 base_controller:
// mobile_panda_ee over mobile_panda). Both environments then run at
// control rate (frame_skip 1, the time limit in control steps), so that
// each of the file's steps becomes `frame_skip` steps whose actions are
// those the layer produced at each control step. "tracked" otherwise: the
// target follows the recording in closed loop (trackTrajectory), at the
// file's rate.
struct ControllerConversion {
  std::string source, target;  // controllers
  std::string method;          // "exact" or "tracked"
  uint32_t frame_skip = 1;     // the file's
  // Over the file's configuration: the layer's environment (state
  // observations) and the target's (what the output's replays build).
  std::vector<std::string> source_overrides, target_overrides;
};
// Empty when `overrides` keep the file's controller.
std::optional<ControllerConversion> planControllerConversion(const PluginRegistry& registry,
                                                             const DemoFileInfo& info,
                                                             const std::vector<std::string>& overrides);
// Both conversions' start: `source` restored to the trajectory's first
// state, `target` reset to the same episode, their scenes checked equal
// (DemoError otherwise, or for a trajectory that does not start at its
// episode's reset).
void startControllerConversion(Environment& source, Environment& target, const Trajectory& trajectory);
// One trajectory converted as `plan` says: `source` built with its
// source_overrides, `target` with its target_overrides. Checks at every
// control step that the target's scene state equals the layer's bit for
// bit, and at every recorded step that the layer's equals the recording's;
// throws DemoError naming the step and the first difference otherwise. The
// result ends where the target's episode ends (its success or time limit).
Trajectory convertTrajectoryController(Environment& source, Environment& target, const Trajectory& trajectory,
                                       uint32_t frame_skip);

// Tracked conversion (convert_tracked.cpp): `source` replays the recording
// (the file's controller, state observations), `target` (the file's
// configuration with the target controller) takes at each step the action
// that follows it: segments the two controllers share by name (base, lift,
// grippers) the recorded value, the base's with a tenth of its drift from
// the recording corrected per step; end-effector velocities (`<side>_ee_linear`,
// `<side>_ee_angular`) towards the recorded TCP pose of the next step,
// relative to body_link. Another segment is a DemoError. The result ends
// where the target's episode ends; its tracking_error is the largest TCP
// distance to the recording after a step.
struct TrackingSpeeds {  // action 1 of the target's segments (its defaults)
  double linear = 0.5, angular = 1.57, base = 0.5, yaw = 3.14, lift = 0.5;
};
TrackingSpeeds readTrackingSpeeds(const EnvironmentOptions& target);
Trajectory trackTrajectory(Environment& source, Environment& target, const Trajectory& trajectory,
                           const TrackingSpeeds& speeds);

ConversionResult convertDemonstrations(const PluginRegistry& registry, const std::string& in_path,
                                       const std::string& out_path,
                                       const std::vector<std::string>& overrides,
                                       const std::vector<std::string>& names, unsigned workers,
                                       const DemoFileInfo& out_info_base,
                                       const ConversionHooks& hooks = {}, bool keep_failed = false);

// --- generating (supplement C.2) -------------------------------------------------------

// The evaluation kit's episodes, kept when successful, until `per_object`
// trajectories of every object (`manibench demos generate`).
struct GenerationOptions {
  // Task, policy, split, objects, base seed, workers, timeouts; its levels
  // and record_successes are set by the generation.
  EvaluationOptions evaluation;
  uint32_t per_object = 1;
  // Episodes tried per object at most (0: 10 x per_object); an object
  // whose policy fails that often ends with fewer trajectories.
  uint32_t max_attempts = 0;
  // --shard I/N (0-based here): only the objects at positions % shards ==
  // shard of evaluation.objects, which must then list every object of the
  // run (docs/distributed.md).
  uint32_t shard = 0, shards = 1;
  // MPI: of the shard's objects, this rank runs those at positions % ranks
  // == rank; the file still describes the shard.
  uint32_t rank = 0, ranks = 1;
  // Objects a resumed run has done already (--resume): not run again.
  std::set<std::string> done_objects;
};

struct GenerationObjectResult {
  std::string object_id;
  uint32_t kept = 0;      // trajectories written
  uint32_t attempts = 0;  // episodes that ran (levels 0..attempts-1)
  uint32_t failures = 0;  // episodes that did not run to their end
};

struct GenerationResult {
  std::string path;
  std::vector<GenerationObjectResult> objects;  // in split order
  std::size_t trajectories = 0;
  std::size_t episodes = 0;
  uint32_t rounds = 0;
  bool interrupted = false;
  std::string stop_reason;
  uint32_t worker_restarts = 0;
  double seconds = 0;
  bool isComplete(uint32_t per_object) const;
};

struct GenerationProgress {
  std::size_t kept = 0, wanted = 0;  // trajectories
  std::size_t episodes = 0, failures = 0;
  double elapsed = 0;  // s
};

struct GenerationHooks {
  std::function<void(const GenerationProgress&)> on_progress;  // may be empty
  std::function<bool()> should_stop;                            // may be empty
  // Each trajectory as it is written to the file (MPI: the other ranks
  // send theirs to rank 0). May be empty.
  std::function<void(const Trajectory&)> on_kept;
  // MPI rank 0: polled between events for the trajectories the other ranks
  // kept (appended to the file as they come: the caller puts the file in
  // the run's order afterwards), whether they have all finished, and then
  // their objects' results. Empty: none.
  std::function<std::vector<Trajectory>()> take_remote;
  std::function<bool()> remote_done;
  std::function<std::vector<GenerationObjectResult>()> take_remote_results;
};

// Runs rounds of evaluation episodes (levels 0, 1, ... of every object that
// still needs trajectories; seeds as `manibench eval` derives them) and
// appends the successful ones to a new file at `path`, in (object, level)
// order, so that the file does not depend on the number of workers. `info`
// describes the set (the controller, observation mode and condition names
// come from the workers' environment). A stop (should_stop) keeps every
// trajectory that finished. Throws EvaluationError when the run cannot
// start and DemoError when the file cannot be written.
GenerationResult generateDemonstrations(const PluginRegistry& registry,
                                        const GenerationOptions& options,
                                        const EnvironmentFactory& make_environment,
                                        const std::string& path, const DemoFileInfo& info,
                                        const GenerationHooks& hooks = {});
// DemoFileInfo::generation and ::generation_result of a run.
std::string formatGeneration(const GenerationOptions& options, const std::vector<std::string>& objects,
                             uint32_t max_attempts);
std::string formatGenerationResult(const GenerationResult& result, uint32_t per_object, uint32_t max_attempts);

// --- shards (merge.cpp, docs/distributed.md) ---------------------------------------

// Demonstration files of one generation (shards, a run cut short and its
// resumed rest) combined into one at `out_path`, the trajectories in the
// order the single run writes them (its rounds replayed from the files'
// levels), so that the set equals the single run's. `shard`/`shards`: the
// share the output is of (0/1: the whole run). Objects without their
// trajectories (a file cut short, a shard not given) are listed in
// `missing` ("object 12: 0 of 2 trajectories"); the output then holds the
// others. Throws DemoError naming the files and the difference when they
// are of different runs, and an object found in two of them.
struct DemoMergeResult {
  std::size_t trajectories = 0;
  std::vector<std::string> missing;
  std::vector<std::string> done_objects;  // objects with all they can get
};
DemoMergeResult mergeDemonstrations(const std::vector<std::string>& inputs, const std::string& out_path,
                                    const DemoFileInfo& out_info_base, uint32_t shard = 0,
                                    uint32_t shards = 1);
// Reads what a file says of its objects (mergeDemonstrations on it alone,
// without writing): the objects done.
std::vector<std::string> findDoneObjects(const std::string& path);
// "" when the file at `path` comes from the generation `info` describes
// (task, policy, configuration, its generation attribute: split, seed,
// objects, counts, noise, shard), else the first difference.
std::string findGenerationDifference(const std::string& path, const DemoFileInfo& info);

}  // namespace manibench
