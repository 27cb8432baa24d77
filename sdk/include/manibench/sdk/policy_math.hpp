// SDK 1.3's path of scripted policies' arithmetic, kept so that a family
// written against it still compiles (the SDK promises 1.x source
// compatibility). It is the kit's since kit 1.0:
// <manibench/kit/policy_math.hpp>, namespace manibench::kit
// (sdk/kit/README.md); new code includes that and links manibench::kit.
// The old names (sdk::getVector3, sdk::MobilePandaSpeeds, ...) resolve to
// the kit's through the using-declarations below
// (tests/sdk/sdk13_paths_test.cpp).
#pragma once

#include <manibench/kit/policy_math.hpp>

namespace manibench::sdk {
using kit::clipNorm;
using kit::clipUnit;
using kit::getQuaternion;
using kit::getVector3;
using kit::MobilePandaSpeeds;
using kit::setBaseAction;
using kit::setEeAction;
using kit::wrapAngle;
}  // namespace manibench::sdk
