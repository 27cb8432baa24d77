// A family's objects: the catalog a task takes its models from, either generated or
// read from a PartNet-Mobility folder (the task's `partnet_dir` key), each
// built once and kept. A PartNet object that cannot be read (or that the
// family cannot use) is skipped when the split is listed, with one warning
// per object and process: one bad object of a user's folder must not make
// the folder unusable.
#pragma once

#include <manibench/kit/common.hpp>
#include <manibench/kit/object_ids.hpp>
#include <manibench/kit/partnet.hpp>

#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace manibench::kit {

// The models of one task, by object id: made by the family's generator, or,
// when `partnet_dir` is set, loaded from that PartNet-Mobility folder.
template <class Model>
class ObjectCatalog {
 public:
  struct Source {
    std::function<std::vector<std::string>(const std::string& split)> list_generated;
    std::function<Model(const std::string& id)> generate;
    std::function<Model(const std::string& folder, const std::string& id)> load_partnet;
    // Why the family cannot use a model ("" when it can): a PartNet object
    // it refuses is skipped as an unreadable one is. May be empty.
    std::function<std::string(const Model&)> check;
    // Runs on every model once it is made (writing its mesh files, say).
    std::function<void(Model&)> finish;
    // What of a PartNet model the family can use it leaves out (a part it
    // cannot make a task of), each with its reason: named once per process
    // on stderr as a skipped object is. May be empty.
    std::function<std::vector<std::string>(const Model&)> notes;
  };

  // `task` and `noun` name the objects in warnings ("OpenCabinetDrawer",
  // "cabinet").
  ObjectCatalog(std::string task, std::string noun, std::string partnet_dir, Source source)
      : task_(std::move(task)), noun_(std::move(noun)), partnet_dir_(std::move(partnet_dir)),
        source_(std::move(source)) {}

  bool isPartNet() const { return !partnet_dir_.empty(); }
  const std::string& getPartNetDir() const { return partnet_dir_; }

  // The model of `id`, made on first use and kept.
  std::shared_ptr<const Model> get(const std::string& id) const {
    auto& slot = models_[id];
    if (!slot) {
      auto model = std::make_shared<Model>(isPartNet() ? source_.load_partnet(partnet_dir_, id) : source_.generate(id));
      if (source_.finish) source_.finish(*model);
      slot = std::move(model);
    }
    return slot;
  }

  // The ids of `split`: the generator's, or the PartNet folder's that load
  // and pass the family's check (the others are skipped, each named once
  // per process on stderr with its folder and the reason).
  std::vector<std::string> list(const std::string& split) const {
    if (!isPartNet()) return source_.list_generated(split);
    std::vector<std::string> ids;
    for (const std::string& id : partnet::listObjectIds(partnet_dir_, split)) {
      std::string reason;
      std::vector<std::string> notes;
      try {
        const std::shared_ptr<const Model> model = get(id);
        if (source_.check) reason = source_.check(*model);
        if (source_.notes && reason.empty()) notes = source_.notes(*model);
      } catch (const std::exception& e) {
        models_.erase(id);
        reason = e.what();
      }
      if (reason.empty()) ids.push_back(id);
      if (!skipped_.insert(id).second) continue;
      const std::string what = "manibench: warning: " + task_ + ": " + (reason.empty() ? "" : "skipping ") + "PartNet " +
                               noun_ + " " + id + " (" + (std::filesystem::path(partnet_dir_) / id).string() + "): ";
      if (!reason.empty()) std::cerr << what << reason << "\n";
      for (const std::string& note : notes) std::cerr << what << "leaving out " << note << "\n";
    }
    return ids;
  }

 private:
  std::string task_, noun_, partnet_dir_;
  Source source_;
  mutable std::map<std::string, std::shared_ptr<Model>> models_;
  mutable std::set<std::string> skipped_;  // named on stderr already
};

// The task key `partnet_dir`: empty (the family's generator) or a folder;
// anything else is an error naming the key.
inline std::string readPartNetDir(const Config& config, const std::string& task) {
  const std::string dir = config.get<std::string>("partnet_dir", "");
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw Error(task + ": task.partnet_dir '" + dir + "' is not a folder", MB_INVALID_ARGUMENT);
  return dir;
}

}  // namespace manibench::kit
