// manibench: the host program. Loads plugins by name and runs them.
//   manibench list | info | run | bench | config | render | objects | eval | demos | demo | train | plot | report | view
// `train`, `plot`, `report` and `view` are other programs, manibench-train,
// manibench-plot, manibench-report and manibench-view,
// found beside this one (as git runs git-<command>): the learning module's
// libtorch and the viewer's GLFW never load here.
// Exit codes: 0 success, 1 failure (reported on stderr), 2 usage error.
// Each command lives in its own command_*.cpp; cli.hpp declares them.
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "cli.hpp"

using namespace manibench::cli;

namespace {

const char* kMainUsage = R"(usage: manibench <command> [options]

Commands:
  list                      every loaded plugin: kind, name, version, library
  info TASK                 observation and action layout, success conditions,
                            masks and objects of a task
  run TASK --policy NAME    run one episode and print steps, return, success
  bench TASK                environment steps per second of a task
  render TASK --out DIR     camera images, masks and point clouds as PNG/PLY
  eval TASK --policy NAME   evaluate a policy on a split's objects: success
                            rates per object, CSV and JSON (docs/evaluation.md)
  eval --verify DIR         check a report against its certificate and re-run
                            its episodes bit for bit
  compare A B               two reports of the same episodes: the paired
                            difference per object and overall, its interval
                            and McNemar's exact test (docs/evaluation.md)
  demos generate|merge|replay|convert|info
                            demonstrations: a policy's successful episodes in
                            HDF5, merged from shards, replayed bit for bit,
                            converted to another observation mode
                            (docs/demonstrations.md)
  objects TASK              object ids of a split (--split train|test)
  survey TASK DIR...        a policy (the task's expert) on every object of
                            folders of PartNet-Mobility objects: success and
                            why each episode failed, per object and category
                            (docs/partnet.md)
  config [TASK]             print the merged YAML configuration
  demo                      list the plugins, then evaluate the cabinet expert
                            on the OpenCabinetDrawer-v0 test split
  train bc|bcq|td3bc        learn a policy from demonstrations (docs/learning.md;
                            built where libtorch is installed)
  train sac|sac-population  SAC agents on the dense reward, one per object for
                            demonstrations (supplement C.2; docs/learning.md)
  plot DIR...               figures: eval results (success and each condition
                            per object, train vs test), training curves or a
                            render folder's point cloud (matplotlib;
                            docs/evaluation.md)
  report DIR                one HTML page of an eval folder: the tables with
                            their intervals, why episodes failed, the figure,
                            videos of a success and a failure per object, the
                            certificate (docs/evaluation.md)
  view TASK                 a window on a task: free and task cameras, masks,
                            point cloud, overlay; drive the robot by keyboard
                            (--record FILE.h5), watch --policy NAME or
                            --replay FILE.h5 (docs/viewer.md; needs a display)

TASK is a task name (a random object of the split each episode) or a
fixed-object id <Task>_<object>-v<N>, e.g. OpenCabinetDrawer_1000-v0.
Run `manibench <command> --help` for a command's options. info, run, bench,
render, eval, objects and config take --config FILE and --set KEY=VALUE
(docs/configuration.md). The commands that run a policy (run, bench, render
--video, eval, demos generate, view) take --policy NAME, a library PATH.so,
a Python policy class PATH.py (docs/python.md) or a checkpoint PATH.pt
(docs/learning.md).
Plugins are searched in $MANIBENCH_PLUGIN_PATH, ~/.local/lib/manibench/plugins,
then lib/manibench/plugins of this program's own installation (or build tree).
)";

// Replaces this process with manibench-<command> from this program's folder;
// `missing` says where that program comes from when it is not there.
int runExternalCommand(const std::string& command, int argc, char** argv, const std::string& missing) {
  char self[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  const std::string dir = n > 0 ? std::filesystem::path(std::string(self, std::size_t(n))).parent_path().string() : ".";
  const std::string program = dir + "/manibench-" + command;
  if (access(program.c_str(), X_OK) != 0)
    throw std::runtime_error("'" + command + "' needs " + program + ", which is not there: " + missing);
  std::vector<char*> args(argv, argv + argc);
  args.push_back(nullptr);
  execv(program.c_str(), args.data());
  throw std::runtime_error("cannot run " + program + ": " + std::strerror(errno));
}

// The command named by argv[1].
int dispatch(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  if (command == "--help" || command == "-h" || command == "help") {
    std::cout << kMainUsage;
    return 0;
  }
  if (command == "list") return commandList(argc, argv);
  if (command == "info") return commandInfo(argc, argv);
  if (command == "run") return commandRun(argc, argv);
  if (command == "config") return commandConfig(argc, argv);
  if (command == "demo") return commandDemo(argc, argv);
  if (command == "bench") return commandBench(argc, argv);
  if (command == "render") return commandRender(argc, argv);
  if (command == "eval") return commandEval(argc, argv);
  if (command == "objects") return commandObjects(argc, argv);
  if (command == "survey") return commandSurvey(argc, argv);
  if (command == "compare") return commandCompare(argc, argv);
  if (command == "demos") return commandDemos(argc, argv);
  if (command == "train")
    return runExternalCommand(command, argc, argv,
                              "the learning module, built where libtorch is installed (Debian's "
                              "libtorch-dev; scripts/install-deps installs it), docs/learning.md");
  if (command == "plot" || command == "report")
    return runExternalCommand(command, argc, argv,
                              "the Python package (built where pybind11, python3-dev and numpy are installed) "
                              "and matplotlib (Debian's python3-matplotlib; scripts/install-deps installs them)");
  if (command == "view")
    return runExternalCommand(command, argc, argv,
                              "the viewer, built where GLFW and Dear ImGui are installed (Debian's "
                              "libglfw3-dev and libimgui-dev; scripts/install-deps installs them), "
                              "docs/viewer.md");
  throw UsageError(command.empty() ? "no command given" : "unknown command '" + command + "'",
                   kMainUsage);
}

}  // namespace

int main(int argc, char** argv) {
  return runMain("manibench", [&] { return dispatch(argc, argv); });
}
