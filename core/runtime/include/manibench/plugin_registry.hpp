// Finds, loads and checks plugin libraries, and finds tasks, controllers and
// policies in them by name.
//
// Search path, first match wins (by file name, as PATH does for programs):
//   1. $MANIBENCH_PLUGIN_PATH (colon-separated directories)
//   2. ~/.local/lib/manibench/plugins
//   3. <prefix>/lib/manibench/plugins (lib/<multiarch>/... for /usr), the
//      host's own installation or build tree: <prefix> is the nearest
//      ancestor of the folder of the host's executable (or Python module)
//      that has that folder (findHostPrefix). Nothing is compiled in, so an
//      installed tree keeps working when moved.
// A library is loaded with Boost.DLL and checked: ABI major equal to the
// host's, minor at least the host's required minor, every struct large
// enough. Descriptors of kinds this host does not know are skipped when the
// plugin's minor version is newer (a minor version may add kinds), refused
// otherwise. A refused library is recorded with a message naming the file and
// both sides' values; the others keep working. Libraries are never unloaded
// while the process runs: descriptors point into them.
#pragma once

#include <manibench/abi.h>
#include <manibench/error.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench {

// The oldest plugin minor version this host accepts (for ABI major 1).
inline constexpr uint16_t kRequiredAbiMinor = 0;

// A plugin could not be loaded, or a name could not be resolved.
class PluginError : public Error {
 public:
  using Error::Error;
};

enum class PluginKind { Task = MB_KIND_TASK, Controller = MB_KIND_CONTROLLER, Policy = MB_KIND_POLICY };
const char* toString(PluginKind kind);

struct LoadedLibrary {
  std::string path;
  std::string name;     // manifest library_name
  std::string version;  // manifest library_version
  uint16_t abi_major = 0;
  uint16_t abi_minor = 0;
};

struct PluginEntry {
  PluginKind kind;
  std::string name;
  std::string summary;
  std::size_t library;  // index into PluginRegistry::getLibraries()
  const mb_descriptor* descriptor;
};

struct LoadFailure {
  std::string path;
  std::string message;
};

// The installation prefix (or build tree) of the running host, found from
// its executable's or Python module's own location; "" when not found.
std::string findHostPrefix();
// <prefix>/share/manibench when it exists (the robots: sdk/data.hpp), else "".
std::string findHostDataRoot();
// <prefix>/<libdir>/manibench, the folder of the host's own modules (the
// MPI module; the plugins are in its plugins/), else "".
std::string findHostModuleDir();

// The controller a policy's actions are for (ABI 1.4), or "" when it names
// none (a policy built against ABI 1.3 or older never does).
std::string getPolicyController(const mb_policy_descriptor& policy);

class PluginRegistry {
 public:
  PluginRegistry() = default;

  // The directories of the search path, in order; only existing ones.
  static std::vector<std::string> calcDefaultSearchPath();

  // Loads every *.so in the given directories (default: the search path).
  // Failures are recorded (getFailures), never thrown. loadSearchPath also
  // sets MANIBENCH_DATA_DIR to findHostDataRoot() unless it is set, so that
  // the plugins it loads read this installation's data (sdk/data.hpp).
  void loadSearchPath();
  void loadDirectories(const std::vector<std::string>& directories);
  // Loads one library and returns its index in getLibraries(); throws
  // PluginError with the precise reason. A library already loaded (same
  // canonical path) is not loaded twice: its index is returned.
  std::size_t loadLibrary(const std::string& path);

  const std::vector<LoadedLibrary>& getLibraries() const { return libraries_; }
  const std::vector<PluginEntry>& getEntries() const { return entries_; }
  const std::vector<LoadFailure>& getFailures() const { return failures_; }

  // Throws PluginError listing the available names of that kind (and how
  // many libraries failed to load) when `name` is unknown.
  const PluginEntry& getEntry(PluginKind kind, const std::string& name) const;
  const PluginEntry* findEntry(PluginKind kind, const std::string& name) const;
  std::vector<std::string> getNames(PluginKind kind) const;

  const mb_task_descriptor& getTask(const std::string& name) const;
  const mb_controller_descriptor& getController(const std::string& name) const;
  const mb_policy_descriptor& getPolicy(const std::string& name) const;

 private:
  std::vector<LoadedLibrary> libraries_;
  std::vector<PluginEntry> entries_;
  std::vector<LoadFailure> failures_;
  std::vector<std::string> loaded_canonical_paths_;
  std::vector<std::string> seen_file_names_;  // shadowing in loadDirectories
};

}  // namespace manibench
