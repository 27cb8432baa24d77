// What every training program of the learning module takes, whatever it
// learns (demonstrations: trainer.hpp's TrainOptions; SAC online:
// sac_trainer.hpp's SacOptions, both built on this): where it writes, its
// algorithm and networks, its seed, threads and device, its checkpoint and
// log cadence, how often and how much it evaluates, and how it was
// started. One check, and one layout in DIR/train.yaml:
//
//   out_dir, algorithm: {...}, network: {...}, seed, threads, device,
//   checkpoint_every, log_every, command       (top level)
//   evaluation: {every, episodes, seed, ...}   (each program adds its own
//                                                evaluation keys here)
//
// readRun also reads the layouts written before this one (SAC's flat
// eval_every, eval_episodes, eval_seed), so a run directory written by an
// older manibench still resumes.
#pragma once

#include <manibench/learning/algorithms.hpp>
#include <manibench/learning/networks.hpp>

#include <cstdint>
#include <string>

namespace YAML {
class Node;
}

namespace manibench::learning {

struct RunOptions {
  std::string out_dir;
  AlgorithmOptions algorithm;
  NetOptions network;
  uint64_t seed = 0;
  int threads = 1;
  std::string device = "cpu";
  int64_t checkpoint_every = 1000;  // in the program's unit: iterations, or env steps (SAC)
  int64_t log_every = 100;          // (the same unit) per log.csv row
  // Success of the current policy every eval_every units (0: never) and at
  // the end: eval_episodes per object, from base seed eval_seed (not 0,
  // `demos generate`'s default, so that the episodes are not the
  // demonstrations' own).
  int64_t eval_every = 0;
  uint32_t eval_episodes = 10;
  uint64_t eval_seed = 1000;
  std::string command;  // how it was started, for train.yaml

  // A LearningError naming the option (as the command line spells it)
  // when one is out of range.
  void checkRun() const;
  // The shared fields into `node` (the layout above); `node["evaluation"]`
  // is a map the program may add to.
  void writeRun(YAML::Node& node) const;
  // Reads what writeRun wrote, or an older layout; `algorithm` names the
  // defaults of what train.yaml omits.
  void readRun(const YAML::Node& node);

 protected:
  RunOptions(const std::string& algorithm_name, int64_t checkpoint_every_default, int64_t log_every_default);
};

}  // namespace manibench::learning
