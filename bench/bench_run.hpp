// One engine running one benchmark scene, as the timing loop sees it: env
// steps, the scene's own checks, and what the table prints about it. The
// scenes built from a bench::Model (model_run.hpp) and the cabinet twin
// (cabinet_twin.hpp) implement it.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "manibench/scene.hpp"

namespace manibench::bench {

constexpr double kControlDt = 0.01;  // one control tick (100 Hz)
constexpr int kTicksPerEnvStep = 5;  // an environment step (20 Hz)

// A uniform number in [lo, hi) that depends only on its arguments, so that
// both engines get the same random commands whatever ran before
// (splitmix64 of the mixed key; std::*_distribution differs between
// standard libraries).
double uniformAt(double lo, double hi, std::uint64_t seed, long episode, long tick, int index);

// The command line's overrides of a scene's own settings.
struct RunOptions {
  std::string integrator;  // manibench's integrator; empty: the scene's
  double accuracy = 0;     // > 0: overrides PhysicsSettings::accuracy
  double fixed_step = 0;   // > 0: overrides PhysicsSettings::fixed_step
  double implicit_step = 0;  // > 0: overrides PhysicsSettings::implicit_step
  double mujoco_dt = 0.002;
  std::string mujoco_integrator;  // empty: the scene's
  // The cabinet twin: object, seed and env steps per episode (0: the
  // task's episode length).
  std::string twin_object;
  std::uint64_t twin_seed = 0;
  int twin_episode_steps = 0;
};

class SceneRun {
 public:
  virtual ~SceneRun() = default;

  // Untimed: brings the scene to where timing starts (resting scenes
  // settle) and checks it.
  virtual void settle() = 0;
  // Env steps per second over at least `seconds` of wall time (at least one
  // step); NaN if the engine failed.
  double measure(double seconds);
  // Untimed: runs to the end of the current episode, so that episodic
  // scenes are checked at least once.
  virtual void finish() = 0;
  // Untimed: runs until `count` episodes are complete (episodic scenes only).
  void runEpisodes(long count);

  bool ok() const { return failure_.empty(); }
  // "" if every check so far passed and the engine reported nothing wrong.
  std::string getProblem() const;
  long getEpisodes() const { return episodes_; }
  // Per completed episode, the state the scene compares between the two
  // engines (same episode, same commands); empty for endless scenes.
  const std::vector<Eigen::VectorXd>& getEpisodeEnds() const { return episode_ends_; }
  // manibench's integrator work so far (all zero for MuJoCo), and the env
  // steps it was spent on.
  virtual IntegratorStatistics getIntegratorStatistics() const { return {}; }
  long getEnvSteps() const { return env_steps_; }
  // A line on what the checks saw (extremes), or "".
  virtual std::string describeChecks() const { return {}; }

 protected:
  // One env step; throws std::runtime_error (or SimulationDiverged) if the
  // simulation broke.
  virtual void runEnvStep() = 0;
  // Called after each measurement window (resting scenes check here).
  virtual void endWindow() {}
  // What the engine itself reports as wrong (MuJoCo's warnings), or "".
  virtual std::string getEngineProblems() const { return {}; }
  // Runs one env step, turning an exception into a failure.
  void envStep();
  void recordEpisodeEnd(Eigen::VectorXd state) { episode_ends_.push_back(std::move(state)); }

  std::string failure_;  // the simulation broke (an exception)
  std::string problem_;  // the first failed check
  long episodes_ = 0;

 private:
  std::vector<Eigen::VectorXd> episode_ends_;
  long env_steps_ = 0;
};

// The two engines on one scene, and what the scene learnt while building
// them (cross-engine checks made before timing, notes for the table).
struct SceneRuns {
  std::unique_ptr<SceneRun> manibench, mujoco;
  std::string integrator;          // manibench's, for the table
  std::vector<std::string> notes;  // printed under the table
  std::string problem;             // "" unless a cross-engine check failed
};

}  // namespace manibench::bench
