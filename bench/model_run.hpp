// The runs of the scenes built from a bench::Model: each engine driven tick
// by tick with the scene's policy, its episodes reset and checked.
#pragma once

#include "bench_run.hpp"
#include "bench_scenes.hpp"

namespace manibench::bench {

// manibench's settings for a model scene under the command line's
// overrides (MuJoCo's single friction coefficient is used for both of
// manibench's).
PhysicsSettings makeModelSettings(const BenchScene& scene, const RunOptions& options);
std::string describeIntegrator(const PhysicsSettings& settings);

// Builds both engines; throws std::exception if either cannot be built.
SceneRuns makeModelRuns(const BenchScene& scene, const RunOptions& options);

}  // namespace manibench::bench
