// A family's objects: the catalog a task takes its models from, either generated or
// read from PartNet-Mobility folders (the task's `partnet_dir` key), each
// built once and kept. A PartNet object that cannot be read (or that the
// family cannot use) is skipped when the split is listed, with one warning
// per object and process: one bad object of a user's folder must not make
// the folder unusable.
#pragma once

#include <manibench/kit/common.hpp>
#include <manibench/kit/object_ids.hpp>
#include <manibench/kit/partnet.hpp>

#include <algorithm>
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

// The PartNet-Mobility folders a task reads its objects from: one folder
// per category, as the dataset lays them out (StorageFurniture/,
// Microwave/, ...), each object's id unique across them (the dataset's
// ids are). The split is each folder's test.txt, or, with test
// categories, by category: the test split is every object of the folders
// named (a category is its folder's name), train every other's, so that a
// policy is tested on categories it never saw (the cross-category
// generalisation that PartManip and GAPartNet measure).
class PartNetFolders {
 public:
  PartNetFolders() = default;
  // One folder, as before folders of several categories ("": none).
  PartNetFolders(std::string folder) {  // NOLINT(google-explicit-constructor)
    if (!folder.empty()) folders_.push_back(std::move(folder));
  }
  PartNetFolders(const char* folder) : PartNetFolders(std::string(folder)) {}  // NOLINT(google-explicit-constructor)
  PartNetFolders(std::vector<std::string> folders, std::vector<std::string> test_categories)
      : folders_(std::move(folders)), test_categories_(std::move(test_categories)) {
    for (const std::string& category : test_categories_) {
      bool found = false;
      std::string names;
      for (const std::string& folder : folders_) {
        found = found || getCategory(folder) == category;
        names += (names.empty() ? "" : ", ") + getCategory(folder);
      }
      if (!found)
        throw Error("PartNet: test category '" + category + "' is none of the folders' (" + names + ")",
                    MB_INVALID_ARGUMENT);
    }
  }

  bool empty() const { return folders_.empty(); }
  const std::vector<std::string>& getFolders() const { return folders_; }
  const std::vector<std::string>& getTestCategories() const { return test_categories_; }
  // A folder's category: its name ("StorageFurniture" for DIR/StorageFurniture/).
  static std::string getCategory(const std::string& folder) {
    std::filesystem::path path = std::filesystem::path(folder).lexically_normal();
    if (path.filename().empty()) path = path.parent_path();  // "DIR/Chair/"
    return path.filename().string();
  }

  // The ids of `split` over every folder, sorted; an id in two folders is
  // an error naming both.
  std::vector<std::string> list(const std::string& split) const {
    if (split != "train" && split != "test")
      throw Error("unknown split '" + split + "' (use train or test)", MB_INVALID_ARGUMENT);
    std::map<std::string, std::string> seen;  // id -> folder
    std::vector<std::string> ids;
    for (const std::string& folder : folders_) {
      const std::vector<std::string> all = partnet::listObjectIds(folder);
      for (const std::string& id : all) {
        const auto [at, fresh] = seen.emplace(id, folder);
        if (!fresh)
          throw Error("PartNet: object " + id + " is in two folders: " + at->second + " and " + folder,
                      MB_INVALID_ARGUMENT);
      }
      std::vector<std::string> in_split;
      if (test_categories_.empty()) {
        in_split = partnet::listObjectIds(folder, split);
      } else {
        const bool test = std::find(test_categories_.begin(), test_categories_.end(), getCategory(folder)) !=
                          test_categories_.end();
        if (test == (split == "test")) in_split = all;
      }
      ids.insert(ids.end(), in_split.begin(), in_split.end());
    }
    std::sort(ids.begin(), ids.end());
    return ids;
  }

  // The folder holding `id` (the first one's when no folder holds it, so
  // that the loader's error names a folder).
  std::string findFolder(const std::string& id) const {
    for (const std::string& folder : folders_)
      if (!partnet::findUrdfFile((std::filesystem::path(folder) / id).string()).empty()) return folder;
    return folders_.empty() ? std::string() : folders_.front();
  }

 private:
  std::vector<std::string> folders_;
  std::vector<std::string> test_categories_;  // empty: each folder's test.txt
};

// The models of one task, by object id: made by the family's generator, or,
// when `partnet_dir` is set, loaded from those PartNet-Mobility folders.
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
  ObjectCatalog(std::string task, std::string noun, PartNetFolders partnet, Source source)
      : task_(std::move(task)), noun_(std::move(noun)), partnet_(std::move(partnet)), source_(std::move(source)) {}

  bool isPartNet() const { return !partnet_.empty(); }
  const PartNetFolders& getPartNetFolders() const { return partnet_; }
  // The first folder ("" when generated): what a one-folder task reads.
  std::string getPartNetDir() const { return partnet_.empty() ? std::string() : partnet_.getFolders().front(); }
  // An object's category (Task::getObjectCategory): the name of the
  // PartNet folder holding it, "" for a generated one.
  std::string getCategory(const std::string& id) const {
    return isPartNet() ? PartNetFolders::getCategory(partnet_.findFolder(id)) : std::string();
  }

  // The model of `id`, made on first use and kept.
  std::shared_ptr<const Model> get(const std::string& id) const {
    auto& slot = models_[id];
    if (!slot) {
      auto model = std::make_shared<Model>(isPartNet() ? source_.load_partnet(partnet_.findFolder(id), id)
                                                       : source_.generate(id));
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
    for (const std::string& id : partnet_.list(split)) {
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
                               noun_ + " " + id + " (" + (std::filesystem::path(partnet_.findFolder(id)) / id).string() + "): ";
      if (!reason.empty()) std::cerr << what << reason << "\n";
      for (const std::string& note : notes) std::cerr << what << "leaving out " << note << "\n";
    }
    return ids;
  }

 private:
  std::string task_, noun_;
  PartNetFolders partnet_;
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

// The task keys `partnet_dir` (empty, a folder, or a list of folders: one
// per category) and `partnet_test_categories` (a list of the folders'
// names: the test split by category, PartNetFolders); errors name the key.
inline PartNetFolders readPartNetFolders(const Config& config, const std::string& task) {
  std::vector<std::string> folders;
  if (config.has("partnet_dir") && config.node()["partnet_dir"].IsSequence())
    folders = config.get<std::vector<std::string>>("partnet_dir", {});
  else if (const std::string dir = config.get<std::string>("partnet_dir", ""); !dir.empty())
    folders.push_back(dir);
  for (const std::string& dir : folders)
    if (!std::filesystem::is_directory(dir))
      throw Error(task + ": task.partnet_dir '" + dir + "' is not a folder", MB_INVALID_ARGUMENT);
  const auto categories = config.has("partnet_test_categories") &&
                                  config.node()["partnet_test_categories"].IsScalar()
                              ? std::vector<std::string>{config.get<std::string>("partnet_test_categories", "")}
                              : config.get<std::vector<std::string>>("partnet_test_categories", {});
  if (!categories.empty() && folders.empty())
    throw Error(task + ": task.partnet_test_categories needs task.partnet_dir", MB_INVALID_ARGUMENT);
  try {
    return PartNetFolders(folders, categories);
  } catch (const Error& e) {
    throw Error(task + ": task.partnet_test_categories: " + e.what(), MB_INVALID_ARGUMENT);
  }
}

}  // namespace manibench::kit
