#include "worker.hpp"

#include <signal.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <manibench/episode.hpp>
#include <manibench/sdk/random.hpp>
#include <manibench/trajectory.hpp>
#include <memory>
#include <optional>

#include "policy_process.hpp"
#include "messages.hpp"

namespace manibench::evaluation_detail {

const char* getPhaseName(uint32_t phase) {
  switch (phase) {
    case kSetup:
      return "setup (building the environment and policy)";
    case kEnvReset:
      return "environment reset";
    case kPolicyReset:
      return "policy reset";
    case kPolicyAct:
      return "policy act";
    case kEnvStep:
      return "environment step";
    default:
      return "idle";
  }
}

int64_t getMonotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

void enterPhase(Slot& slot, Phase phase) {
  slot.since_ns.store(getMonotonicNs());
  slot.phase.store(phase);
}

namespace {

// What a worker does after an episode.
enum class After { kGoOn, kNewPolicy, kLeave };

Phase toWorkerPhase(EpisodePhase phase) {
  switch (phase) {
    case EpisodePhase::EnvReset:
      return kEnvReset;
    case EpisodePhase::PolicyReset:
      return kPolicyReset;
    case EpisodePhase::PolicyAct:
      return kPolicyAct;
    case EpisodePhase::EnvStep:
      return kEnvStep;
  }
  return kIdle;
}

// Runs one episode; failures of the policy or the environment are recorded,
// never thrown. The slot follows the episode's phases (the coordinator's
// view of a worker that hangs or dies). With `record_trajectory` the
// episode is recorded, and kept in the record when it succeeds.
After runWorkerEpisode(Environment& env, ActingPolicy& policy, Slot& slot,
                       bool record_trajectory, double action_noise, EpisodeRecord& record) {
  const auto start = getMonotonicNs();
  const std::size_t conditions = env.getTaskDescription().success_conditions.size();
  record.flags.assign(conditions, 0);
  After after = After::kGoOn;
  EpisodeHooks hooks;
  hooks.on_phase = [&slot](EpisodePhase phase, uint32_t step) {
    slot.step.store(step);
    enterPhase(slot, toWorkerPhase(phase));
  };
  // The opening curve's input: the task's `opened` signal, after the reset
  // and each step (measureProgress reads the scene and changes nothing).
  const std::vector<std::string>& signals = env.getTaskDescription().progress_signals;
  const auto opened_signal = std::find(signals.begin(), signals.end(), "opened");
  const auto measureOpened = [&] {
    if (opened_signal == signals.end()) return;
    const double opened = env.measureProgress()[std::size_t(opened_signal - signals.begin())];
    record.max_opened = std::isnan(record.max_opened) ? opened : std::max(record.max_opened, opened);
  };
  hooks.on_step = [&slot, &record, &measureOpened](const StepResult&, const EpisodeResult& so_far) {
    record.total_reward = so_far.total_reward;
    slot.total_reward.store(record.total_reward);
    measureOpened();
    return true;
  };
  // Exploration noise: N(0, action_noise^2) on every action value, from a
  // generator of the episode's seed (the same episode gets the same noise).
  sdk::Random noise(record.spec.seed ^ 0x6e6f697365000000ULL);
  Eigen::VectorXd policy_action;
  if (action_noise > 0)
    hooks.perturb_action = [&](Eigen::VectorXd& action) {
      policy_action = action;
      for (Eigen::Index i = 0; i < action.size(); ++i) {
        // Box-Muller; 1 - u keeps the logarithm finite.
        const double u = 1.0 - noise.uniform(0, 1), v = noise.uniform(0, 1);
        action[i] += action_noise * std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * v);
      }
    };
  std::optional<TrajectoryRecorder> recorder;
  bool scene_ready = false;  // the episode's scene is built: its sources count
  hooks.on_reset = [&] {
    scene_ready = true;
    measureOpened();
    if (recorder) recorder->onReset(record.spec.object_id, record.spec.level, record.spec.seed);
  };
  if (record_trajectory) {
    recorder.emplace(env);
    hooks.on_transition = [&](const Eigen::VectorXd& action, const StepResult& step) {
      recorder->onStep(action, step, action_noise > 0 ? &policy_action : nullptr);
    };
  }
  try {
    slot.step.store(0);
    slot.total_reward.store(0);
    const EpisodeResult result =
        runEpisode(env, policy, record.spec.object_id, record.spec.seed, hooks);
    record.success = result.success;
    record.success_once = result.success_once;
    record.flags = result.final_flags;
    record.flags.resize(conditions, 0);
    if (recorder && record.success) record.trajectory = std::make_shared<Trajectory>(recorder->take());
  } catch (const std::exception& e) {
    const uint32_t phase = slot.phase.load();
    record.failure_step = slot.step.load();
    record.success = false;
    record.success_once = false;
    record.flags.assign(conditions, 0);
    record.max_opened = std::numeric_limits<double>::quiet_NaN();
    // The policy object may be in any state after failing: a new one.
    after = After::kNewPolicy;
    if (const auto* process = dynamic_cast<const PolicyProcessFailure*>(&e)) {
      record.failure = process->failure();
    } else if (dynamic_cast<const InvalidAction*>(&e)) {
      record.failure = failure::kInvalidAction;
    } else if (const auto* call = dynamic_cast<const PluginCallError*>(&e);
               call && isPolicyPhase(phase)) {
      // The SDK reports a wrong-size action as an invalid argument of act.
      record.failure = (phase == kPolicyAct && call->status() == MB_INVALID_ARGUMENT)
                           ? failure::kInvalidAction
                           : failure::kPolicyError;
    } else if (isPolicyPhase(phase)) {
      record.failure = failure::kPolicyError;
    } else {
      record.failure = failure::kEnvironmentError;
      after = After::kLeave;  // a fresh process rather than a scene in an unknown state
    }
    record.message = std::string(getPhaseName(phase)) + " at step " +
                     std::to_string(record.failure_step) + ": " + e.what();
  }
  record.steps = env.getElapsedSteps();
  // What the episode's scene was built from, for the certificate; a mesh
  // file gone since the build fails the episode rather than the run.
  if (scene_ready) {
    try {
      record.sources = env.getScene().getSourceDigests();
    } catch (const std::exception& e) {
      if (!record.failed()) {
        record.failure = failure::kEnvironmentError;
        record.success = false;
        record.success_once = false;
        record.flags.assign(conditions, 0);
        record.max_opened = std::numeric_limits<double>::quiet_NaN();
        record.failure_step = record.steps;
        record.message = std::string("hashing the scene's files: ") + e.what();
      }
    }
  }
  record.seconds = double(getMonotonicNs() - start) * 1e-9;
  enterPhase(slot, kIdle);
  return after;
}

// The bytes of the observation's arrays (the sandboxed policy's block is
// sized from them).
std::size_t calcObservationBytes(const Environment& env) {
  const VisualObservation& v = env.getVisualObservation();
  return std::size_t(env.getObservation().size()) * sizeof(double) +
         (v.points.xyz.size() + v.points.rgb.size() + v.rgb.size() + v.depth.size()) *
             sizeof(float) +
         v.points.masks.size() + v.rgb_bytes.size() + v.masks.size();
}

std::unique_ptr<ActingPolicy> makePolicy(const WorkerContext& context, Environment& env) {
  const EvaluationOptions& options = *context.options;
  const PolicyLayout layout = env.calcPolicyLayout(env.getObservationMode());
  if (!options.sandbox_policy)
    return std::make_unique<PolicyInstance>(*context.registry, options.policy,
                                            options.policy_config, layout);
  PolicyProcessSettings settings;
  settings.registry = context.registry;
  settings.policy = options.policy;
  settings.policy_config = options.policy_config;
  settings.layout = layout;
  settings.read_paths = options.policy_read_paths;
  // The policy's library, its folder and the folder above: the host's
  // private libraries, which a plugin may load from beside itself
  // (torch_policy its learning runtime: lib/manibench/ above plugins/).
  const std::filesystem::path library =
      context.registry->getLibraries()[context.registry->getEntry(PluginKind::Policy, options.policy).library].path;
  for (const std::filesystem::path& path :
       {library, library.parent_path(), library.parent_path().parent_path()})
    settings.read_paths.push_back(path.string());
  settings.call_timeout = options.step_timeout;
  settings.create_timeout = options.environment_timeout;
  settings.cpu_limit = options.policy_cpu_limit;
  settings.memory_bytes = options.policy_memory_limit;
  settings.output_bytes = options.policy_output_limit;
  if (env.getObservationMode() != ObservationMode::State && env.getObservation().size() == 0) {
    // A visual observation's size is known once there is one: a reset
    // (episodes do not depend on what ran before them).
    const std::vector<std::string> objects =
        options.objects.empty() ? env.listObjects(options.split) : options.objects;
    if (!objects.empty()) env.reset(objects.front(), 0);
  }
  settings.observation_bytes = calcObservationBytes(env);
  settings.scratch_dir = context.scratch_dir;
  return std::make_unique<SandboxedPolicy>(settings);
}

// The task as this worker's environment configures it.
EvaluationTaskInfo describeTask(const Environment& env, const std::string& split) {
  const TaskDescription& task = env.getTaskDescription();
  EvaluationTaskInfo info;
  info.observation_mode = env.getObservationMode();
  info.controller = env.getControllerDescription().name;
  info.condition_names = task.success_conditions;
  info.split_objects = env.listObjects(split);
  for (const std::string& id : info.split_objects) info.split_categories.push_back(env.getObjectCategory(id));
  info.max_episode_steps = task.max_episode_steps;
  info.action_dim = env.getControllerDescription().action_dim;
  info.observation_dim = task.observation_dim;
  return info;
}

}  // namespace

int runWorker(int fd, Slot& slot, const WorkerContext& context) {
  enterPhase(slot, kSetup);
  std::unique_ptr<Environment> env;
  std::unique_ptr<ActingPolicy> policy;
  {
    Writer w;
    try {
      env = (*context.make_environment)();
      policy = makePolicy(context, *env);
      const EvaluationTaskInfo info = describeTask(*env, context.options->split);
      transferReady(w.u8(kReady), info);
    } catch (const std::exception& e) {
      w = Writer();
      w.u8(kSetupError).str(e.what());
    }
    enterPhase(slot, kIdle);
    wire::sendFrame(fd, w);
    if (!policy) return 0;
  }
  std::string payload;
  while (wire::receiveFrame(fd, payload)) {
    try {
      Reader in(payload);
      if (in.u8() != kRun) break;
      EpisodeRecord record;
      transferRun(in, record.spec);
      const After after =
          runWorkerEpisode(*env, *policy, slot, context.options->record_successes,
                           context.options->action_noise, record);
      if (auto* sandboxed = dynamic_cast<SandboxedPolicy*>(policy.get())) sandboxed->relayOutput();
      Writer w;
      transferResult(w.u8(kResult), record);
      w.u8(record.trajectory ? 1 : 0);
      if (record.trajectory) transferTrajectory(w, *record.trajectory);
      // Whether this worker leaves after the episode (the coordinator then
      // hands the next episode to a fresh one, not to this one).
      w.u8(after == After::kLeave ? 1 : 0);
      if (!wire::sendFrame(fd, w) || after == After::kLeave) break;
      if (after == After::kNewPolicy) {
        enterPhase(slot, kSetup);
        policy.reset();
        policy = makePolicy(context, *env);
        enterPhase(slot, kIdle);
      }
    } catch (const std::exception& e) {
      // Even a new policy could not be made: tell, and leave.
      Writer w;
      w.u8(kSetupError).str(e.what());
      wire::sendFrame(fd, w);
      break;
    }
  }
  policy.reset();  // a sandboxed policy's process ends, its folder goes
  return 0;
}

}  // namespace manibench::evaluation_detail
