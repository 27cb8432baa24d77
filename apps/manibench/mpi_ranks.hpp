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

// Ties an evaluation to the ranks: rank 0 receives the others' records
// (options.ranks/rank and the hooks set here), the others send theirs.
// Every rank calls prepare() before evaluatePolicy and finish() after.
class RankedEvaluation {
 public:
  explicit RankedEvaluation(MpiRanks& ranks) : ranks_(ranks) {}
  // Sets options.rank/ranks; rank 0 tells the others which episodes
  // `options.resumed` holds, the others wait for that; hooks get the
  // record exchange. `stop` ends a wait early.
  void prepare(EvaluationOptions& options, EvaluationHooks& hooks, const std::function<bool()>& stop);
  // Not rank 0: tells rank 0 this rank is done (`why` empty: complete).
  void finish(const std::string& why);
  // Not rank 0: rank 0 learns that this rank could not run.
  void fail(const std::string& message);
  // Rank 0: what ranks reported as errors.
  const std::vector<std::string>& getErrors() const { return errors_; }

 private:
  std::vector<EpisodeRecord> takeRecords();
  MpiRanks& ranks_;
  int done_ = 0;
  std::vector<std::string> errors_;
};

// The same for `demos generate`: the ranks share the objects, the others
// send each trajectory they keep and, at the end, their objects' results.
class RankedGeneration {
 public:
  explicit RankedGeneration(MpiRanks& ranks) : ranks_(ranks) {}
  // Sets options.rank/ranks; rank 0 sends options.done_objects (--resume),
  // the others wait for them; hooks get the exchange.
  void prepare(GenerationOptions& options, GenerationHooks& hooks, const std::function<bool()>& stop);
  // Not rank 0: its objects' results (formatGenerationResult), or that it
  // failed.
  void finish(const std::string& result_json);
  void fail(const std::string& message);
  const std::vector<std::string>& getErrors() const { return errors_; }

 private:
  std::vector<Trajectory> takeTrajectories();
  MpiRanks& ranks_;
  int done_ = 0;
  std::vector<GenerationObjectResult> results_;
  std::vector<std::string> errors_;
};

// Not rank 0: waits for rank 0's kMpiStart; its payload.
std::string waitForStart(MpiRanks& ranks, const std::function<bool()>& stop);

}  // namespace manibench::cli
