// manibench list: every plugin library found, what it registered, and the
// libraries refused with the reason.
#include <iomanip>
#include <iostream>
#include <manibench/task_name.hpp>

#include "cli.hpp"

namespace manibench::cli {

namespace {

const char* kListUsage = R"(usage: manibench list

Lists every plugin library found on the search path with what it registered
(kind, name, library version, file), then any library that was refused and why.
)";

}  // namespace

int commandList(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {}, {}, kListUsage);
  if (args.help) {
    std::cout << kListUsage;
    return 0;
  }
  if (!args.positional.empty()) throw UsageError("list takes no arguments", kListUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  std::cout << "search path:\n";
  for (const std::string& dir : mb::PluginRegistry::calcDefaultSearchPath())
    std::cout << "  " << dir << "\n";
  std::cout << "\n" << std::left << std::setw(12) << "KIND" << std::setw(26) << "NAME"
            << std::setw(10) << "VERSION" << "LIBRARY\n";
  for (const mb::PluginEntry& e : registry.getEntries()) {
    const mb::LoadedLibrary& lib = registry.getLibraries()[e.library];
    std::cout << std::left << std::setw(12) << mb::toString(e.kind) << std::setw(26) << e.name
              << std::setw(10) << lib.version << lib.path << "\n";
  }
  for (const std::string& task : registry.getNames(mb::PluginKind::Task)) {
    const std::string form = mb::makeFixedObjectId(task, "<object>");
    if (form.empty()) continue;
    std::cout << "\nevery task <Task>-v<N> is also one environment per object (or object group):\n"
              << "<Task>_<object>-v<N>, e.g. " << form
              << " (`manibench objects TASK` lists the objects)\n";
    break;
  }
  if (!registry.getFailures().empty()) {
    std::cout << "\nrefused libraries:\n";
    for (const mb::LoadFailure& f : registry.getFailures()) std::cout << "  " << f.message << "\n";
  }
  return 0;
}

}  // namespace manibench::cli
