// The viewer's free camera: it orbits a target point (yaw about the world's
// z axis, pitch above the horizon, distance), pans the target in the view
// plane and zooms by distance, as mouse drags and the wheel ask. Poses are
// the renderer's (SAPIEN camera frame: +x forward, +z up).
#pragma once

#include <manibench/geometry.hpp>
#include <manibench/renderer.hpp>

#include <Eigen/Core>

namespace manibench::viewer {

class FreeCamera {
 public:
  // Looks at `target` from `distance` m, `yaw` rad about z (0: from +x
  // towards -x) and `pitch` rad above the horizon.
  void aim(const Eigen::Vector3d& target, double distance, double yaw, double pitch);
  // From behind and above a robot at `base` heading `yaw` (rad about z),
  // a little to its right, looking past it at what lies ahead of it (the
  // tasks put the object there).
  void aimAtRobot(const Eigen::Vector3d& base, double yaw);

  // A drag of (dx, dy) pixels: turns about the target (right: the scene
  // turns right, down: the camera rises).
  void orbit(double dx, double dy);
  // A drag of (dx, dy) pixels in a view `viewport_height` pixels high: the
  // point under the mouse stays under it (at the target's depth).
  void pan(double dx, double dy, int viewport_height);
  // Wheel `steps` (positive: closer), 10 % of the distance per step.
  void zoom(double steps);
  // Moves target and camera together (following the robot).
  void translate(const Eigen::Vector3d& delta) { target_ += delta; }

  Pose calcPose() const;
  // The camera at a `width` x `height` image (fovy fixed).
  CameraSpec makeSpec(int width, int height) const;
  const Eigen::Vector3d& getTarget() const { return target_; }
  double getDistance() const { return distance_; }
  double getYaw() const { return yaw_; }
  double getPitch() const { return pitch_; }

  static constexpr double kFovy = 0.9;  // rad, about 52 degrees
  static constexpr double kMinDistance = 0.2, kMaxDistance = 30;

 private:
  Eigen::Vector3d target_{0, 0, 0.6};
  double distance_ = 4, yaw_ = 0, pitch_ = 0.4;
};

}  // namespace manibench::viewer
