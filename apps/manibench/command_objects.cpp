// manibench objects: the object ids of a task's split, grouped by the
// object family member they belong to when the ids say so ("1003_link_1":
// target link_1 of cabinet 1003).
#include <iomanip>
#include <iostream>
#include <map>

#include <manibench/task_name.hpp>

#include "cli.hpp"

namespace manibench::cli {

namespace {

const char* kObjectsUsage = R"(usage: manibench objects TASK [--split train|test] [--ids] [--config FILE]... [--set KEY=VALUE]...

Lists the objects of a task's split (default train), as configured (a task
may read its objects from a folder named in its `task:` keys). Ids of the
form <object>_link_<k> (one target link of an articulated object, as in
OpenCabinetDoor-v0) are grouped by object. Every object, or group, is also an
environment of its own: <Task>_<object>-v<N>, e.g. OpenCabinetDrawer_1000-v0
(every target link of cabinet 1000) or OpenCabinetDrawer_1000_link_0-v0; given
such an id, this lists its objects (the same whatever the split).

Options:
  --split train|test      the split (default train)
  --ids                   only the ids, one a line (for scripts)
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key, e.g. --set task.partnet_dir=DIR; repeatable
)";

}  // namespace

int commandObjects(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {"split", "config", "set"}, {"ids"}, kObjectsUsage);
  if (args.help) {
    std::cout << kObjectsUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("objects takes one TASK", kObjectsUsage);
  const std::string task = args.positional[0];
  const std::string split = parseSplit(args, "train", kObjectsUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  const auto env = makeEnvironment(registry, task, getConfigSources(args), true);
  const std::vector<std::string> ids = env->listObjects(split);
  if (args.options.count("ids")) {
    for (const std::string& id : ids) std::cout << id << "\n";
    return 0;
  }
  std::vector<std::pair<std::string, std::vector<std::string>>> groups;  // in listing order
  for (const std::string& id : ids) {
    const std::size_t at = id.rfind("_link_");
    const std::string group = at == std::string::npos ? id : id.substr(0, at);
    if (groups.empty() || groups.back().first != group) groups.push_back({group, {}});
    groups.back().second.push_back(at == std::string::npos ? "" : id.substr(at + 1));
  }
  const std::string& task_name = env->getTaskDescription().name;
  if (env->getFixedObjects().empty())
    std::cout << task << ", split " << split << ": " << ids.size() << " object"
              << (ids.size() == 1 ? "" : "s");
  else
    std::cout << task << " (fixed objects of " << task_name << ", whatever the split): "
              << ids.size() << " object" << (ids.size() == 1 ? "" : "s");
  if (groups.size() != ids.size())
    std::cout << " (target links of " << groups.size() << " articulated object"
              << (groups.size() == 1 ? "" : "s") << ")";
  std::cout << "\n";
  const std::string fixed_form = mb::makeFixedObjectId(task_name, "<object>");
  if (env->getFixedObjects().empty() && !fixed_form.empty())
    std::cout << "one object (or all of a group) as an environment: " << fixed_form << "\n";
  for (const auto& [group, links] : groups) {
    std::cout << "  " << std::left << std::setw(14) << group;
    for (const std::string& link : links)
      if (!link.empty()) std::cout << " " << group << "_" << link;
    std::cout << "\n";
  }
  return 0;
}

}  // namespace manibench::cli
