// What a mobile-manipulation task family includes: the SDK, the mobile
// Panda (its facts, observation, placement; the experts' segments), the
// object catalog and ids, the object facts (object_facts.hpp), and the SDK's fully specified random numbers.
// A family writes `using namespace manibench::kit;` in its own namespace
// and then names everything it shares plainly: sdk::Task, Config, Error,
// Pose, SceneView, kPi, putPose, Random, hashString, mobile_panda::...
#pragma once

#include <manibench/kit/catalog.hpp>
#include <manibench/kit/object_facts.hpp>
#include <manibench/kit/mobile_panda.hpp>
#include <manibench/sdk.hpp>
#include <manibench/sdk/random.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace manibench::kit {

namespace sdk = manibench::sdk;
using sdk::hashString;
using sdk::Random;

}  // namespace manibench::kit
