// The twin of the real workload: OpenCabinetDrawer-v0 (the mobile Panda and
// one generated cabinet) stepped by manibench's real Environment and by
// MuJoCo 2.2.2 under the same random action sequence.
//
// manibench: the environment as `manibench bench` builds it (plugins from
// the search path, the task's configuration, its default controller
// mobile_panda), reset on one object and seed, stepped with
// Environment::step. MuJoCo: the same physical scene, converted from the
// URDF texts and settings the manibench scene was built from
// (urdf_twin.hpp), driven by a copy of mobile_panda's drive law
// (mobile_panda_law.hpp) against MuJoCo's own state. docs/performance.md
// lists what is matched and what cannot be.
//
// Before timing, three cross-engine checks: the copied drive law replayed
// on the manibench scene reproduces Environment::step bit for bit; both
// engines hold still under zero actions; and both follow a short open-loop
// action sequence in free space to within a tolerance.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "bench_run.hpp"
#include "bench_scenes.hpp"

namespace manibench::bench {

// The scene "cabinet_random"; its make_documents writes the MJCF and both
// URDFs.
BenchScene makeCabinetTwinScene();

}  // namespace manibench::bench
