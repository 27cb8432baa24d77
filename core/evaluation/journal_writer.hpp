// Appends lines to an evaluation's journal (docs/distributed.md, "Journal")
// with one write(2) each, so that a kill loses at most the line being
// written (which readJournal then ignores).
#pragma once

#include <manibench/evaluation.hpp>

#include <string>

namespace manibench::evaluation_detail {

// The line that ends a run's part of the journal: whether it finished, its
// wall time and worker restarts (summed over a resumed run's parts).
std::string formatJournalEnd(const EvaluationResult& result, double seconds);

class JournalWriter {
 public:
  JournalWriter() = default;
  ~JournalWriter();
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;
  // Creates `path` (and its folder) with `header` as the first line, or
  // with `append` opens it and cuts a last line a kill left unfinished.
  void open(const std::string& path, const std::string& header, bool append);
  void write(const std::string& line);  // no-op while not open
  bool isOpen() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
  std::string path_;
};

}  // namespace manibench::evaluation_detail
