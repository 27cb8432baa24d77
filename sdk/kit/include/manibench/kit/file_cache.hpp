// Files a family makes once and keeps on disk: a generated bucket's meshes,
// the convex pieces of a PartNet part (convex_decomposition.hpp). URDF
// names meshes by file, so what a family computes must exist as files
// before the host loads the URDF. A cache folder is named after what its
// content was made from (a hash the caller gives), written once: workers of
// one evaluation run in parallel, each writes into a private folder and
// renames it into place, and whoever comes second finds the folder complete
// and uses it.
#pragma once

#include <manibench/kit/common.hpp>

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <string>
#include <system_error>

namespace manibench::kit {

// $MANIBENCH_CACHE_DIR, else $XDG_CACHE_HOME/manibench, else
// ~/.cache/manibench, else the system's temporary folder.
inline std::string getDefaultCacheRoot() {
  namespace fs = std::filesystem;
  if (const char* dir = std::getenv("MANIBENCH_CACHE_DIR"); dir && *dir) return dir;
  if (const char* dir = std::getenv("XDG_CACHE_HOME"); dir && *dir) return std::string(dir) + "/manibench";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/manibench";
  return (fs::temp_directory_path() / ("manibench-cache-" + std::to_string(getuid()))).string();
}

// FNV-1a, 64 bits, over a sequence of byte strings (each followed by a
// separator, so that ("ab", "c") and ("a", "bc") differ), as 16 hex digits.
class ContentHash {
 public:
  ContentHash& add(const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      h_ ^= bytes[i];
      h_ *= 0x100000001b3ULL;
    }
    h_ ^= 0xff;
    h_ *= 0x100000001b3ULL;
    return *this;
  }
  ContentHash& add(const std::string& s) { return add(s.data(), s.size()); }
  std::string str() const {
    std::ostringstream out;
    out << std::hex << std::setw(16) << std::setfill('0') << h_;
    return out.str();
  }

 private:
  uint64_t h_ = 0xcbf29ce484222325ULL;
};

namespace detail {
constexpr const char* kCompleteStamp = ".complete";
}  // namespace detail

// Whether `folder` was written completely by writeFilesOnce.
inline bool isCompleteFolder(const std::string& folder) {
  return std::filesystem::exists(std::filesystem::path(folder) / detail::kCompleteStamp);
}

// Writes `files` (name -> text) into `folder` unless it is there complete
// already; `what` names the caller in errors ("MoveBucket"). Throws Error
// when the folder cannot be made.
inline void writeFilesOnce(const std::string& folder, const std::map<std::string, std::string>& files,
                           const std::string& what) {
  namespace fs = std::filesystem;
  const fs::path target(folder);
  if (isCompleteFolder(folder)) return;
  std::error_code ec;
  fs::create_directories(target.parent_path(), ec);
  if (ec)
    throw Error(what + ": cannot create the cache folder " + target.parent_path().string() + " (" + ec.message() +
                    "; set MANIBENCH_CACHE_DIR)",
                MB_ERROR);
  static int counter = 0;  // one process may stage several folders
  const fs::path staging = target.parent_path() / (target.filename().string() + ".tmp." + std::to_string(getpid()) +
                                                   "." + std::to_string(++counter));
  fs::remove_all(staging, ec);
  fs::create_directory(staging, ec);
  if (ec) throw Error(what + ": cannot create " + staging.string() + ": " + ec.message(), MB_ERROR);
  auto put = [&](const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    out.close();
    if (!out) throw Error(what + ": cannot write " + path.string(), MB_ERROR);
  };
  for (const auto& [name, text] : files) put(staging / name, text);
  put(staging / detail::kCompleteStamp, "");
  fs::rename(staging, target, ec);
  if (ec) {  // another process was first (or the folder is stale without its stamp)
    fs::remove_all(staging);
    if (!isCompleteFolder(folder))
      throw Error(what + ": cannot put the cache folder in place at " + target.string() + ": " + ec.message(),
                  MB_ERROR);
  }
}

}  // namespace manibench::kit
