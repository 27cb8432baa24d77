// manibench objects: the object ids of a task's split, grouped by the
// object family member they belong to when the ids say so ("1003_link_1":
// target link_1 of cabinet 1003).
#include <iomanip>
#include <iostream>
#include <map>

#include <manibench/environment.hpp>
#include <manibench/stopwatch.hpp>
#include <manibench/task_name.hpp>

#include "cli.hpp"

namespace manibench::cli {

namespace {

const char* kObjectsUsage = R"(usage: manibench objects TASK [--split train|test] [--ids] [--check] [--config FILE]... [--set KEY=VALUE]...

Lists the objects of a task's split (default train), as configured (a task
may read its objects from a folder named in its `task:` keys). Ids of the
form <object>_link_<k> (one target link of an articulated object, as in
OpenCabinetDoor-v0) are grouped by object. Every object, or group, is also an
environment of its own: <Task>_<object>-v<N>, e.g. OpenCabinetDrawer_1000-v0
(every target link of cabinet 1000) or OpenCabinetDrawer_1000_link_0-v0; given
such an id, this lists its objects (the same whatever the split).

With --check, every object of the split is loaded (its scene built twice,
reset and stepped 5 times with a zero action), one line each: loaded, with
its movable joints, its targets (ids), its collision pieces and the time
to build its scene the first time and again (meshes and hulls cached), or
skipped with the reason. Objects the task itself cannot use (a PartNet
object without a handle, say) are named in the warnings before the lines.
It exits 1 if any listed object fails.

Options:
  --split train|test      the split (default train)
  --ids                   only the ids, one a line (for scripts)
  --check                 load every object and say how it went
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key, e.g. --set task.partnet_dir=DIR; repeatable
)";

// The ids by the object they belong to, in listing order: "1003_link_1"
// is target link_1 of cabinet 1003 ("" for a plain id).
std::vector<std::pair<std::string, std::vector<std::string>>> groupObjects(const std::vector<std::string>& ids) {
  std::vector<std::pair<std::string, std::vector<std::string>>> groups;
  for (const std::string& id : ids) {
    const std::size_t at = id.rfind("_link_");
    const std::string group = at == std::string::npos ? id : id.substr(0, at);
    if (groups.empty() || groups.back().first != group) groups.push_back({group, {}});
    groups.back().second.push_back(at == std::string::npos ? "" : id.substr(at + 1));
  }
  return groups;
}

// One line per object: built twice (cold, then from the mesh caches),
// reset, stepped. Returns the number that failed.
int checkObjects(mb::Environment& env, const std::vector<std::string>& ids, double construction_s) {
  int failed = 0;
  const auto groups = groupObjects(ids);
  const std::string& robot = env.getTaskDescription().robot_articulation;
  for (const auto& [group, links] : groups) {
    const std::string first = links.front().empty() ? group : group + "_" + links.front();
    std::cout << "  " << std::left << std::setw(14) << group << std::flush;
    try {
      // The environment built the first object when it was made.
      const mb::Clock::time_point cold = mb::Clock::now();
      if (group != groups.front().first) env.loadObject(first);
      const double first_s = group == groups.front().first ? construction_s : mb::secondsSince(cold);
      const mb::Clock::time_point warm = mb::Clock::now();
      env.loadObject(first);
      const double again_s = mb::secondsSince(warm);
      env.reset(first, 0);
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(env.getControllerDescription().action_dim);
      for (int k = 0; k < 5; ++k) env.step(zero);
      const mb::Scene& scene = env.getScene();
      std::size_t movable = 0;
      int pieces = 0;
      for (int a = 0; a < scene.getArticulationCount(); ++a) {
        if (scene.getArticulationName(a) == robot) continue;
        movable += scene.getJoints(a).size();
        pieces += scene.getCollisionShapeCount(a);
      }
      std::cout << " loaded: " << movable << " movable joints";
      if (!links.front().empty()) {
        std::cout << ", " << links.size() << " target" << (links.size() == 1 ? "" : "s");
        for (const std::string& link : links) std::cout << " " << group << "_" << link;
      }
      std::cout << ", " << pieces << " collision pieces, scene " << std::fixed << std::setprecision(2) << first_s
                << " s (again " << again_s << " s)\n";
    } catch (const std::logic_error&) {
      throw;
    } catch (const std::exception& e) {
      ++failed;
      std::cout << " skipped: " << e.what() << "\n";
    }
  }
  return failed;
}

}  // namespace

int commandObjects(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {"split", "config", "set"}, {"ids", "check"}, kObjectsUsage);
  if (args.help) {
    std::cout << kObjectsUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("objects takes one TASK", kObjectsUsage);
  const std::string task = args.positional[0];
  const std::string split = parseSplit(args, "train", kObjectsUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  const mb::Clock::time_point start = mb::Clock::now();
  const auto env = makeEnvironment(registry, task, getConfigSources(args), true);
  const double construction_s = mb::secondsSince(start);
  const std::vector<std::string> ids = env->listObjects(split);
  if (args.options.count("ids")) {
    for (const std::string& id : ids) std::cout << id << "\n";
    return 0;
  }
  const auto groups = groupObjects(ids);
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
  if (args.options.count("check")) {
    for (const auto& [id, reason] : env->getSkippedObjects())
      std::cout << "  " << std::left << std::setw(14) << id << " skipped: " << reason << "\n";
    const int failed = checkObjects(*env, ids, construction_s);
    std::cout << groups.size() - static_cast<std::size_t>(failed) << " of " << groups.size()
              << " objects loaded\n";
    return failed == 0 && env->getSkippedObjects().empty() ? 0 : 1;
  }
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
