// SDK 1.3's path of the mobile Panda helpers, kept so that a family written
// against it still compiles (the SDK promises 1.x source compatibility).
// They are the kit's since kit 1.0: <manibench/kit/mobile_panda.hpp>,
// namespace manibench::kit::mobile_panda (sdk/kit/README.md); new code
// includes that and links manibench::kit. The old names resolve to the
// kit's through the using-directive below (tests/sdk/sdk13_paths_test.cpp).
#pragma once

#include <manibench/kit/mobile_panda.hpp>

namespace manibench::sdk::mobile_panda {
using namespace manibench::kit::mobile_panda;
}  // namespace manibench::sdk::mobile_panda
