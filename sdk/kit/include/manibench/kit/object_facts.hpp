// Per-object facts a family keeps as data, not code: the size a PartNet
// object is loaded at (its scale policy) and what a family needs to know of
// particular objects (ManiSkill v1's hand-tuned scales and target counts,
// keyed by v1's ids). One YAML file per family ships in the data folder
// (assets/objects/<family>.yaml, found through sdk::findDataDirectory);
// a user extends it with a file of their own, named by the task key
// `object_facts`, whose entries replace the shipped ones object by object.
//
//   source: where the numbers came from
//   scale:                 # the rule for objects the file does not list
//     fixed: 0.3           #   every object at this scale, or
//     diagonal: 1.0        #   the visual bounding box's diagonal (m) at q = 0,
//     min: 0.28            #   the scale kept within [min, max]
//     max: 0.81
//   objects:
//     "4018": {scale: 0.35}
//     "1000": {scale: 0.61, doors: 2, drawers: 2}
//
// The task key `partnet_scale` means the same in every family: a fixed
// scale for every object, replacing both the rule and the per-object
// scales (0, the default: the file's).
#pragma once

#include <manibench/kit/common.hpp>
#include <manibench/sdk/data.hpp>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>

namespace manibench::kit {

class ObjectFacts {
 public:
  // One object's entry: the keys a family reads (getNumber).
  using Entry = std::map<std::string, double>;

  ObjectFacts() = default;
  // Reads the shipped file of `family` from the data folder
  // (<data>/objects/<family>.yaml), then the task's `object_facts` file when
  // set; `partnet_scale` from the task's configuration. Errors name the file.
  ObjectFacts(const sdk::Config& config, const std::string& family) {
    read(sdk::findDataDirectory("objects") + "/" + family + ".yaml");
    const std::string user = config.get<std::string>("object_facts", "");
    if (!user.empty()) read(user);
    fixed_override_ = config.get<double>("partnet_scale", 0.0);
    if (!(fixed_override_ >= 0) || !std::isfinite(fixed_override_))
      throw Error(family + ": task.partnet_scale must be positive (or 0: the object facts' scale, " +
                      source_files_ + ")",
                  MB_INVALID_ARGUMENT);
  }

  // Whether the rule needs the object's unscaled diagonal (so a loader
  // reads the object once before it knows its scale).
  bool needsDiagonal(const std::string& id) const {
    return !(fixed_override_ > 0) && findNumber(id, "scale") < 0 && !(fixed_ > 0);
  }
  // The scale of `id`: partnet_scale, else its entry's, else the rule's
  // (`diagonal`: the visual bounds' diagonal at q = 0, unscaled).
  double calcScale(const std::string& id, double diagonal = 0) const {
    if (fixed_override_ > 0) return fixed_override_;
    if (const double own = findNumber(id, "scale"); own > 0) return own;
    if (fixed_ > 0) return fixed_;
    if (!(target_diagonal_ > 0))
      throw Error("object facts (" + source_files_ + "): no scale for object " + id +
                      " (give scale: {fixed: S} or {diagonal: D})",
                  MB_INVALID_ARGUMENT);
    if (!(diagonal > 0) || !std::isfinite(diagonal))
      throw Error("PartNet object " + id + ": its visual geometry has no extent", MB_INVALID_ARGUMENT);
    return std::clamp(target_diagonal_ / diagonal, min_scale_, max_scale_);
  }
  // Whether the scale of `id` comes from its own entry (v1's, a user's).
  bool hasOwnScale(const std::string& id) const { return !(fixed_override_ > 0) && findNumber(id, "scale") > 0; }
  // A number of `id`'s entry, or -1 when it has none.
  double findNumber(const std::string& id, const std::string& key) const {
    const auto object = objects_.find(id);
    if (object == objects_.end()) return -1;
    const auto value = object->second.find(key);
    return value == object->second.end() ? -1 : value->second;
  }
  bool hasObject(const std::string& id) const { return objects_.count(id) > 0; }
  const std::string& getSourceFiles() const { return source_files_; }

 private:
  void read(const std::string& path) {
    if (!std::filesystem::is_regular_file(path))
      throw Error("object facts: no file " + path, MB_NOT_FOUND);
    source_files_ += (source_files_.empty() ? "" : ", ") + path;
    try {
      const YAML::Node root = YAML::LoadFile(path);
      if (const YAML::Node scale = root["scale"]) {
        for (const auto& item : scale) {
          const std::string key = item.first.as<std::string>();
          const double value = item.second.as<double>();
          if (!(value > 0) || !std::isfinite(value))
            throw Error(path + ":" + std::to_string(item.second.Mark().line + 1) + ": scale." + key +
                            " must be a positive number",
                        MB_INVALID_ARGUMENT);
          if (key == "fixed") {
            fixed_ = value;
          } else if (key == "diagonal") {
            target_diagonal_ = value;
          } else if (key == "min") {
            min_scale_ = value;
          } else if (key == "max") {
            max_scale_ = value;
          } else {
            throw Error(path + ":" + std::to_string(item.first.Mark().line + 1) + ": unknown key scale." + key +
                            " (fixed, diagonal, min, max)",
                        MB_INVALID_ARGUMENT);
          }
        }
      }
      if (const YAML::Node objects = root["objects"]) {
        for (const auto& object : objects) {
          const std::string id = object.first.as<std::string>();
          Entry entry;
          for (const auto& field : object.second) {
            const double value = field.second.as<double>();
            if (!std::isfinite(value) || value < 0)
              throw Error(path + ":" + std::to_string(field.second.Mark().line + 1) + ": objects." + id + "." +
                              field.first.as<std::string>() + " must be a non-negative number",
                          MB_INVALID_ARGUMENT);
            entry[field.first.as<std::string>()] = value;
          }
          objects_[id] = entry;  // a later file replaces the object's entry
        }
      }
    } catch (const YAML::Exception& e) {
      throw Error("object facts " + path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg, MB_INVALID_ARGUMENT);
    }
  }

  std::string source_files_;
  double fixed_override_ = 0;  // task.partnet_scale
  double fixed_ = 0;           // scale.fixed
  double target_diagonal_ = 0, min_scale_ = 0, max_scale_ = 1e9;
  std::map<std::string, Entry> objects_;
};

}  // namespace manibench::kit
