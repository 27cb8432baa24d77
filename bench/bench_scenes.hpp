// The benchmark scenes: each a bench::Model, the integrators that suit it,
// a scripted controller and a sanity check that both engines must pass (a
// benchmark of a broken scene measures nothing).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "bench_engines.hpp"
#include "bench_model.hpp"
#include "bench_run.hpp"

namespace manibench::bench {

struct BenchScene {
  std::string name;         // what --scene matches
  std::string description;  // one line for the table's legend
  Model model;
  // manibench's PhysicsSettings::integrator for this scene (the Simbody
  // notes: CPodes for articulated scenes and few bodies, a fixed-step
  // explicit integrator for many free bodies).
  std::string integrator = "cpodes";
  // MuJoCo's integrator: "implicit" where stiff velocity-dependent drives
  // need it at a 2 ms step, otherwise MuJoCo's default "Euler".
  std::string mujoco_integrator = "Euler";
  // Contact this scene cannot do without (probed in manibench at start-up).
  bool needs_box_box = false;
  // Scripted episodes of this many control ticks, each starting from the
  // initial state; 0: one endless episode (resting scenes).
  int episode_ticks = 0;
  // Simulated seconds before the first check and the first timing.
  double settle_time = 0.5;
  // Drive targets for control tick `tick` (from 0) of episode `episode`
  // (from 0; endless scenes have one), one per Model::drives entry; empty
  // for scenes without drives. A function of its arguments only, so that
  // both engines get the same commands.
  std::function<void(long episode, long tick, std::vector<DriveTarget>& targets)> policy;
  // "" if the engine's state is physically sane. Resting scenes are checked
  // after settling and after every measurement window, episodic scenes at
  // the end of every episode.
  std::function<std::string(const Engine& engine)> check;
  // Episodic scenes: joints (articulation, name) whose positions at the end
  // of each episode are compared between the engines; with a tolerance > 0
  // a larger difference fails the scene, with 0 it is only reported.
  std::vector<std::pair<int, std::string>> compared_joints;
  double compare_tolerance = 0;
  // Scenes that are not a bench::Model (the cabinet twin) build their two
  // runs themselves; `model` is then unused.
  std::function<SceneRuns(const RunOptions& options)> make_runs;
  // Their documents for --write-models: (file name suffix, text) pairs.
  std::function<std::vector<std::pair<std::string, std::string>>(const RunOptions& options)>
      make_documents;
};

std::vector<BenchScene> makeScenes();

}  // namespace manibench::bench
