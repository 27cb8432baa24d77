// `manibench train sac-population` (supplement C.2's divide and conquer):
// one SAC agent per object of a split, each trained by its own `manibench
// train sac` process on the object's fixed-object id, in its own directory
// with its own seed (derived from the base seed and the object id alone,
// so objects can be spread over machines without changing anything),
// evaluated, and retrained from scratch with the next seed while its
// success rate is below the threshold (C.2: 0.3). Resumable per object:
// run the same command again. Layout:
//
//   DIR/population.yaml               the options; then per object: attempts,
//                                     success rate, accepted, the policy config
//   DIR/objects/ID/attempt_K/         a `train sac` directory (train.log, eval/)
//   DIR/objects/ID/policy.yaml        the accepted (or best) attempt's checkpoint
//   DIR/objects/ID/result.yaml        written when the object is finished
//   DIR/demos/ID.h5                   with --demos N: N successful episodes per
//                                     accepted object, from its own agent
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace manibench::learning::programs {

struct PopulationOptions {
  std::string task;
  std::string split = "train";
  std::vector<std::string> objects;  // empty: the split's
  std::string out_dir;
  uint64_t seed = 0;
  double threshold = 0.3;     // C.2
  unsigned max_attempts = 3;  // trainings per object at most
  unsigned eval_episodes = 20;
  uint64_t eval_seed = 1000;
  unsigned demos_per_object = 0;  // 0: no demonstrations
  // --shard I/N (0-based here), or the MPI rank and size: only the objects
  // at positions % shards == shard (docs/distributed.md).
  uint32_t shard = 0, shards = 1;
  // The `manibench train sac` options every object's training gets
  // (--steps, --workers, Table 6's overrides, --config, ...).
  std::vector<std::string> sac_args;
};

int runPopulation(const PopulationOptions& options);
// The shard from --shard I/N (`text`, may be empty), else from the MPI
// launcher's rank and size; the launcher's variables are then removed, so
// that the `manibench` processes the population starts run on their own.
void placeOnShard(const std::string& text, uint32_t& shard, uint32_t& shards);

}  // namespace manibench::learning::programs
