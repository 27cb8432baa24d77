// Environment ids: a registered task name ("OpenCabinetDrawer-v0": a
// random object of the split each reset) or a fixed-object id
// ("OpenCabinetDrawer_1000-v0", "OpenCabinetDoor_1000_link_0-v0",
// "Reach_3-v0"), as ManiSkill registers per object. The fixed form is
// <Base>_<spec>-v<N> for a registered task <Base>-v<N>; it keeps the
// objects whose id equals <spec> or starts with <spec>_ (so a cabinet
// id selects every target link of that cabinet). Generic: every task
// gets it, from its own object ids.
#pragma once

#include <manibench/plugin_registry.hpp>

#include <optional>
#include <string>
#include <vector>

namespace manibench {

struct TaskId {
  std::string task;         // the registered task
  std::string object_spec;  // empty: every object of the task
  bool isFixed() const { return !object_spec.empty(); }
};

// `name` as a registered task, else as <Base>_<spec>-v<N> with <Base>-v<N>
// registered (the longest such base wins: task names may contain
// underscores). Only the name is checked here, not the objects. Throws
// PluginError listing the tasks (with a hint on the fixed form) when
// neither fits.
TaskId resolveTaskId(const PluginRegistry& registry, const std::string& name);
// The same rule over a list of task names; nullopt when `name` fits none.
std::optional<TaskId> matchTaskId(const std::vector<std::string>& tasks, const std::string& name);

// The fixed-object id of `spec` in `task`: ("Reach-v0", "3") -> "Reach_3-v0";
// empty when the task's name does not end in -v<N>.
std::string makeFixedObjectId(const std::string& task, const std::string& spec);

// Whether object `id` belongs to `spec`: equal, or `spec` + "_" a prefix.
bool matchesObjectSpec(const std::string& id, const std::string& spec);

// The objects of `train` then `test` (duplicates dropped, order kept) that
// match the id's spec. Throws PluginError naming the task, the spec and how
// to list the objects when none does. An id without a spec: empty.
std::vector<std::string> selectFixedObjects(const TaskId& id, const std::vector<std::string>& train,
                                            const std::vector<std::string>& test);

}  // namespace manibench
