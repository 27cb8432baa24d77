// MPI ranks through libmanibench_mpi.so (mpi_ranks.hpp, docs/distributed.md).
#include "mpi_ranks.hpp"

#include <manibench/plugin_registry.hpp>

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
  // Beside this program (the build tree), then in the library folder of
  // the installation this program is in, found from where it is as the
  // plugins are (a moved install or the .deb too), then at the configured
  // prefix.
  char self[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  const std::filesystem::path dir =
      n > 0 ? std::filesystem::path(std::string(self, std::size_t(n))).parent_path() : ".";
  std::vector<std::string> candidates = {(dir / "libmanibench_mpi.so").string()};
  if (const std::string modules = findHostModuleDir(); !modules.empty())
    candidates.push_back(modules + "/libmanibench_mpi.so");
  candidates.push_back(std::string(MANIBENCH_INSTALL_LIBDIR) + "/manibench/libmanibench_mpi.so");
  std::string errors;
  for (const std::string& path : candidates) {
    if (access(path.c_str(), R_OK) != 0) continue;
    // RTLD_GLOBAL: Open MPI's own components resolve libmpi's symbols.
    module_->handle = dlopen(path.c_str(), RTLD_NOW | RTLD_GLOBAL);
    if (module_->handle) break;
    errors += std::string("; ") + dlerror();
  }
  if (!module_->handle) {
    std::string looked;
    for (const std::string& path : candidates) looked += (looked.empty() ? "" : ", ") + path;
    throw std::runtime_error("started by mpirun, but this build has no MPI module (looked for " + looked + errors +
                             "): build with Debian's libopenmpi-dev installed (scripts/install-deps)");
  }
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

std::string RankedRun::exchangeStart(const std::string& start, const std::function<bool()>& stop) {
  if (isRankZero()) {
    for (int r = 1; r < ranks_.getSize(); ++r) ranks_.send(r, kMpiStart, start);
    return start;
  }
  int source = 0, tag = 0;
  std::string bytes;
  while (!ranks_.receive(source, tag, bytes) || tag != kMpiStart) {
    if (stop && stop()) throw std::runtime_error("stopped before rank 0 started the run");
    usleep(10000);
  }
  return bytes;
}

void RankedRun::receive(const std::function<void(const std::string&)>& on_record,
                        const std::function<void(const std::string&)>& on_done) {
  int source = 0, tag = 0;
  std::string bytes;
  while (ranks_.receive(source, tag, bytes)) {
    if (tag == kMpiRecord) on_record(bytes);
    if (tag == kMpiError) errors_.push_back("rank " + std::to_string(source) + ": " + bytes);
    if (tag == kMpiDone) {
      ++done_;
      on_done(bytes);
    }
  }
}

void RankedRun::finish(const std::string& payload) {
  if (!isRankZero()) ranks_.send(0, kMpiDone, payload);
}

void RankedRun::fail(const std::string& message) {
  if (isRankZero()) return;
  ranks_.send(0, kMpiError, message);
  ranks_.send(0, kMpiDone, "");
}

void RankedEvaluation::prepare(EvaluationOptions& options, EvaluationHooks& hooks,
                               const std::function<bool()>& stop) {
  options.rank = uint32_t(ranks_.getRank());
  options.ranks = uint32_t(ranks_.getSize());
  // The indices of the episodes rank 0's journal has (only they matter to
  // the others: which episodes not to run).
  std::string done;
  for (const EpisodeRecord& r : options.resumed) {
    const uint64_t index = r.spec.index;
    done.append(reinterpret_cast<const char*>(&index), sizeof(index));
  }
  done = exchangeStart(done, stop);
  if (isRankZero()) {
    hooks.take_remote = [this] {
      std::vector<EpisodeRecord> records;
      receive([&](const std::string& bytes) { records.push_back(unpackEpisodeRecord(bytes)); },
              [this](const std::string& why) {
                if (!why.empty() && why != "complete") errors_.push_back("a rank stopped: " + why);
              });
      return records;
    };
    hooks.remote_done = [this] { return areOthersDone(); };
    return;
  }
  options.resumed.clear();
  for (std::size_t at = 0; at + 8 <= done.size(); at += 8) {
    EpisodeRecord r;
    std::memcpy(&r.spec.index, done.data() + at, 8);
    options.resumed.push_back(r);
  }
  auto previous = hooks.on_episode;
  hooks.on_episode = [this, previous](EpisodeRecord& r) {
    if (previous) previous(r);
    ranks_.send(0, kMpiRecord, packEpisodeRecord(r));
  };
}

void RankedGeneration::prepare(GenerationOptions& options, GenerationHooks& hooks,
                               const std::function<bool()>& stop) {
  options.rank = uint32_t(ranks_.getRank());
  options.ranks = uint32_t(ranks_.getSize());
  std::string done;
  for (const std::string& object : options.done_objects) done += object + "\n";
  done = exchangeStart(done, stop);
  if (isRankZero()) {
    hooks.take_remote = [this] {
      std::vector<Trajectory> trajectories;
      receive(
          [&](const std::string& bytes) {
            EpisodeRecord r = unpackEpisodeRecord(bytes);
            if (r.trajectory) trajectories.push_back(*r.trajectory);
          },
          [this](const std::string& results) {
            if (results.empty()) return;
            const auto json = nlohmann::json::parse(results);
            for (const auto& [object, o] : json.at("objects").items())
              results_.push_back({object, o.at("kept"), o.at("attempts"), o.at("failures")});
          });
      return trajectories;
    };
    hooks.remote_done = [this] { return areOthersDone(); };
    hooks.take_remote_results = [this] { return std::move(results_); };
    return;
  }
  std::istringstream objects(done);
  options.done_objects.clear();
  for (std::string object; std::getline(objects, object);) options.done_objects.insert(object);
  hooks.on_kept = [this](const Trajectory& t) {
    EpisodeRecord r;
    r.trajectory = std::make_shared<Trajectory>(t);
    ranks_.send(0, kMpiRecord, packEpisodeRecord(r));
  };
}

}  // namespace manibench::cli
