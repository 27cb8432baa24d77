// The renderer's camera geometry that needs no context: depth images to
// points, and a camera pose looking at a target.
#include <manibench/renderer.hpp>

#include <string>
#include <vector>

namespace manibench {

Eigen::Matrix3Xf calcCameraPoints(const CameraImages& images, bool world,
                                  std::vector<int>* pixels) {
  const std::size_t count = static_cast<std::size_t>(images.width) * images.height;
  if (images.depth.size() != count) {
    throw RenderError("calcCameraPoints: " + std::to_string(images.depth.size()) +
                      " depth values for a " + std::to_string(images.width) + "x" +
                      std::to_string(images.height) + " image");
  }
  std::size_t valid = 0;
  for (float z : images.depth) valid += z > 0 ? 1 : 0;
  Eigen::Matrix3Xf points(3, static_cast<Eigen::Index>(valid));
  if (pixels != nullptr) pixels->resize(valid);
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  if (world) {
    rotation = images.camera_to_world.linear();
    translation = images.camera_to_world.translation();
  }
  Eigen::Index k = 0;
  for (int row = 0; row < images.height; ++row) {
    for (int col = 0; col < images.width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * images.width + col;
      const float z = images.depth[i];
      if (!(z > 0)) continue;
      points.col(k) = calcPixelPoint(images.intrinsic, rotation, translation, row, col, z);
      if (pixels != nullptr) (*pixels)[static_cast<std::size_t>(k)] = static_cast<int>(i);
      ++k;
    }
  }
  return points;
}

Pose calcLookAtPose(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                    const Eigen::Vector3d& up) {
  const Eigen::Vector3d forward = target - eye;
  if (!(forward.norm() > 1e-12)) throw RenderError("calcLookAtPose: eye and target coincide");
  const Eigen::Vector3d x = forward.normalized();
  Eigen::Vector3d y = up.cross(x);
  if (y.norm() < 1e-9) y = Eigen::Vector3d::UnitX().cross(x);  // looking along `up`
  if (y.norm() < 1e-9) y = Eigen::Vector3d::UnitY().cross(x);
  y.normalize();
  const Eigen::Vector3d z = x.cross(y);
  Eigen::Matrix3d rotation;
  rotation.col(0) = x;
  rotation.col(1) = y;
  rotation.col(2) = z;
  Pose pose;
  pose.position = eye;
  pose.orientation = Eigen::Quaterniond(rotation).normalized();
  return pose;
}

}  // namespace manibench
