#include <manibench/plugin_registry.hpp>

#include <manibench/sdk/data.hpp>

#include <boost/dll/shared_library.hpp>

#include <dlfcn.h>
#include <link.h>
#include <sys/auxv.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <sstream>

namespace fs = std::filesystem;

namespace manibench {
namespace {

// Libraries stay loaded for the life of the process: descriptors, names and
// function pointers handed out by the registry point into them. Deliberately
// leaked so no static destructor unloads them at exit either.
void keepLoadedForever(boost::dll::shared_library library) {
  static std::mutex mutex;
  static auto* libraries = new std::vector<boost::dll::shared_library>();
  std::lock_guard<std::mutex> lock(mutex);
  libraries->push_back(std::move(library));
}

std::string abiString(unsigned major, unsigned minor) {
  return std::to_string(major) + "." + std::to_string(minor);
}

// The smallest struct a plugin may hand us for each kind: the size the
// oldest accepted minor version (kRequiredAbiMinor) defined. ABI 1.2's
// state functions, 1.4's policy controller and 1.5's reset_episode are optional: an older
// plugin ends before them.
std::size_t calcMinimumDescriptorSize(uint32_t kind) {
  static_assert(kRequiredAbiMinor < 2, "raise the minimum sizes with kRequiredAbiMinor");
  switch (kind) {
    case MB_KIND_TASK: return offsetof(mb_task_descriptor, get_state);
    case MB_KIND_CONTROLLER: return offsetof(mb_controller_descriptor, get_state);
    case MB_KIND_POLICY: return offsetof(mb_policy_descriptor, controller);
    default: return 0;
  }
}

bool hasAllFunctions(const mb_descriptor& d) {
  switch (d.kind) {
    case MB_KIND_TASK: {
      const auto& t = reinterpret_cast<const mb_task_descriptor&>(d);
      return t.create && t.destroy && t.get_info && t.list_objects && t.build_scene &&
             t.reset && t.observe && t.compute_reward && t.evaluate_success;
    }
    case MB_KIND_CONTROLLER: {
      const auto& c = reinterpret_cast<const mb_controller_descriptor&>(d);
      return c.create && c.destroy && c.get_info && c.reset && c.compute;
    }
    case MB_KIND_POLICY: {
      const auto& p = reinterpret_cast<const mb_policy_descriptor&>(d);
      return p.create && p.destroy && p.reset && p.act;
    }
    default: return false;
  }
}

void appendExistingDirectory(std::vector<std::string>& out, const std::string& dir) {
  if (dir.empty()) return;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  const std::string canonical = fs::canonical(dir, ec).string();
  if (ec) return;
  if (std::find(out.begin(), out.end(), canonical) == out.end()) out.push_back(canonical);
}

// The folder of the image holding the host (this code): the executable, or
// the Python module. dladdr names the main program by its argv[0] (a bare
// "manibench" when a shell or subprocess found it through PATH), so the
// main program is recognised by its program headers (AT_PHDR) and read
// from /proc/self/exe instead.
fs::path findHostImageFolder() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&findHostImageFolder), &info) == 0 || info.dli_fbase == nullptr)
    return {};
  const auto* header = static_cast<const ElfW(Ehdr)*>(info.dli_fbase);
  const bool main_program = reinterpret_cast<std::uintptr_t>(info.dli_fbase) + header->e_phoff == getauxval(AT_PHDR);
  std::error_code ec;
  const fs::path image =
      fs::canonical(main_program ? "/proc/self/exe" : (info.dli_fname ? info.dli_fname : ""), ec);
  return ec ? fs::path() : image.parent_path();
}

}  // namespace

const char* toString(PluginKind kind) {
  switch (kind) {
    case PluginKind::Task: return "task";
    case PluginKind::Controller: return "controller";
    case PluginKind::Policy: return "policy";
  }
  return "unknown";
}

std::vector<std::string> PluginRegistry::calcDefaultSearchPath() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("MANIBENCH_PLUGIN_PATH")) {
    std::stringstream stream(env);
    std::string dir;
    while (std::getline(stream, dir, ':')) appendExistingDirectory(dirs, dir);
  }
  if (const char* home = std::getenv("HOME"))
    appendExistingDirectory(dirs, std::string(home) + "/.local/lib/manibench/plugins");
  const std::string prefix = findHostPrefix();
  if (!prefix.empty()) appendExistingDirectory(dirs, prefix + "/" + MANIBENCH_PLUGIN_SUBDIR);
  return dirs;
}

void PluginRegistry::loadSearchPath() {
  // Before any plugin is created: tasks read it through
  // sdk::findDataDirectory. setenv here, at start-up, before threads read
  // the environment; an explicit setting (the user's) is kept.
  const std::string data = findHostDataRoot();
  if (!data.empty()) setenv("MANIBENCH_DATA_DIR", data.c_str(), 0);
  loadDirectories(calcDefaultSearchPath());
}

std::string findHostPrefix() {
  return sdk::findPrefixAbove(findHostImageFolder(), MANIBENCH_PLUGIN_SUBDIR).string();
}

std::string findHostModuleDir() {
  const std::string prefix = findHostPrefix();
  return prefix.empty() ? "" : (fs::path(prefix) / fs::path(MANIBENCH_PLUGIN_SUBDIR).parent_path()).string();
}

std::string findHostDataRoot() {
  const std::string prefix = findHostPrefix();
  std::error_code ec;
  if (prefix.empty() || !fs::is_directory(prefix + "/" + sdk::kDataSubdir, ec)) return "";
  return prefix + "/" + sdk::kDataSubdir;
}

void PluginRegistry::loadDirectories(const std::vector<std::string>& directories) {
  for (const std::string& dir : directories) {
    std::error_code ec;
    std::vector<fs::path> files;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
      if (it->path().extension() == ".so") files.push_back(it->path());
    if (ec) {
      failures_.push_back({dir, "cannot read plugin directory " + dir + ": " + ec.message()});
      continue;
    }
    std::sort(files.begin(), files.end());  // load order must not depend on the file system
    for (const fs::path& file : files) {
      // An earlier directory's library of the same file name shadows this
      // one, even when it was refused: first match wins, as in PATH.
      const std::string file_name = file.filename().string();
      if (std::find(seen_file_names_.begin(), seen_file_names_.end(), file_name) !=
          seen_file_names_.end())
        continue;
      seen_file_names_.push_back(file_name);
      try {
        loadLibrary(file.string());
      } catch (const PluginError& e) {
        failures_.push_back({file.string(), e.what()});
      }
    }
  }
}

std::size_t PluginRegistry::loadLibrary(const std::string& path) {
  std::error_code ec;
  const std::string canonical = fs::canonical(path, ec).string();
  if (ec) throw PluginError("cannot load plugin " + path + ": " + ec.message());
  const auto already = std::find(loaded_canonical_paths_.begin(), loaded_canonical_paths_.end(), canonical);
  if (already != loaded_canonical_paths_.end())
    return std::size_t(already - loaded_canonical_paths_.begin());

  boost::dll::shared_library library;
  try {
    // rtld_now: an unresolved symbol fails here, with the linker's message,
    // instead of crashing at the first call.
    library.load(path, boost::dll::load_mode::rtld_now | boost::dll::load_mode::rtld_local);
  } catch (const std::exception& e) {
    throw PluginError("cannot load plugin " + path + ": " + e.what());
  }
  if (!library.has(MB_ENTRY_POINT_NAME))
    throw PluginError("not a manibench plugin: " + path + " exports no entry point '" +
                      MB_ENTRY_POINT_NAME +
                      "' (define it with MANIBENCH_PLUGIN_LIBRARY, see sdk/include/manibench/abi.h)");
  const void* entry_address = library.get<const void*>(MB_ENTRY_POINT_NAME);
  if (entry_address == nullptr)
    throw PluginError("plugin " + path + ": entry point '" MB_ENTRY_POINT_NAME "' is null");
  const auto entry = reinterpret_cast<mb_entry_fn>(entry_address);
  const mb_manifest* manifest = nullptr;
  try {
    manifest = entry();
  } catch (const std::exception& e) {
    throw PluginError("plugin " + path + ": the entry point threw: " + e.what());
  } catch (...) {
    throw PluginError("plugin " + path + ": the entry point threw");
  }
  if (manifest == nullptr)
    throw PluginError("plugin " + path + ": the entry point returned no manifest");

  const std::string host_abi = abiString(MB_ABI_MAJOR, MB_ABI_MINOR);
  // abi_major/minor sit right after struct_size; read them only if present.
  if (!MB_HAS_FIELD(mb_manifest, abi_minor, manifest->struct_size))
    throw PluginError("plugin " + path + ": manifest struct_size is " +
                      std::to_string(manifest->struct_size) + " bytes, too small to hold a version (host ABI " +
                      host_abi + " expects " + std::to_string(sizeof(mb_manifest)) + ")");
  if (manifest->abi_major != MB_ABI_MAJOR || manifest->abi_minor < kRequiredAbiMinor)
    throw PluginError("plugin " + path + " was built for manibench plugin ABI " +
                      abiString(manifest->abi_major, manifest->abi_minor) +
                      ", but this host speaks ABI " + host_abi + " and needs major " +
                      std::to_string(MB_ABI_MAJOR) + " with minor >= " +
                      std::to_string(kRequiredAbiMinor) + "; rebuild the plugin against this SDK");
  if (manifest->struct_size < sizeof(mb_manifest))
    throw PluginError("plugin " + path + ": manifest struct_size is " +
                      std::to_string(manifest->struct_size) + " bytes, but ABI " +
                      abiString(MB_ABI_MAJOR, kRequiredAbiMinor) + " needs at least " +
                      std::to_string(sizeof(mb_manifest)));
  if (manifest->descriptor_count > 0 && manifest->descriptors == nullptr)
    throw PluginError("plugin " + path + ": manifest lists " +
                      std::to_string(manifest->descriptor_count) + " descriptors but no array");

  const std::size_t library_index = libraries_.size();
  std::vector<PluginEntry> new_entries;
  for (uint32_t i = 0; i < manifest->descriptor_count; ++i) {
    const mb_descriptor* d = manifest->descriptors[i];
    const std::string where = "plugin " + path + ": descriptor #" + std::to_string(i);
    if (d == nullptr) throw PluginError(where + " is null");
    if (d->struct_size < sizeof(mb_descriptor))
      throw PluginError(where + " has struct_size " + std::to_string(d->struct_size) +
                        ", smaller than its header (" + std::to_string(sizeof(mb_descriptor)) +
                        " bytes)");
    const std::size_t minimum = calcMinimumDescriptorSize(d->kind);
    if (minimum == 0) {
      // A newer minor version may add kinds this host cannot use: skip them.
      if (manifest->abi_minor > MB_ABI_MINOR) continue;
      throw PluginError(where + " has unknown kind " + std::to_string(d->kind) +
                        " (this host knows task=1, controller=2, policy=3)");
    }
    const std::string kind = toString(static_cast<PluginKind>(d->kind));
    if (d->name == nullptr || d->name[0] == '\0')
      throw PluginError(where + " (" + kind + ") has no name");
    if (d->struct_size < minimum)
      throw PluginError(where + " (" + kind + " '" + d->name + "') has struct_size " +
                        std::to_string(d->struct_size) + ", but ABI " +
                        abiString(MB_ABI_MAJOR, kRequiredAbiMinor) + " needs at least " +
                        std::to_string(minimum) + " bytes for a " + kind + " descriptor");
    if (!hasAllFunctions(*d))
      throw PluginError(where + " (" + kind + " '" + d->name + "') lacks a required function pointer");
    const PluginKind plugin_kind = static_cast<PluginKind>(d->kind);
    for (const PluginEntry& e : new_entries)
      if (e.kind == plugin_kind && e.name == d->name)
        throw PluginError("plugin " + path + " registers " + kind + " '" + d->name + "' twice");
    if (const PluginEntry* existing = findEntry(plugin_kind, d->name))
      throw PluginError("duplicate " + kind + " name '" + d->name + "': registered by " +
                        libraries_[existing->library].path + " and again by " + path);
    new_entries.push_back({plugin_kind, d->name, d->summary ? d->summary : "", library_index, d});
  }

  // Everything checked: commit.
  LoadedLibrary record;
  record.path = canonical;
  record.name = manifest->library_name ? manifest->library_name : fs::path(path).stem().string();
  record.version = manifest->library_version ? manifest->library_version : "";
  record.abi_major = manifest->abi_major;
  record.abi_minor = manifest->abi_minor;
  libraries_.push_back(std::move(record));
  entries_.insert(entries_.end(), new_entries.begin(), new_entries.end());
  loaded_canonical_paths_.push_back(canonical);
  keepLoadedForever(std::move(library));
  return library_index;
}

const PluginEntry* PluginRegistry::findEntry(PluginKind kind, const std::string& name) const {
  for (const PluginEntry& e : entries_)
    if (e.kind == kind && e.name == name) return &e;
  return nullptr;
}

std::vector<std::string> PluginRegistry::getNames(PluginKind kind) const {
  std::vector<std::string> names;
  for (const PluginEntry& e : entries_)
    if (e.kind == kind) names.push_back(e.name);
  std::sort(names.begin(), names.end());
  return names;
}

const PluginEntry& PluginRegistry::getEntry(PluginKind kind, const std::string& name) const {
  if (const PluginEntry* e = findEntry(kind, name)) return *e;
  std::string message = std::string("no ") + toString(kind) + " named '" + name + "'";
  const std::vector<std::string> names = getNames(kind);
  if (names.empty()) {
    message += "; no " + std::string(toString(kind)) + " is loaded";
  } else {
    message += "; available: ";
    for (std::size_t i = 0; i < names.size(); ++i) message += (i ? ", " : "") + names[i];
  }
  if (!failures_.empty())
    message += " (" + std::to_string(failures_.size()) +
               " plugin librar" + (failures_.size() == 1 ? "y" : "ies") +
               " failed to load; `manibench list` shows why)";
  throw PluginError(message);
}

const mb_task_descriptor& PluginRegistry::getTask(const std::string& name) const {
  return *reinterpret_cast<const mb_task_descriptor*>(getEntry(PluginKind::Task, name).descriptor);
}
const mb_controller_descriptor& PluginRegistry::getController(const std::string& name) const {
  return *reinterpret_cast<const mb_controller_descriptor*>(
      getEntry(PluginKind::Controller, name).descriptor);
}
const mb_policy_descriptor& PluginRegistry::getPolicy(const std::string& name) const {
  return *reinterpret_cast<const mb_policy_descriptor*>(getEntry(PluginKind::Policy, name).descriptor);
}

std::string getPolicyController(const mb_policy_descriptor& policy) {
  if (!MB_HAS_FIELD(mb_policy_descriptor, controller, policy.header.struct_size) || policy.controller == nullptr)
    return "";
  return policy.controller;
}

}  // namespace manibench
