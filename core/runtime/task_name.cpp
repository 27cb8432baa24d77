#include <manibench/task_name.hpp>

#include <algorithm>
#include <cctype>

namespace manibench {

namespace {
// The position of a trailing "-v<digits>" in `name`, or npos.
std::size_t findVersionSuffix(const std::string& name) {
  const std::size_t at = name.rfind("-v");
  if (at == std::string::npos || at + 2 == name.size()) return std::string::npos;
  for (std::size_t i = at + 2; i < name.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) return std::string::npos;
  return at;
}
}  // namespace

std::optional<TaskId> matchTaskId(const std::vector<std::string>& tasks, const std::string& name) {
  if (std::find(tasks.begin(), tasks.end(), name) != tasks.end()) return TaskId{name, ""};
  const std::size_t name_version = findVersionSuffix(name);
  if (name_version == std::string::npos) return std::nullopt;
  std::optional<TaskId> best;
  std::size_t best_base = 0;
  for (const std::string& task : tasks) {
    const std::size_t base = findVersionSuffix(task);
    if (base == std::string::npos || task.compare(base, std::string::npos, name, name_version,
                                                  std::string::npos) != 0)
      continue;
    // name = base + "_" + spec + version, with a non-empty spec.
    if (name_version <= base + 1 || name.compare(0, base, task, 0, base) != 0 || name[base] != '_')
      continue;
    if (!best || base > best_base) {
      best_base = base;
      best = TaskId{task, name.substr(base + 1, name_version - base - 1)};
    }
  }
  return best;
}

TaskId resolveTaskId(const PluginRegistry& registry, const std::string& name) {
  if (std::optional<TaskId> id = matchTaskId(registry.getNames(PluginKind::Task), name)) return *id;
  try {
    registry.getEntry(PluginKind::Task, name);
  } catch (const PluginError& e) {
    throw PluginError(std::string(e.what()) +
                      "; a fixed-object environment is named <Task>_<object>-v<N> after a task "
                      "<Task>-v<N>, e.g. OpenCabinetDrawer_1000-v0 (`manibench objects TASK` "
                      "lists the objects)");
  }
  return {name, ""};  // not reached: getEntry threw
}

std::string makeFixedObjectId(const std::string& task, const std::string& spec) {
  const std::size_t version = findVersionSuffix(task);
  if (version == std::string::npos) return "";
  return task.substr(0, version) + "_" + spec + task.substr(version);
}

bool matchesObjectSpec(const std::string& id, const std::string& spec) {
  if (id.size() < spec.size() || id.compare(0, spec.size(), spec) != 0) return false;
  return id.size() == spec.size() || id[spec.size()] == '_';
}

std::vector<std::string> selectFixedObjects(const TaskId& id, const std::vector<std::string>& train,
                                            const std::vector<std::string>& test) {
  std::vector<std::string> objects;
  if (!id.isFixed()) return objects;
  for (const std::vector<std::string>* split : {&train, &test})
    for (const std::string& object : *split)
      if (matchesObjectSpec(object, id.object_spec) &&
          std::find(objects.begin(), objects.end(), object) == objects.end())
        objects.push_back(object);
  if (objects.empty())
    throw PluginError(id.task + " has no object '" + id.object_spec + "' nor objects '" +
                      id.object_spec + "_*' (manibench objects " + id.task +
                      " --split train|test lists them)");
  return objects;
}

}  // namespace manibench
