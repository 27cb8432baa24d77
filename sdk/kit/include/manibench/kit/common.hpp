// The kit's base: the SDK names its headers use. The kit (manibench::kit,
// <manibench/kit/...>) is what the mobile-manipulation task families share
// beyond the ABI: the mobile Panda, PartNet-Mobility objects, URDF trees,
// scripted policies' arithmetic, object catalogs. Header-only, over the
// SDK; versioned on its own (version.hpp), apart from the ABI.
#pragma once

#include <manibench/kit/version.hpp>
#include <manibench/sdk/common.hpp>
#include <manibench/sdk/scene_view.hpp>

namespace manibench::kit {

using sdk::Config;
using sdk::Error;
using sdk::kPi;
using sdk::Pose;
using sdk::SceneView;
using sdk::Segment;
using sdk::Twist;

// Writes `pose` at `at` of a state vector: position, then the quaternion
// w, x, y, z (the observations' order).
inline void putPose(Eigen::Ref<Eigen::VectorXd> out, uint32_t at, const Pose& pose) {
  out.segment<3>(at) = pose.position;
  out.segment<4>(at + 3) << pose.orientation.w(), pose.orientation.x(), pose.orientation.y(), pose.orientation.z();
}

}  // namespace manibench::kit
