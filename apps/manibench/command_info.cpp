// manibench info: a task's timing, observation and action layouts, success
// conditions, masks, objects and cameras, as configured.
#include <iostream>
#include <memory>

#include "cli.hpp"

namespace manibench::cli {

namespace {

const char* kInfoUsage = R"(usage: manibench info TASK [--controller NAME] [--config FILE]... [--set KEY=VALUE]...

Prints the task's timing, observation layout, the controller's action layout,
the success conditions, segmentation masks and the objects of each split, as
configured. TASK may be a fixed-object id such as OpenCabinetDrawer_1000-v0
(<Task>_<object>-v<N>): then the objects are that environment's.

Options:
  --controller NAME       override the task's default controller
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key, e.g. --set control.frequency=50; repeatable
)";

}  // namespace

int commandInfo(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {"controller", "config", "set"}, {}, kInfoUsage);
  if (args.help) {
    std::cout << kInfoUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("info needs exactly one TASK", kInfoUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  const std::unique_ptr<mb::Environment> env_owner =
      makeEnvironment(registry, args.positional[0], getConfigSources(args), true);
  mb::Environment& env = *env_owner;
  const mb::TaskDescription& task = env.getTaskDescription();
  const std::vector<std::string> train = env.listObjects("train");
  const std::vector<std::string> test = env.listObjects("test");
  if (train.empty()) throw std::runtime_error("task '" + task.name + "' has no train objects");
  env.reset(train.front(), 0);  // the action layout needs the robot's joints
  const mb::ControllerDescription& controller = env.getControllerDescription();

  if (!env.getFixedObjects().empty()) std::cout << "environment " << env.getEnvironmentId() << ": ";
  std::cout << "task " << task.name << " ("
            << registry.getLibraries()[registry.getEntry(mb::PluginKind::Task, task.name).library].path
            << ")\n";
  std::cout << "control " << task.control_frequency << " Hz, frame skip " << task.frame_skip
            << ", " << task.max_episode_steps << " steps per episode\n\n";
  std::cout << "observation (state), " << task.observation_dim << " values:\n";
  printSegments(task.observation_segments);
  std::cout << "pointcloud and rgbd modes: the first " << task.agent_state_dim
            << " values (the robot's own state) with the visual data\n";
  std::cout << "\naction, " << controller.action_dim << " values in [-1, 1], controller '"
            << controller.name << "'"
            << ((controller.flags & MB_CONTROLLER_BALANCE_PASSIVE_FORCES) ? " (balances gravity)" : "")
            << ":\n";
  printSegments(controller.action_segments);
  std::cout << "\nsuccess conditions:";
  for (const std::string& c : task.success_conditions) std::cout << " " << c;
  std::cout << "\nmasks:";
  if (task.masks.empty()) std::cout << " (none)";
  for (const std::string& m : task.masks) std::cout << " " << m;
  if (env.getFixedObjects().empty()) {
    std::cout << "\nobjects: " << train.size() << " train, " << test.size() << " test\n";
  } else {
    std::cout << "\nfixed objects (" << env.getFixedObjects().size() << "):";
    for (const std::string& o : env.getFixedObjects()) std::cout << " " << o;
    std::cout << "\n";
  }
  std::cout << "scene: " << env.getScene().getVisualShapes().size() << " visuals, "
            << env.getScene().calcVisualTriangleCount()
            << " mesh triangles (the renderer adds tessellated primitives)\n";
  std::cout << "cameras:";
  const std::vector<mb::CameraMount>& cameras = env.getOptions().observation.cameras;
  if (cameras.empty()) std::cout << " (none)";
  for (const mb::CameraMount& c : cameras)
    std::cout << " " << c.spec.name << " (" << c.spec.width << "x" << c.spec.height << ", "
              << (c.articulation.empty() ? std::string("world")
                                         : c.articulation + (c.link.empty() ? "" : ":" + c.link))
              << ")";
  std::cout << "\n";
  return 0;
}

}  // namespace manibench::cli
