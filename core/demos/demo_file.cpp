// The demonstration file (docs/demonstrations.md has the layout): root
// attributes describing the whole set, then one group per trajectory
// (traj_0, traj_1, ...) with ManiSkill's dataset names. Written trajectory
// by trajectory and flushed after each, so that a run killed or a file cut
// short keeps every trajectory written before.
#include <manibench/demos.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "hdf5.hpp"

namespace manibench {

using namespace demos_detail;

namespace {

constexpr const char* kFormat = "manibench-demonstrations";
constexpr uint64_t kFormatVersion = 1;
// Room in a trajectory group's header for its links (datasets, obs) and,
// as much again, its attributes: 16 left the links of a state-mode
// trajectory spilling into a second header chunk.
constexpr unsigned kTrajectoryLinks = 32;

std::string getTrajectoryName(std::size_t index) { return "traj_" + std::to_string(index); }

// traj_<n> -> n, or -1 for any other name.
long parseTrajectoryIndex(const std::string& name) {
  if (name.rfind("traj_", 0) != 0 || name.size() == 5 || name.size() > 15) return -1;
  for (std::size_t i = 5; i < name.size(); ++i)
    if (name[i] < '0' || name[i] > '9') return -1;
  return std::stol(name.substr(5));
}


std::string formatDims(const std::vector<hsize_t>& dims) {
  std::string text = "(";
  for (std::size_t k = 0; k < dims.size(); ++k) text += (k ? ", " : "") + std::to_string(dims[k]);
  return text + ")";
}

// Throws unless dataset `name` of `group` has `rank` dims with the given
// leading ones (0: any).
std::vector<hsize_t> expectDims(const Handle& group, const std::string& name,
                                std::vector<hsize_t> expected) {
  const std::vector<hsize_t> dims = readDims(group, name);
  bool ok = dims.size() == expected.size();
  for (std::size_t k = 0; ok && k < dims.size(); ++k) ok = expected[k] == 0 || expected[k] == dims[k];
  if (!ok) {
    std::string wanted = "(";
    for (std::size_t k = 0; k < expected.size(); ++k)
      wanted += (k ? ", " : "") + (expected[k] ? std::to_string(expected[k]) : std::string("*"));
    throw DemoError("dataset '" + name + "' has shape " + formatDims(dims) + ", expected " + wanted + ")");
  }
  return dims;
}

// Calls visit(parent, name, path) for each dataset of a trajectory group,
// those of its `obs` group in the visual modes ("obs/xyz").
template <class F>
void forEachDataset(const Handle& group, ObservationMode mode, F&& visit) {
  for (const std::string& link : listLinks(group)) {
    if (link == "obs" && mode != ObservationMode::State) {
      const Handle obs = openGroup(group, "obs");
      for (const std::string& inner : listLinks(obs)) visit(obs, inner, "obs/" + inner);
    } else {
      visit(group, link, link);
    }
  }
}

bool canOpenGroup(const Handle& file, const std::string& name) {
  if (!hasLink(file, name)) return false;
  try {
    openGroup(file, name);
    return true;
  } catch (const Hdf5Error&) {
    return false;
  }
}

std::string describeCut(const FileLayout& layout) {
  return "cut short: " + std::to_string(layout.bytes) + " of the " +
         std::to_string(layout.recorded_bytes) + " bytes its superblock records";
}

// Throws unless every byte of the trajectory's data (but the environment
// states, unless `with_env_states`) lies before the file's end. HDF5 reads
// what lies past a file's end as zeros: metadata fails its checksum, but an
// uncompressed dataset would read wrong values without an error.
void expectWithinFile(const Handle& group, ObservationMode mode, const FileLayout& layout,
                      bool with_env_states) {
  forEachDataset(group, mode, [&](const Handle& parent, const std::string& name, const std::string& path) {
    if (!with_env_states && (name == "env_states" || name == "env_state_offsets")) return;
    const uint64_t end = calcDataEnd(parent, name);
    if (end > layout.bytes)
      throw DemoError("lies past the cut: dataset '" + path + "' ends at byte " + std::to_string(end) +
                      ", the file at " + std::to_string(layout.bytes) + " (" + describeCut(layout) + ")");
  });
}

// --- writing ----------------------------------------------------------------------

void writeObservations(const Handle& group, const Trajectory& t) {
  const hsize_t n = t.getObservationCount();
  if (t.mode == ObservationMode::State) {
    writeDataset(group, "obs", {n, t.state_dim}, t.state);
    return;
  }
  const Handle obs = createGroup(group, "obs", 8);
  writeDataset(obs, "agent", {n, t.state_dim}, t.state);
  if (t.mode == ObservationMode::PointCloud) {
    const bool uniform = std::all_of(t.point_counts.begin(), t.point_counts.end(),
                                     [&](uint32_t c) { return c == t.point_counts.front(); });
    const hsize_t total = t.xyz.size() / 3;
    if (uniform && n > 0) {
      // ManiSkill's shapes: (T + 1, N, 3).
      const hsize_t points = t.point_counts.front();
      writeDataset(obs, "xyz", {n, points, 3}, t.xyz);
      writeDataset(obs, "rgb", {n, points, 3}, t.point_rgb);
      writeDataset(obs, "seg", {n, points, t.mask_count}, t.point_masks);
    } else {
      // Clouds of different sizes: concatenated, point_count says where.
      writeDataset(obs, "xyz", {total, 3}, t.xyz);
      writeDataset(obs, "rgb", {total, 3}, t.point_rgb);
      writeDataset(obs, "seg", {total, t.mask_count}, t.point_masks);
      writeDataset(obs, "point_count", {n}, t.point_counts);
    }
  } else {
    const std::vector<hsize_t> rgb_dims{n, t.height, t.width, 3 * hsize_t(t.camera_count)};
    if (t.image_rgb_bytes.empty())
      writeDataset(obs, "rgb", rgb_dims, t.image_rgb);
    else  // observation.rgb_dtype uint8
      writeDataset(obs, "rgb", rgb_dims, t.image_rgb_bytes);
    writeDataset(obs, "depth", {n, t.height, t.width, t.camera_count}, t.depth);
    writeDataset(obs, "seg", {n, t.height, t.width, hsize_t(t.mask_count) * t.camera_count},
                 t.image_masks);
    writeAttribute(obs, "camera_count", uint64_t(t.camera_count));
  }
  writeAttribute(obs, "mask_count", uint64_t(t.mask_count));
}

void writeTrajectory(const Handle& file, const std::string& name, const DemoFileInfo& info,
                     const Trajectory& t) {
  const Handle group = createGroup(file, name, kTrajectoryLinks);
  writeAttribute(group, "task", info.task);
  writeAttribute(group, "controller", info.controller);
  writeAttribute(group, "object_id", t.object_id);
  writeAttribute(group, "level", t.level);
  writeAttribute(group, "seed", t.seed);
  writeAttribute(group, "steps", uint64_t(t.steps));
  writeAttribute(group, "success", uint64_t(t.success ? 1 : 0));
  writeAttribute(group, "total_reward", t.total_reward);
  if (t.tracking_error >= 0) writeAttribute(group, "tracking_error", t.tracking_error);
  const hsize_t steps = t.steps;
  writeDataset(group, "actions", {steps, t.action_dim}, t.actions);
  if (!t.policy_actions.empty())
    writeDataset(group, "policy_actions", {steps, t.action_dim}, t.policy_actions);
  writeDataset(group, "rewards", {steps}, t.rewards);
  writeDataset(group, "terminated", {steps}, t.terminated);
  writeDataset(group, "truncated", {steps}, t.truncated);
  writeDataset(group, "success", {steps}, t.success_flags);
  writeDataset(group, "conditions", {steps, t.condition_count}, t.conditions);
  writeObservations(group, t);
  writeDataset(group, "env_states", {t.env_states.size()}, t.env_states);
  writeDataset(group, "env_state_offsets", {t.env_state_offsets.size()}, t.env_state_offsets);
}

// The root holds only the format's name and version; the description
// lives in group `meta`, made before any trajectory and never changed, so
// that HDF5 never moves it when the root's link list grows (a file cut short
// keeps it).
void writeInfo(const Handle& file, const DemoFileInfo& info) {
  writeAttribute(file, "format", std::string(kFormat));
  writeAttribute(file, "format_version", kFormatVersion);
  const Handle meta = createGroup(file, "meta", 1);
  writeAttribute(meta, "manibench_version", info.manibench_version);
  writeAttribute(meta, "task", info.task);
  writeAttribute(meta, "env_id", info.environment_id);
  writeAttribute(meta, "controller", info.controller);
  writeAttribute(meta, "obs_mode", std::string(toString(info.observation_mode)));
  writeAttribute(meta, "condition_names", info.condition_names);
  writeAttribute(meta, "config", info.config);
  writeAttribute(meta, "plugins", info.plugins);
  writeAttribute(meta, "policy", info.policy);
  writeAttribute(meta, "created", info.created);
  writeAttribute(meta, "command", info.command);
  if (!info.generation.empty()) writeAttribute(meta, "generation", info.generation);
  if (!info.converted_from.empty()) writeAttribute(meta, "converted_from", info.converted_from);
  if (!info.conversion.empty()) writeAttribute(meta, "conversion", info.conversion);
}

// --- reading ----------------------------------------------------------------------

DemoFileInfo readInfo(const Handle& file) {
  if (!hasAttribute(file, "format") || readStringAttribute(file, "format") != kFormat)
    throw DemoError("not a manibench demonstration file (no format = \"" + std::string(kFormat) +
                    "\" attribute at its root)");
  DemoFileInfo info;
  info.format_version = readUintAttribute(file, "format_version");
  if (info.format_version != kFormatVersion)
    throw DemoError("format version " + std::to_string(info.format_version) +
                    "; this build reads version " + std::to_string(kFormatVersion));
  if (!hasLink(file, "meta")) throw DemoError("no group 'meta' (the set's description)");
  const Handle meta = openGroup(file, "meta");
  info.manibench_version = readStringAttribute(meta, "manibench_version");
  info.task = readStringAttribute(meta, "task");
  info.environment_id = readStringAttribute(meta, "env_id");
  info.controller = readStringAttribute(meta, "controller");
  const std::string mode = readStringAttribute(meta, "obs_mode");
  const std::optional<ObservationMode> parsed = findObservationMode(mode);
  if (!parsed) throw DemoError("unknown observation mode '" + mode + "' (attribute obs_mode)");
  info.observation_mode = *parsed;
  info.condition_names = readStringsAttribute(meta, "condition_names");
  info.config = readStringAttribute(meta, "config");
  info.plugins = readStringAttribute(meta, "plugins");
  info.policy = readStringAttribute(meta, "policy");
  info.created = readStringAttribute(meta, "created");
  info.command = readStringAttribute(meta, "command");
  if (hasAttribute(meta, "generation")) info.generation = readStringAttribute(meta, "generation");
  if (hasAttribute(meta, "converted_from")) info.converted_from = readStringAttribute(meta, "converted_from");
  if (hasAttribute(meta, "conversion")) info.conversion = readStringAttribute(meta, "conversion");
  // Written by close(), after the last trajectory: absent in a file cut short.
  if (hasAttribute(file, "generation_result"))
    info.generation_result = readStringAttribute(file, "generation_result");
  return info;
}

void readSummaryInto(const Handle& group, Trajectory& t) {
  t.object_id = readStringAttribute(group, "object_id");
  t.level = readUintAttribute(group, "level");
  t.seed = readUintAttribute(group, "seed");
  t.steps = uint32_t(readUintAttribute(group, "steps"));
  t.success = readUintAttribute(group, "success") != 0;
  t.total_reward = readDoubleAttribute(group, "total_reward");
  if (hasAttribute(group, "tracking_error")) t.tracking_error = readDoubleAttribute(group, "tracking_error");
}

void readObservations(const Handle& group, const DemoFileInfo& info, Trajectory& t) {
  const hsize_t n = hsize_t(t.steps) + 1;
  t.mode = info.observation_mode;
  if (t.mode == ObservationMode::State) {
    t.state_dim = uint32_t(expectDims(group, "obs", {n, 0})[1]);
    t.state = readDataset<double>(group, "obs");
    return;
  }
  if (!hasLink(group, "obs")) throw DemoError("no group 'obs'");
  const Handle obs = openGroup(group, "obs");
  t.mask_count = uint32_t(readUintAttribute(obs, "mask_count"));
  t.state_dim = uint32_t(expectDims(obs, "agent", {n, 0})[1]);
  t.state = readDataset<double>(obs, "agent");
  if (t.mode == ObservationMode::PointCloud) {
    if (hasLink(obs, "point_count")) {
      expectDims(obs, "point_count", {n});
      t.point_counts = readDataset<uint32_t>(obs, "point_count");
      uint64_t total = 0;
      for (uint32_t c : t.point_counts) total += c;
      expectDims(obs, "xyz", {total, 3});
      expectDims(obs, "rgb", {total, 3});
      expectDims(obs, "seg", {total, t.mask_count});
    } else {
      const hsize_t points = expectDims(obs, "xyz", {n, 0, 3})[1];
      expectDims(obs, "rgb", {n, points, 3});
      expectDims(obs, "seg", {n, points, t.mask_count});
      t.point_counts.assign(n, uint32_t(points));
    }
    t.xyz = readDataset<float>(obs, "xyz");
    t.point_rgb = readDataset<float>(obs, "rgb");
    t.point_masks = readDataset<uint8_t>(obs, "seg");
  } else {
    t.camera_count = uint32_t(readUintAttribute(obs, "camera_count"));
    const std::vector<hsize_t> dims = expectDims(obs, "rgb", {n, 0, 0, 3 * hsize_t(t.camera_count)});
    t.height = uint32_t(dims[1]);
    t.width = uint32_t(dims[2]);
    expectDims(obs, "depth", {n, t.height, t.width, t.camera_count});
    expectDims(obs, "seg", {n, t.height, t.width, hsize_t(t.mask_count) * t.camera_count});
    if (readElementType(obs, "rgb").is_float)
      t.image_rgb = readDataset<float>(obs, "rgb");
    else
      t.image_rgb_bytes = readDataset<uint8_t>(obs, "rgb");
    t.depth = readDataset<float>(obs, "depth");
    t.image_masks = readDataset<uint8_t>(obs, "seg");
  }
}

void readTrajectory(const Handle& group, const DemoFileInfo& info, bool with_env_states, Trajectory& t) {
  readSummaryInto(group, t);
  const hsize_t steps = t.steps;
  const std::vector<hsize_t> action_dims = expectDims(group, "actions", {steps, 0});
  t.action_dim = uint32_t(action_dims[1]);
  t.actions = readDataset<double>(group, "actions");
  if (hasLink(group, "policy_actions")) {
    expectDims(group, "policy_actions", {steps, t.action_dim});
    t.policy_actions = readDataset<double>(group, "policy_actions");
  }
  expectDims(group, "rewards", {steps});
  t.rewards = readDataset<double>(group, "rewards");
  for (const char* name : {"terminated", "truncated", "success"}) expectDims(group, name, {steps});
  t.terminated = readDataset<uint8_t>(group, "terminated");
  t.truncated = readDataset<uint8_t>(group, "truncated");
  t.success_flags = readDataset<uint8_t>(group, "success");
  t.condition_count = uint32_t(info.condition_names.size());
  expectDims(group, "conditions", {steps, t.condition_count});
  t.conditions = readDataset<uint8_t>(group, "conditions");
  readObservations(group, info, t);
  if (!with_env_states) return;
  expectDims(group, "env_state_offsets", {steps + 2});
  t.env_state_offsets = readDataset<uint64_t>(group, "env_state_offsets");
  t.env_states = readDataset<uint8_t>(group, "env_states");
  bool ordered = t.env_state_offsets.front() == 0 && t.env_state_offsets.back() == t.env_states.size();
  for (std::size_t k = 1; ordered && k < t.env_state_offsets.size(); ++k)
    ordered = t.env_state_offsets[k - 1] <= t.env_state_offsets[k];
  if (!ordered)
    throw DemoError("env_state_offsets do not partition env_states (" +
                    std::to_string(t.env_states.size()) + " bytes)");
}

// Runs `body`, turning HDF5's errors into DemoErrors naming `where`.
template <class F>
auto withContext(const std::string& where, F&& body) -> decltype(body()) {
  try {
    return body();
  } catch (const DemoError& e) {
    throw DemoError(where + ": " + e.what());
  } catch (const Hdf5Error& e) {
    throw DemoError(where + ": " + e.what());
  }
}

}  // namespace

// --- DemoWriter -----------------------------------------------------------------------

struct DemoWriter::Impl {
  std::string path;
  DemoFileInfo info;
  Handle file;
  std::size_t count = 0;
  std::vector<Trajectory> summaries;
};

DemoWriter::DemoWriter(const std::string& path, const DemoFileInfo& info, std::size_t expected_trajectories)
    : impl_(new Impl) {
  impl_->path = path;
  impl_->info = info;
  withContext("'" + path + "'", [&] {
    // The root's links: meta and the trajectories.
    impl_->file = createFile(path, unsigned(std::min<std::size_t>(expected_trajectories + 1, 60000)));
    writeInfo(impl_->file, info);
    flushFile(impl_->file);
  });
}

DemoWriter::~DemoWriter() {
  try {
    close();
  } catch (...) {
    // A destructor cannot report; close() explicitly to see errors.
  }
}

std::string DemoWriter::append(const Trajectory& trajectory) {
  if (!impl_->file.valid()) throw DemoError("'" + impl_->path + "' is closed");
  const std::string name = getTrajectoryName(impl_->count);
  withContext("'" + impl_->path + "', " + name, [&] {
    if (trajectory.condition_count != impl_->info.condition_names.size())
      throw DemoError(std::to_string(trajectory.condition_count) + " success conditions, the file has " +
                      std::to_string(impl_->info.condition_names.size()));
    if (trajectory.mode != impl_->info.observation_mode)
      throw DemoError(std::string("observations in mode ") + toString(trajectory.mode) + ", the file's are " +
                      toString(impl_->info.observation_mode));
    writeTrajectory(impl_->file, name, impl_->info, trajectory);
    flushFile(impl_->file);
  });
  ++impl_->count;
  Trajectory summary;
  summary.object_id = trajectory.object_id;
  summary.level = trajectory.level;
  summary.seed = trajectory.seed;
  summary.steps = trajectory.steps;
  summary.success = trajectory.success;
  summary.total_reward = trajectory.total_reward;
  summary.tracking_error = trajectory.tracking_error;
  impl_->summaries.push_back(std::move(summary));
  return name;
}

void DemoWriter::close(const std::string& generation_result) {
  if (!impl_ || !impl_->file.valid()) return;
  if (!generation_result.empty())
    withContext("'" + impl_->path + "'",
                [&] { writeAttribute(impl_->file, "generation_result", generation_result); });
  impl_->file.reset();
  std::vector<std::string> names;
  for (std::size_t i = 0; i < impl_->count; ++i) names.push_back(getTrajectoryName(i));
  const std::string json_path = getDemoJsonPath(impl_->path);
  std::ofstream out(json_path);
  out << formatDemoJson(impl_->info, names, impl_->summaries);
  if (!out) throw DemoError("cannot write '" + json_path + "'");
}

std::size_t DemoWriter::getCount() const { return impl_->count; }
const std::string& DemoWriter::getPath() const { return impl_->path; }

// --- DemoReader -----------------------------------------------------------------------

struct DemoReader::Impl {
  std::string path;
  FileLayout layout;
  Handle file;
  DemoFileInfo info;
  std::vector<std::string> names;
};

DemoReader::DemoReader(const std::string& path) : impl_(new Impl) {
  impl_->path = path;
  withContext("'" + path + "'", [&] {
    std::error_code error;
    if (std::filesystem::is_directory(path, error)) throw DemoError("is a directory");
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw DemoError("cannot be read (no such file, or no permission)");
    char signature[8] = {};
    probe.read(signature, 8);
    if (probe.gcount() != 8 || std::string(signature, 8) != "\x89HDF\r\n\x1a\n")
      throw DemoError("is not an HDF5 file (no HDF5 signature)");
    const FileLayout& layout = impl_->layout = readFileLayout(path);
    try {
      impl_->file = openForReading(path);
      impl_->info = readInfo(impl_->file);
      std::vector<std::pair<long, std::string>> found;
      for (const std::string& name : listLinks(impl_->file))
        if (const long index = parseTrajectoryIndex(name); index >= 0) found.emplace_back(index, name);
      std::sort(found.begin(), found.end());
      for (auto& [index, name] : found) impl_->names.push_back(std::move(name));
    } catch (const std::exception& e) {
      // A file cut before its first trajectory was complete: say where the
      // cut fell (HDF5's own reason is a checksum or a read past the end).
      if (layout.bytes < 12 || (layout.superblock_end != 0 && layout.bytes < layout.superblock_end))
        throw DemoError("cut short inside its HDF5 superblock (" + std::to_string(layout.bytes) +
                        " bytes): nothing in it can be read (" + e.what() + ")");
      if (!layout.isCutShort()) throw;
      const bool in_root = layout.root_header_end == 0 || layout.bytes < layout.root_header_end;
      if (in_root)
        throw DemoError(describeCut(layout) + ", inside the root group's header (from byte " +
                        std::to_string(layout.root_header) +
                        "), which lists the trajectories and precedes them all: no trajectory was "
                        "complete before the cut (" + e.what() + ")");
      throw DemoError(describeCut(layout) + ": " + e.what());
    }
  });
}

DemoReader::~DemoReader() = default;
const std::string& DemoReader::getPath() const { return impl_->path; }
const DemoFileInfo& DemoReader::getInfo() const { return impl_->info; }
const std::vector<std::string>& DemoReader::getTrajectoryNames() const { return impl_->names; }
uint64_t DemoReader::getFileBytes() const { return impl_->layout.bytes; }
uint64_t DemoReader::getRecordedBytes() const { return impl_->layout.recorded_bytes; }

Trajectory DemoReader::read(const std::string& name, bool with_env_states) const {
  return withContext("'" + impl_->path + "', trajectory " + name, [&] {
    if (!hasLink(impl_->file, name)) throw DemoError("no such trajectory");
    const Handle group = openGroup(impl_->file, name);
    if (impl_->layout.isCutShort()) {
      // A file written before trajectory groups kept their links in their
      // header: the links' heap, which HDF5 does not checksum, lies
      // wholly before the next trajectory's group (HDF5 allocates only at
      // the file's end), so that group's header reading whole vouches
      // for it. Without that, listing the links could crash HDF5.
      const std::string next = getTrajectoryName(std::size_t(parseTrajectoryIndex(name)) + 1);
      if (hasDenseLinks(group) && !canOpenGroup(impl_->file, next))
        throw DemoError("may lie past the cut: its links are in HDF5's dense storage (a file written "
                        "before manibench kept them in the group's header), which cannot be checked (" +
                        describeCut(impl_->layout) + ")");
      expectWithinFile(group, impl_->info.observation_mode, impl_->layout, with_env_states);
    }
    Trajectory t;
    readTrajectory(group, impl_->info, with_env_states, t);
    return t;
  });
}

Trajectory DemoReader::readSummary(const std::string& name) const {
  return withContext("'" + impl_->path + "', trajectory " + name, [&] {
    if (!hasLink(impl_->file, name)) throw DemoError("no such trajectory");
    const Handle group = openGroup(impl_->file, name);
    Trajectory t;
    readSummaryInto(group, t);
    return t;
  });
}

uint64_t DemoReader::calcStorageBytes(const std::string& name) const {
  return withContext("'" + impl_->path + "', trajectory " + name, [&] {
    const Handle group = openGroup(impl_->file, name);
    uint64_t bytes = 0;
    forEachDataset(group, impl_->info.observation_mode,
                   [&](const Handle& parent, const std::string& dataset, const std::string&) {
                     const Handle d(check(H5Dopen2(parent.get(), dataset.c_str(), H5P_DEFAULT), dataset));
                     bytes += H5Dget_storage_size(d.get());
                   });
    return bytes;
  });
}

// --- the JSON sidecar -------------------------------------------------------------------

std::string getDemoJsonPath(const std::string& h5_path) {
  for (const char* extension : {".h5", ".hdf5"}) {
    const std::string e = extension;
    if (h5_path.size() > e.size() && h5_path.compare(h5_path.size() - e.size(), e.size(), e) == 0)
      return h5_path.substr(0, h5_path.size() - e.size()) + ".json";
  }
  return h5_path + ".json";
}

std::string formatDemoJson(const DemoFileInfo& info, const std::vector<std::string>& names,
                           const std::vector<Trajectory>& summaries) {
  nlohmann::ordered_json json;
  json["format"] = kFormat;
  json["format_version"] = info.format_version;
  json["manibench_version"] = info.manibench_version;
  json["env_info"] = {{"task", info.task},
                      {"env_id", info.environment_id},
                      {"controller", info.controller},
                      {"obs_mode", toString(info.observation_mode)},
                      {"condition_names", info.condition_names}};
  json["config"] = info.config;
  json["plugins"] = nlohmann::ordered_json::parse(info.plugins.empty() ? "[]" : info.plugins, nullptr, false);
  json["policy"] = info.policy;
  json["created"] = info.created;
  json["command"] = info.command;
  if (!info.converted_from.empty()) json["converted_from"] = info.converted_from;
  if (!info.conversion.empty()) json["conversion"] = info.conversion;
  nlohmann::ordered_json episodes = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < names.size() && i < summaries.size(); ++i) {
    const Trajectory& t = summaries[i];
    episodes.push_back({{"episode_id", i},
                        {"name", names[i]},
                        {"object_id", t.object_id},
                        {"level", t.level},
                        {"seed", t.seed},
                        {"elapsed_steps", t.steps},
                        {"success", t.success},
                        {"total_reward", t.total_reward}});
    if (t.tracking_error >= 0) episodes.back()["tracking_error"] = t.tracking_error;
  }
  json["episodes"] = std::move(episodes);
  return json.dump(2) + "\n";
}

}  // namespace manibench
