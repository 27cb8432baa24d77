// The host's geometric records, one type per concept: every part of the
// host (scene, renderer, observation, the bridge to plugins) uses these, and
// the conversions to and from the ABI's frozen records live here once.
#pragma once

#include <manibench/abi.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace manibench {

struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

struct Twist {
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();  // world frame, rad/s
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();   // of the link origin, m/s
};

// One joint drive for the next control step, exactly as a controller plugin
// fills it (abi.h): tau = stiffness (position_target - q) + damping
// (velocity_target - qdot) + force, clamped to the effort limit when one is
// set. The ABI's record itself, so that the host hands the scene what the
// controller wrote without a copy; in C++ its fields start at 0 (a passive
// joint).
using DriveCommand = mb_drive_command;

// `a` then `b`: the pose of frame b, given in frame a, in a's parent frame.
inline Pose composePoses(const Pose& a, const Pose& b) {
  Pose out;
  out.position = a.position + a.orientation * b.position;
  out.orientation = (a.orientation * b.orientation).normalized();
  return out;
}

// mb_pose <-> Pose. The quaternion is copied as it is (w, x, y, z); whoever
// accepts a pose from a plugin checks that it has unit length.
inline Pose makePose(const mb_pose& p) {
  Pose out;
  out.position = Eigen::Vector3d(p.position[0], p.position[1], p.position[2]);
  out.orientation = Eigen::Quaterniond(p.quaternion[0], p.quaternion[1], p.quaternion[2],
                                       p.quaternion[3]);
  return out;
}
inline mb_pose makeCPose(const Pose& p) {
  mb_pose out;
  for (int i = 0; i < 3; ++i) out.position[i] = p.position[i];
  out.quaternion[0] = p.orientation.w();
  out.quaternion[1] = p.orientation.x();
  out.quaternion[2] = p.orientation.y();
  out.quaternion[3] = p.orientation.z();
  return out;
}

}  // namespace manibench
