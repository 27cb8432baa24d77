// MPI ranks through libmanibench_mpi.so (mpi_ranks.hpp, docs/distributed.md).
#include "mpi_ranks.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

namespace manibench::cli {

#ifndef MANIBENCH_INSTALL_LIBDIR
#define MANIBENCH_INSTALL_LIBDIR "/usr/local/lib"
#endif

struct MpiRanks::Module {
  void* handle = nullptr;
  int (*init)(int*, int*) = nullptr;
  int (*send)(int, int, const void*, uint64_t) = nullptr;
  int (*probe)(int*, int*, int*, uint64_t*) = nullptr;
  int (*receive)(int, int, void*, uint64_t) = nullptr;
  int (*finalize)() = nullptr;
};

bool MpiRanks::isStartedByMpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"})
    if (std::getenv(name)) return true;
  return false;
}

MpiRanks::MpiRanks() : module_(std::make_unique<Module>()) {
  // Beside this program (the build tree), then the install's library folder.
  char self[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  const std::filesystem::path dir =
      n > 0 ? std::filesystem::path(std::string(self, std::size_t(n))).parent_path() : ".";
  const std::vector<std::string> candidates = {
      (dir / "libmanibench_mpi.so").string(),
      std::string(MANIBENCH_INSTALL_LIBDIR) + "/manibench/libmanibench_mpi.so"};
  std::string errors;
  for (const std::string& path : candidates) {
    if (access(path.c_str(), R_OK) != 0) continue;
    // RTLD_GLOBAL: Open MPI's own components resolve libmpi's symbols.
    module_->handle = dlopen(path.c_str(), RTLD_NOW | RTLD_GLOBAL);
    if (module_->handle) break;
    errors += std::string("; ") + dlerror();
  }
  if (!module_->handle)
    throw std::runtime_error("started by mpirun, but this build has no MPI module (looked for " + candidates[0] +
                             " and " + candidates[1] + errors +
                             "): build with Debian's libopenmpi-dev installed (scripts/install-deps)");
  auto find = [&](const char* name) {
    void* symbol = dlsym(module_->handle, name);
    if (!symbol) throw std::runtime_error(std::string("the MPI module lacks ") + name);
    return symbol;
  };
  module_->init = reinterpret_cast<int (*)(int*, int*)>(find("manibench_mpi_init"));
  module_->send = reinterpret_cast<int (*)(int, int, const void*, uint64_t)>(find("manibench_mpi_send"));
  module_->probe = reinterpret_cast<int (*)(int*, int*, int*, uint64_t*)>(find("manibench_mpi_probe"));
  module_->receive = reinterpret_cast<int (*)(int, int, void*, uint64_t)>(find("manibench_mpi_receive"));
  module_->finalize = reinterpret_cast<int (*)()>(find("manibench_mpi_finalize"));
  if (const int rc = module_->init(&rank_, &size_))
    throw std::runtime_error("MPI_Init failed (error " + std::to_string(rc) + ")");
}

MpiRanks::~MpiRanks() {
  // Leaving on an error: no MPI_Finalize, whose fence would wait for ranks
  // that wait for this one; mpirun ends the job on the non-zero exit.
  if (std::uncaught_exceptions() == 0 && module_->finalize) module_->finalize();
}

void MpiRanks::send(int destination, int tag, const std::string& bytes) {
  if (const int rc = module_->send(destination, tag, bytes.data(), bytes.size()))
    throw std::runtime_error("MPI_Send to rank " + std::to_string(destination) + " failed (error " +
                             std::to_string(rc) + ")");
}

bool MpiRanks::receive(int& source, int& tag, std::string& bytes) {
  int found = 0;
  uint64_t size = 0;
  if (const int rc = module_->probe(&found, &source, &tag, &size))
    throw std::runtime_error("MPI_Iprobe failed (error " + std::to_string(rc) + ")");
  if (!found) return false;
  bytes.resize(size);
  if (const int rc = module_->receive(source, tag, bytes.data(), size))
    throw std::runtime_error("MPI_Recv from rank " + std::to_string(source) + " failed (error " +
                             std::to_string(rc) + ")");
  return true;
}

void RankedEvaluation::prepare(EvaluationOptions& options, EvaluationHooks& hooks,
                               const std::function<bool()>& stop) {
  options.rank = uint32_t(ranks_.getRank());
  options.ranks = uint32_t(ranks_.getSize());
  if (ranks_.getRank() == 0) {
    std::string done;
    for (const EpisodeRecord& r : options.resumed) {
      const uint64_t index = r.spec.index;
      done.append(reinterpret_cast<const char*>(&index), sizeof(index));
    }
    for (int r = 1; r < ranks_.getSize(); ++r) ranks_.send(r, kMpiStart, done);
    hooks.take_remote = [this] { return takeRecords(); };
    hooks.remote_done = [this] { return done_ == ranks_.getSize() - 1; };
    return;
  }
  // The others: which episodes rank 0's journal has (only their indices
  // matter here), then each finished record goes to rank 0.
  const std::string bytes = waitForStart(ranks_, stop);
  options.resumed.clear();
  for (std::size_t at = 0; at + 8 <= bytes.size(); at += 8) {
    EpisodeRecord r;
    std::memcpy(&r.spec.index, bytes.data() + at, 8);
    options.resumed.push_back(r);
  }
  auto previous = hooks.on_episode;
  hooks.on_episode = [this, previous](EpisodeRecord& r) {
    if (previous) previous(r);
    ranks_.send(0, kMpiRecord, packEpisodeRecord(r));
  };
}

std::vector<EpisodeRecord> RankedEvaluation::takeRecords() {
  std::vector<EpisodeRecord> records;
  int source = 0, tag = 0;
  std::string bytes;
  while (ranks_.receive(source, tag, bytes)) {
    if (tag == kMpiRecord) records.push_back(unpackEpisodeRecord(bytes));
    if (tag == kMpiError) errors_.push_back("rank " + std::to_string(source) + ": " + bytes);
    if (tag == kMpiDone) {
      ++done_;
      if (!bytes.empty() && bytes != "complete") errors_.push_back("rank " + std::to_string(source) + ": " + bytes);
    }
  }
  return records;
}

void RankedEvaluation::finish(const std::string& why) {
  if (ranks_.getRank() != 0) ranks_.send(0, kMpiDone, why.empty() ? "complete" : why);
}

void RankedEvaluation::fail(const std::string& message) {
  if (ranks_.getRank() == 0) return;
  ranks_.send(0, kMpiError, message);
  ranks_.send(0, kMpiDone, "");
}

std::string waitForStart(MpiRanks& ranks, const std::function<bool()>& stop) {
  int source = 0, tag = 0;
  std::string bytes;
  while (!ranks.receive(source, tag, bytes) || tag != kMpiStart) {
    if (stop && stop()) throw std::runtime_error("stopped before rank 0 started the run");
    usleep(10000);
  }
  return bytes;
}

void RankedGeneration::prepare(GenerationOptions& options, GenerationHooks& hooks,
                               const std::function<bool()>& stop) {
  options.rank = uint32_t(ranks_.getRank());
  options.ranks = uint32_t(ranks_.getSize());
  if (ranks_.getRank() == 0) {
    std::string done;
    for (const std::string& object : options.done_objects) done += object + "\n";
    for (int r = 1; r < ranks_.getSize(); ++r) ranks_.send(r, kMpiStart, done);
    hooks.take_remote = [this] { return takeTrajectories(); };
    hooks.remote_done = [this] { return done_ == ranks_.getSize() - 1; };
    hooks.take_remote_results = [this] { return std::move(results_); };
    return;
  }
  std::istringstream done(waitForStart(ranks_, stop));
  options.done_objects.clear();
  for (std::string object; std::getline(done, object);) options.done_objects.insert(object);
  hooks.on_kept = [this](const Trajectory& t) {
    EpisodeRecord r;
    r.trajectory = std::make_shared<Trajectory>(t);
    ranks_.send(0, kMpiRecord, packEpisodeRecord(r));
  };
}

std::vector<Trajectory> RankedGeneration::takeTrajectories() {
  std::vector<Trajectory> trajectories;
  int source = 0, tag = 0;
  std::string bytes;
  while (ranks_.receive(source, tag, bytes)) {
    if (tag == kMpiRecord) {
      EpisodeRecord r = unpackEpisodeRecord(bytes);
      if (r.trajectory) trajectories.push_back(*r.trajectory);
    }
    if (tag == kMpiError) errors_.push_back("rank " + std::to_string(source) + ": " + bytes);
    if (tag == kMpiDone) {
      ++done_;
      if (bytes.empty()) continue;
      const auto json = nlohmann::json::parse(bytes);
      for (const auto& [object, o] : json.at("objects").items())
        results_.push_back({object, o.at("kept"), o.at("attempts"), o.at("failures")});
    }
  }
  return trajectories;
}

void RankedGeneration::finish(const std::string& result_json) {
  if (ranks_.getRank() != 0) ranks_.send(0, kMpiDone, result_json);
}

void RankedGeneration::fail(const std::string& message) {
  if (ranks_.getRank() == 0) return;
  ranks_.send(0, kMpiError, message);
  ranks_.send(0, kMpiDone, "");
}

}  // namespace manibench::cli
