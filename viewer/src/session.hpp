// What the viewer runs, without the window: an environment and its
// episodes, driven by keyboard teleoperation, by a policy plugin, or by a
// demonstration file being replayed; the episode's numbers for the
// overlay; and the recording of teleoperated (or policy) episodes into a
// demonstration file. The window decides when a step happens (real time,
// pause, single steps), so episodes are stepped here one at a time rather
// than through runEpisode; the calls keep abi.h's order all the same
// (environment reset, policy reset, then act and step).
#pragma once

#include <manibench/config.hpp>
#include <manibench/demos.hpp>
#include <manibench/environment.hpp>
#include <manibench/plugin_instances.hpp>
#include <manibench/plugin_registry.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace manibench::viewer {

enum class SessionMode { Teleop, Policy, Replay };

struct SessionOptions {
  SessionMode mode = SessionMode::Teleop;
  std::string task;          // task or fixed-object id (Teleop, Policy)
  ConfigSources sources;     // --config, --set, --controller, --obs
  std::string object;        // empty: drawn from the split by the seed
  std::string split = "train";
  uint64_t seed = 0;
  std::string policy;        // registered name (Policy)
  std::string policy_config; // YAML handed to its create
  std::string record_path;   // --record FILE.h5 (empty: none)
  std::string replay_path;   // --replay FILE.h5
  std::string trajectory;    // --trajectory traj_N (empty: the first)
  std::string command;       // the command line, for the file's description
};

// Where an episode stands.
enum class EpisodeStatus { Running, Success, TimeLimit, Failed };

class Session {
 public:
  // Builds the environment (or the demonstration file's) and starts the
  // first episode. Throws what the environment, the policy and the file
  // throw, naming what is at fault.
  Session(PluginRegistry& registry, SessionOptions options);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // One env step: `teleop_action` in Teleop mode; the policy's action in
  // Policy mode; the recorded action in Replay mode. Nothing once the
  // episode is over. An EpisodeFailure or a policy's error ends the
  // episode as Failed (getFailure says why) instead of escaping.
  void step(const Eigen::VectorXd& teleop_action = Eigen::VectorXd());
  // Starts the episode again (same object and seed); the one in progress
  // is recorded unless `discard`. Replay: back to the first state.
  void restart(bool discard = false);
  // The next object of the split (same seed); Replay: the next trajectory
  // of the file.
  void nextObject();
  // Replay: the recorded state `t` (0 .. getReplayLength()).
  void seek(uint32_t t);

  // Ends the session: the episode in progress is recorded (when it has
  // steps) and the file closed. Called by the destructor too; safe twice.
  void close();

  SessionMode getMode() const { return options_.mode; }
  const SessionOptions& getOptions() const { return options_; }
  Environment& updEnvironment() { return *env_; }
  const Environment& getEnvironment() const { return *env_; }
  EpisodeStatus getStatus() const { return status_; }
  bool isOver() const { return status_ != EpisodeStatus::Running; }
  const std::string& getFailure() const { return failure_; }
  // Flags and values of the success conditions after the last step or
  // reset, the last reward and the sum so far.
  const StepResult& getLastStep() const { return last_; }
  double getReturn() const { return return_; }
  const Eigen::VectorXd& getLastAction() const { return last_action_; }
  const std::string& getPolicyName() const;
  // Counts the episodes started and the states restored: when it changes,
  // the environment may have rebuilt its scene.
  uint64_t getEpisodeCount() const { return episode_count_; }

  // Replay: the trajectory shown, its length, and whether every state
  // stepped so far equals the recording bit for bit (false, with the first
  // difference in getReplayDivergence, once one differs).
  const std::string& getTrajectoryName() const { return trajectory_name_; }
  uint32_t getReplayLength() const;
  bool isReplayExact() const { return replay_divergence_.empty(); }
  const std::string& getReplayDivergence() const { return replay_divergence_; }
  std::size_t getTrajectoryCount() const { return trajectory_names_.size(); }

  // Recording: the file (empty: none) and the trajectories written so far.
  const std::string& getRecordPath() const { return options_.record_path; }
  std::size_t getRecordedCount() const;

 private:
  void startEpisode();
  void finishEpisode();  // records the episode, if recording and it has steps
  void loadTrajectory(const std::string& name);
  void setStatusFrom(const StepResult& result);

  PluginRegistry& registry_;
  SessionOptions options_;
  std::unique_ptr<Environment> env_;
  std::unique_ptr<PolicyInstance> policy_;
  std::vector<std::string> objects_;  // teleop/policy: the split's (or the fixed id's)
  std::size_t object_index_ = 0;
  EpisodeStatus status_ = EpisodeStatus::Running;
  std::string failure_;
  StepResult last_;
  double return_ = 0;
  Eigen::VectorXd last_action_;

  // Recording.
  class Recording;
  std::unique_ptr<Recording> recording_;

  // Replay.
  std::unique_ptr<DemoReader> reader_;
  std::vector<std::string> trajectory_names_;
  std::string trajectory_name_;
  std::optional<Trajectory> trajectory_;
  std::string replay_divergence_;
  bool closed_ = false;
  uint64_t episode_count_ = 0;
};

const char* toString(EpisodeStatus status);

}  // namespace manibench::viewer
