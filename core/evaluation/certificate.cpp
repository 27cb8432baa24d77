// An evaluation's certificate (docs/evaluation.md, "Certificate"): the
// build, the SHA-256 of every plugin library and policy file, the merged
// configuration, each object's files as its scenes read them, the episode
// list, and the digests of the CSV files; what `eval --verify` checks a
// report against.
#include <link.h>

#include <algorithm>
#include <filesystem>
#include <manibench/evaluation.hpp>
#include <manibench/sha256.hpp>
#include <manibench/task_name.hpp>
#include <nlohmann/json.hpp>
#include <sstream>

namespace manibench {
namespace {

using Json = nlohmann::ordered_json;

struct BuildIdSearch {
  uintptr_t address = 0;  // an address inside this library's code
  std::string id;
  std::string file;  // the object that holds it ("" for the main program)
  bool found = false;
};

// The GNU build-id note of the loaded object that holds `address`.
int findBuildId(dl_phdr_info* info, size_t, void* data) {
  auto* search = static_cast<BuildIdSearch*>(data);
  bool inside = false;
  for (int i = 0; i < info->dlpi_phnum && !inside; ++i) {
    const ElfW(Phdr)& p = info->dlpi_phdr[i];
    const uintptr_t start = info->dlpi_addr + p.p_vaddr;
    inside = p.p_type == PT_LOAD && search->address >= start && search->address < start + p.p_memsz;
  }
  if (!inside) return 0;
  search->found = true;
  search->file = info->dlpi_name ? info->dlpi_name : "";
  for (int i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& p = info->dlpi_phdr[i];
    if (p.p_type != PT_NOTE) continue;
    const auto* at = reinterpret_cast<const unsigned char*>(info->dlpi_addr + p.p_vaddr);
    const unsigned char* end = at + p.p_memsz;
    while (at + sizeof(ElfW(Nhdr)) <= end) {
      const auto* note = reinterpret_cast<const ElfW(Nhdr)*>(at);
      const unsigned char* name = at + sizeof(ElfW(Nhdr));
      const unsigned char* desc = name + ((note->n_namesz + 3) & ~3u);
      if (note->n_type == NT_GNU_BUILD_ID && note->n_namesz == 4 && std::equal(name, name + 4, "GNU")) {
        static const char* digits = "0123456789abcdef";
        for (unsigned k = 0; k < note->n_descsz; ++k) {
          search->id += digits[desc[k] >> 4];
          search->id += digits[desc[k] & 15];
        }
        return 1;
      }
      at = desc + ((note->n_descsz + 3) & ~3u);
    }
  }
  return 1;
}

// A folder's regular files, in name order (so the list does not depend on
// the file system's).
std::vector<std::string> listFiles(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::is_directory(path, error)) return {path};
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(path, error); !error && it != fs::end(it); it.increment(error))
    if (it->is_regular_file(error)) files.push_back(it->path().string());
  if (error) throw EvaluationError("cannot list the policy folder '" + path + "': " + error.message());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

const std::string& getManibenchBuildId() {
  static const std::string id = [] {
    BuildIdSearch search;
    search.address = reinterpret_cast<uintptr_t>(&findBuildId);
    dl_iterate_phdr(findBuildId, &search);
    if (!search.id.empty()) return search.id;
    // No note (a linker without --build-id): the executable's bytes.
    const std::string file = search.file.empty() ? "/proc/self/exe" : search.file;
    try {
      return "sha256:" + calcFileSha256(file);
    } catch (const std::exception&) {
      return std::string("unknown");
    }
  }();
  return id;
}

std::vector<FileDigest> calcInputDigests(const PluginRegistry& registry, const EvaluationOptions& options,
                                         const std::string& controller) {
  std::vector<FileDigest> digests;
  auto library = [&](PluginKind kind, const char* role, const std::string& name) {
    const PluginEntry& entry = registry.getEntry(kind, name);
    const std::string& path = registry.getLibraries()[entry.library].path;
    digests.push_back({role, name, path, calcFileSha256(path)});
  };
  library(PluginKind::Task, "task", resolveTaskId(registry, options.task).task);
  if (!controller.empty()) library(PluginKind::Controller, "controller", controller);
  library(PluginKind::Policy, "policy", options.policy);
  for (const std::string& given : options.policy_files)
    for (const std::string& file : listFiles(given))
      if (std::none_of(digests.begin(), digests.end(), [&](const FileDigest& d) { return d.path == file; }))
        digests.push_back({"policy file", given, file, calcFileSha256(file)});
  return digests;
}

void writeCertificateJson(std::ostream& out, const EvaluationResult& result) {
  const EvaluationOptions& o = result.options;
  Json c;
  c["manibench_certificate"] = 1;
  c["manibench_version"] = getManibenchVersion();
  c["build_id"] = getManibenchBuildId();
  c["command"] = o.command;
  c["working_directory"] = o.working_directory;
  Json inputs = Json::array();
  for (const FileDigest& d : result.inputs)
    inputs.push_back({{"role", d.role}, {"name", d.name}, {"file", d.path}, {"sha256", d.sha256}});
  c["inputs"] = inputs;
  c["configuration"] = {{"sha256", calcSha256(o.configuration)}, {"yaml", o.configuration}};
  // Each object's files, as the scenes of its episodes read them (the
  // union over its episodes, in episode order).
  Json objects = Json::object();
  for (const EpisodeSpec& spec : result.planned)
    if (!objects.contains(spec.object_id)) objects[spec.object_id] = Json::array();
  for (const EpisodeRecord& r : result.episodes) {
    Json& list = objects[r.spec.object_id];
    for (const std::string& line : r.sources)
      if (std::find(list.begin(), list.end(), line) == list.end()) list.push_back(line);
  }
  c["objects"] = objects;
  Json episodes = Json::array();
  for (const EpisodeSpec& spec : result.planned) episodes.push_back({spec.object_id, spec.level, spec.seed});
  c["episodes"] = {{"seed", o.seed}, {"levels", o.levels}, {"list", episodes}};
  if (o.shards > 1) c["shard"] = std::to_string(o.shard + 1) + "/" + std::to_string(o.shards);
  std::ostringstream episodes_csv, summary_csv;
  writeEpisodesCsv(episodes_csv, result);
  writeSummaryCsv(summary_csv, result);
  c["files"] = {{"episodes.csv", calcSha256(episodes_csv.str())}, {"summary.csv", calcSha256(summary_csv.str())}};
  out << c.dump(2) << "\n";
}

}  // namespace manibench
