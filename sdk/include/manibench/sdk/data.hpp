// Where a plugin finds manibench's data (the robots' URDF, meshes and facts:
// README.md, "Data folders"): one call,
//   const std::string robots = manibench::sdk::findDataDirectory("robots");
// never a path compiled in, so that an installed tree still works after it
// is moved (or unpacked from the .deb elsewhere) and an out-of-tree task
// finds the robots of the manibench it runs under.
//
// The folder is <data root>/<name>, the first data root of:
//  1. $MANIBENCH_DATA_DIR: a host sets it, when unset, to the data root of
//     its own installation (PluginRegistry::loadSearchPath), so every plugin
//     it loads, wherever that plugin lives, reads the host's data; a user
//     may set it to use other data;
//  2. <prefix>/share/manibench for the first ancestor <prefix> of the
//     plugin library's own folder that has one (a plugin installed with
//     manibench, or one in manibench's build tree, whose build/share/manibench
//     mirrors the install).
// The folder must exist: otherwise an error names every place looked at.
#pragma once

#include <manibench/sdk/common.hpp>

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace manibench::sdk {

// share/manibench, relative to an installation prefix.
inline constexpr const char* kDataSubdir = "share/manibench";
// Ancestors of a library's folder tried for <ancestor>/share/manibench:
// bin/, lib/manibench/plugins/ and lib/python3.X/dist-packages/manibench/
// are at most four levels below their prefix.
inline constexpr int kDataSearchDepth = 5;

// The folder of the shared library (or executable) holding this code. With
// the SDK's hidden visibility each plugin has its own copy of this
// function, so its address lies in the calling plugin (and, called by the
// host, in the host's executable or Python module).
inline std::filesystem::path findOwnImageFolder() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&findOwnImageFolder), &info) == 0 || info.dli_fname == nullptr)
    return {};
  std::error_code ec;
  const std::filesystem::path image = std::filesystem::canonical(info.dli_fname, ec);
  return ec ? std::filesystem::path() : image.parent_path();
}

// The installation prefix `folder` belongs to: the nearest ancestor of
// `folder` (itself included, kDataSearchDepth levels) holding the folder
// `relative` (e.g. "share/manibench/robots"); empty when none does. The
// host finds its plugins the same way.
inline std::filesystem::path findPrefixAbove(const std::filesystem::path& folder, const std::string& relative) {
  std::error_code ec;
  std::filesystem::path at = folder;
  for (int level = 0; level < kDataSearchDepth && !at.empty(); ++level) {
    if (std::filesystem::is_directory(at / relative, ec)) return at;
    if (at == at.parent_path()) break;
    at = at.parent_path();
  }
  return {};
}

// <data root>/<name> (see the top of this file); an Error (MB_NOT_FOUND)
// naming where it looked when no data root has `name`.
inline std::string findDataDirectory(const std::string& name) {
  std::error_code ec;
  std::vector<std::string> looked;
  if (const char* env = std::getenv("MANIBENCH_DATA_DIR"); env != nullptr && *env != '\0') {
    const std::filesystem::path dir = std::filesystem::path(env) / name;
    if (std::filesystem::is_directory(dir, ec)) return dir.string();
    looked.push_back(dir.string() + " ($MANIBENCH_DATA_DIR)");
  }
  const std::filesystem::path own = findOwnImageFolder();
  const std::string relative = std::string(kDataSubdir) + "/" + name;
  if (const std::filesystem::path prefix = findPrefixAbove(own, relative); !prefix.empty())
    return (prefix / relative).string();
  looked.push_back(relative + " above " + (own.empty() ? "(unknown)" : own.string()));
  std::string where;
  for (const std::string& l : looked) where += (where.empty() ? "" : ", ") + l;
  throw Error("manibench data folder '" + name + "' not found (looked in " + where +
                  "); set MANIBENCH_DATA_DIR to the folder that holds it (an installation's share/manibench)",
              MB_NOT_FOUND);
}

}  // namespace manibench::sdk
