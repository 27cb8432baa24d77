// manibench demo: the plugin list, then the cabinet expert's evaluation on
// the OpenCabinetDrawer-v0 test split.
#include <iostream>
#include <string>
#include <vector>

#include "cli.hpp"

namespace manibench::cli {

namespace {

const char* kDemoUsage = R"(usage: manibench demo [--out DIR]

Lists the plugins, then evaluates the scripted expert (open_cabinet_expert,
on the mobile_panda_ee controller it names) on the test split of OpenCabinetDrawer-v0 in
state mode, one episode per object with two workers, and prints the table:
the same as

  manibench eval OpenCabinetDrawer-v0 --policy open_cabinet_expert \
      --obs state --split test \
      --episodes-per-object 1 --workers 2 --seed 0 --out DIR

Options:
  --out DIR   where the CSV and JSON files go (default demo-results)
)";

}  // namespace

int commandDemo(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2, {"out"}, {}, kDemoUsage);
  if (args.help) {
    std::cout << kDemoUsage;
    return 0;
  }
  if (!args.positional.empty()) throw UsageError("demo takes no arguments", kDemoUsage);
  commandList(2, argv);
  std::cout << "\n" << std::flush;
  std::vector<std::string> words = {argv[0], "eval", "OpenCabinetDrawer-v0",
                                    "--policy", "open_cabinet_expert",
                                    "--obs", "state", "--split", "test",
                                    "--episodes-per-object", "1", "--workers", "2",
                                    "--seed", "0", "--out", valueOr(args, "out", "demo-results")};
  std::vector<char*> eval_argv;
  for (std::string& w : words) eval_argv.push_back(w.data());
  eval_argv.push_back(nullptr);
  return manibench::cli::commandEval(int(words.size()), eval_argv.data());
}

}  // namespace manibench::cli
