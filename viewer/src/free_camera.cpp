#include "free_camera.hpp"

#include <algorithm>
#include <cmath>

namespace manibench::viewer {
namespace {

constexpr double kMaxPitch = 1.55;    // rad, just short of straight down
constexpr double kRadPerPixel = 0.006;

Eigen::Vector3d calcDirection(double yaw, double pitch) {  // target -> eye
  return {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch)};
}

}  // namespace

void FreeCamera::aim(const Eigen::Vector3d& target, double distance, double yaw, double pitch) {
  target_ = target;
  distance_ = std::clamp(distance, kMinDistance, kMaxDistance);
  yaw_ = yaw;
  pitch_ = std::clamp(pitch, -kMaxPitch, kMaxPitch);
}

void FreeCamera::aimAtRobot(const Eigen::Vector3d& base, double yaw) {
  const Eigen::Vector3d ahead(std::cos(yaw), std::sin(yaw), 0);
  aim(base + 0.8 * ahead + Eigen::Vector3d(0, 0, 0.6), 3.4, yaw + M_PI + 0.55, 0.42);
}

void FreeCamera::orbit(double dx, double dy) {
  yaw_ = std::remainder(yaw_ - dx * kRadPerPixel, 2 * M_PI);
  pitch_ = std::clamp(pitch_ + dy * kRadPerPixel, -kMaxPitch, kMaxPitch);
}

void FreeCamera::pan(double dx, double dy, int viewport_height) {
  const double metres_per_pixel =
      2 * distance_ * std::tan(kFovy / 2) / std::max(1, viewport_height);
  const Eigen::Vector3d back = calcDirection(yaw_, pitch_);
  const Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(back).normalized();
  const Eigen::Vector3d up = back.cross(right);
  target_ += metres_per_pixel * (-dx * right + dy * up);
}

void FreeCamera::zoom(double steps) {
  distance_ = std::clamp(distance_ * std::pow(0.9, steps), kMinDistance, kMaxDistance);
}

Pose FreeCamera::calcPose() const {
  return calcLookAtPose(target_ + distance_ * calcDirection(yaw_, pitch_), target_);
}

CameraSpec FreeCamera::makeSpec(int width, int height) const {
  CameraSpec spec;
  spec.name = "viewer_free_camera";
  spec.width = width;
  spec.height = height;
  spec.fovy = kFovy;
  spec.near = 0.05;
  spec.far = 50;
  return spec;
}

}  // namespace manibench::viewer
