// `manibench train sac` and `manibench train sac-population` (sac_command.cpp).
#pragma once

#include <string>

namespace manibench::learning::programs {

// Whether argv names a SAC command: `sac`, `sac-population`, or --resume
// of a directory that holds a SAC training.
bool isSacCommand(int argc, char** argv);
int runSacCommand(int argc, char** argv);

}  // namespace manibench::learning::programs
