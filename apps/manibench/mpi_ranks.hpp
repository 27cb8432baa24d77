// MPI ranks for `mpirun -np R manibench eval` (docs/distributed.md): the
// program does not link MPI; when mpirun starts it, it loads
// libmanibench_mpi.so (distributed/) with dlopen and talks through its few
// calls. Rank 0 runs its part of the episodes and writes every file; the
// other ranks run theirs and send each finished episode's record to rank 0.
#pragma once

#include <manibench/demos.hpp>
#include <manibench/evaluation.hpp>

#include <memory>
#include <string>
#include <vector>

namespace manibench::cli {

class MpiRanks {
 public:
  // Whether an MPI launcher (Open MPI's mpirun, or a PMIx/PMI one such as
  // srun) started this process.
  static bool isStartedByMpi();
  // Loads the module and initializes MPI; throws naming where the module
  // was looked for when this build has none.
  MpiRanks();
  ~MpiRanks();  // MPI_Finalize
  MpiRanks(const MpiRanks&) = delete;
  MpiRanks& operator=(const MpiRanks&) = delete;
  int getRank() const { return rank_; }
  int getSize() const { return size_; }
  void send(int destination, int tag, const std::string& bytes);
  // A message that waits, without blocking: false when none.
  bool receive(int& source, int& tag, std::string& bytes);

 private:
  struct Module;
  std::unique_ptr<Module> module_;
  int rank_ = 0, size_ = 1;
};

// The messages between the ranks.
enum MpiTag : int {
  kMpiStart = 1,   // 0 -> r: the episode indices already done (--resume), u64 each
  kMpiRecord = 2,  // r -> 0: one finished episode (packEpisodeRecord)
  kMpiDone = 3,    // r -> 0: its part ended ("complete" or why not)
  kMpiError = 4,   // r -> 0: it could not run (the message), then kMpiDone
};

// What an evaluation and a generation share over the ranks: rank 0 sends
// the others a start message (what a resumed run has done) and receives
// their records, errors and ends; the others wait for the start, then send.
class RankedRun {
 public:
  explicit RankedRun(MpiRanks& ranks) : ranks_(ranks) {}
  // Not rank 0: tells rank 0 this rank is done (`payload`: why not
  // complete, or the generation's results).
  void finish(const std::string& payload);
  // Not rank 0: rank 0 learns that this rank could not run.
  void fail(const std::string& message);
  // Rank 0: what ranks reported as errors.
  const std::vector<std::string>& getErrors() const { return errors_; }

 protected:
  // Rank 0 sends `start` to every other rank and returns it; the others
  // wait for it (`stop` ends the wait) and return what came.
  std::string exchangeStart(const std::string& start, const std::function<bool()>& stop);
  // Rank 0: the waiting messages; records to `on_record`, each end's
  // payload to `on_done`.
  void receive(const std::function<void(const std::string&)>& on_record,
               const std::function<void(const std::string&)>& on_done);
  bool areOthersDone() const { return done_ == ranks_.getSize() - 1; }
  bool isRankZero() const { return ranks_.getRank() == 0; }

  MpiRanks& ranks_;
  int done_ = 0;
  std::vector<std::string> errors_;
};

// Ties an evaluation to the ranks: rank 0 receives the others' records
// (options.ranks/rank and the hooks set here), the others send theirs.
// Every rank calls prepare() before evaluatePolicy and, but rank 0,
// finish() or fail() after.
class RankedEvaluation : public RankedRun {
 public:
  using RankedRun::RankedRun;
  // Sets options.rank/ranks; rank 0 tells the others which episodes
  // `options.resumed` holds, the others wait for that; hooks get the
  // record exchange. `stop` ends a wait early.
  void prepare(EvaluationOptions& options, EvaluationHooks& hooks, const std::function<bool()>& stop);
};

// The same for `demos generate`: the ranks share the objects, the others
// send each trajectory they keep and, at the end (finish), their objects'
// results (formatGenerationResult).
class RankedGeneration : public RankedRun {
 public:
  using RankedRun::RankedRun;
  // Sets options.rank/ranks; rank 0 sends options.done_objects (--resume),
  // the others wait for them; hooks get the exchange.
  void prepare(GenerationOptions& options, GenerationHooks& hooks, const std::function<bool()>& stop);

 private:
  std::vector<GenerationObjectResult> results_;
};

}  // namespace manibench::cli
