// The generated buckets' mesh files on disk: URDF names its convex pieces
// by file, so a generated bucket's OBJ texts are written once into a cache
// folder named after the bucket and a hash of the texts. Workers of one
// evaluation run in parallel: each writes into a private folder and renames
// it into place; whoever comes second finds the folder complete and uses it.
#include "move_bucket.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <system_error>

namespace move_bucket {

namespace fs = std::filesystem;

namespace {

constexpr const char* kStamp = ".complete";

std::string hashFiles(const std::map<std::string, std::string>& files) {
  uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a over names and texts
  for (const auto& [name, text] : files)
    for (const std::string* s : {&name, &text}) {
      for (unsigned char c : *s) {
        h ^= c;
        h *= 0x100000001b3ULL;
      }
      h ^= 0xff;
      h *= 0x100000001b3ULL;
    }
  std::ostringstream out;
  out << std::hex << std::setw(16) << std::setfill('0') << h;
  return out.str();
}

}  // namespace

std::string getDefaultCacheRoot() {
  if (const char* dir = std::getenv("MANIBENCH_CACHE_DIR"); dir && *dir) return dir;
  if (const char* dir = std::getenv("XDG_CACHE_HOME"); dir && *dir) return std::string(dir) + "/manibench";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/manibench";
  return (fs::temp_directory_path() / ("manibench-cache-" + std::to_string(getuid()))).string();
}

void writeMeshFiles(BucketModel& model, const std::string& cache_root) {
  if (model.files.empty()) return;
  const fs::path folder = fs::path(cache_root) / "buckets" / (model.id + "-" + hashFiles(model.files));
  if (fs::exists(folder / kStamp)) {
    model.base_dir = folder.string();
    return;
  }
  std::error_code ec;
  fs::create_directories(folder.parent_path(), ec);
  if (ec)
    throw Error("MoveBucket: cannot create the mesh cache folder " + folder.parent_path().string() + " (" +
                    ec.message() + "; set task.cache_dir or MANIBENCH_CACHE_DIR)",
                MB_ERROR);
  std::ostringstream private_name;
  private_name << folder.filename().string() << ".tmp." << getpid() << "." << std::hex
               << reinterpret_cast<std::uintptr_t>(&model);
  const fs::path staging = folder.parent_path() / private_name.str();
  fs::remove_all(staging, ec);
  fs::create_directory(staging, ec);
  if (ec) throw Error("MoveBucket: cannot create " + staging.string() + ": " + ec.message(), MB_ERROR);
  auto put = [&](const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    out.close();
    if (!out) throw Error("MoveBucket: cannot write " + path.string(), MB_ERROR);
  };
  for (const auto& [name, text] : model.files) put(staging / name, text);
  put(staging / kStamp, "");
  fs::rename(staging, folder, ec);
  if (ec) {  // another process was first (or the folder is stale without its stamp)
    fs::remove_all(staging);
    if (!fs::exists(folder / kStamp))
      throw Error("MoveBucket: cannot put the bucket meshes in place at " + folder.string() + ": " + ec.message(),
                  MB_ERROR);
  }
  model.base_dir = folder.string();
}

}  // namespace move_bucket
