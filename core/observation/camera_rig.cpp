// Cameras mounted on links of a scene (or fixed in the world).
#include <manibench/visual_observer.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <vector>

namespace manibench {

std::string describeArticulations(const Scene& scene) {
  std::string names;
  for (int i = 0; i < scene.getArticulationCount(); ++i)
    names += (names.empty() ? "'" : ", '") + scene.getArticulationName(i) + "'";
  return names.empty() ? "none" : names;
}

ThirdPersonView calcThirdPersonView(const Scene& scene, const std::string& articulation, int width,
                                    int height) {
  ThirdPersonView view;
  view.camera.name = "third_person";
  view.camera.width = width;
  view.camera.height = height;
  view.camera.fovy = 1.0;
  view.camera.far = 20;
  // Framed on everything the task put in the scene (the robot, the task's
  // objects): the corners of every visual shape's box (a mesh's vertices,
  // a primitive's extent) at the links' poses now; the camera looks at the middle of what it sees
  // and stands as close as keeps every corner in the frame. Before, it
  // stood a fixed 3.9 m from a point over the robot's root, from the
  // object's far side, and robot and cabinet filled about a fifth of the
  // frame's height.
  const int robot = scene.findArticulation(articulation);
  std::set<int> robot_links;
  if (robot >= 0)
    for (int link : scene.listLinks(robot)) robot_links.insert(link);
  std::vector<Eigen::Vector3d> corners;
  // The means of the robot's shapes' corners and of the other shapes'
  // (the root of a mobile robot stays at the world's origin: its planar
  // joints move the base).
  Eigen::Vector3d robot_mean = Eigen::Vector3d::Zero(), objects = Eigen::Vector3d::Zero();
  int robot_corners = 0, object_corners = 0;
  for (const VisualShape& shape : scene.getVisualShapes()) {
    if (shape.link < 0) continue;
    Eigen::Vector3d local_lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d local_hi = -local_lo;
    if (shape.kind == VisualShape::Kind::Mesh) {
      if (shape.meshes)
        for (const VisualMesh& mesh : *shape.meshes)
          for (const Eigen::Vector3f& v : mesh.positions) {  // mesh_scale applied at load
            const Eigen::Vector3d p = v.cast<double>();
            local_lo = local_lo.cwiseMin(p);
            local_hi = local_hi.cwiseMax(p);
          }
      if (!(local_lo.array() <= local_hi.array()).all()) continue;
    } else {
      const Eigen::Vector3d& z = shape.size;
      const Eigen::Vector3d half = shape.kind == VisualShape::Kind::Box      ? 0.5 * z
                                   : shape.kind == VisualShape::Kind::Sphere ? Eigen::Vector3d::Constant(z.x())
                                                                             : Eigen::Vector3d(z.x(), z.x(), 0.5 * z.y() + z.x());
      local_lo = -half;
      local_hi = half;
    }
    const Pose pose = composePoses(scene.getLinkPose(shape.link), shape.pose_in_link);
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d c((corner & 1) ? local_hi.x() : local_lo.x(), (corner & 2) ? local_hi.y() : local_lo.y(),
                              (corner & 4) ? local_hi.z() : local_lo.z());
      Eigen::Vector3d w = pose.position + pose.orientation * c;
      w.z() = std::max(w.z(), scene.getGroundHeight());  // below the ground is not seen
      corners.push_back(w);
      if (robot_links.count(shape.link)) {
        robot_mean += w;
        ++robot_corners;
      } else {
        objects += w;
        ++object_corners;
      }
    }
  }
  if (corners.empty())  // nothing drawn: the robot's root, or the origin
    corners.push_back(robot >= 0 ? scene.getRootPose(robot).position : Eigen::Vector3d::Zero());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : corners) mean += c / double(corners.size());
  // The camera's axes: toward it, right, up. It looks from the robot's side
  // of the objects (the robot starts facing the door, drawer, chair or
  // bucket it works on), turned 45 degrees to the robot's right and 24
  // degrees above: the robot is on the near side of what is framed, not
  // behind the object where it would be hidden once it reaches it. Without
  // a robot or objects, from +x turned the same way.
  Eigen::Vector3d toward_robot = Eigen::Vector3d::UnitX();
  if (robot_corners > 0 && object_corners > 0) {
    Eigen::Vector3d d = robot_mean / double(robot_corners) - objects / double(object_corners);
    d.z() = 0;
    if (d.norm() > 1e-6) toward_robot = d.normalized();
  }
  const Eigen::Vector3d side = Eigen::AngleAxisd(-M_PI / 4, Eigen::Vector3d::UnitZ()) * toward_robot;
  const Eigen::Vector3d back = (side + std::tan(24.0 * M_PI / 180) * Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(back).normalized();
  const Eigen::Vector3d up = back.cross(right);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const Eigen::Vector3d& c : corners) {
    const Eigen::Vector2d p(right.dot(c - mean), up.dot(c - mean));
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector2d middle = 0.5 * (lo + hi);
  const Eigen::Vector3d target = mean + middle.x() * right + middle.y() * up;
  // Each corner in the frame: its offset from the middle within the view's
  // half-angle at its depth (the camera at `distance` along `back`), with
  // 5 % of the frame to spare; never nearer than 1 m.
  constexpr double kMargin = 1.05, kMinDistance = 1.0;
  const double tan_y = std::tan(0.5 * view.camera.fovy);
  const double tan_x = tan_y * double(width) / double(std::max(1, height));
  double distance = kMinDistance;
  for (const Eigen::Vector3d& c : corners) {
    const Eigen::Vector3d d = c - target;
    const double toward = back.dot(d);  // nearer the camera by this much
    distance = std::max({distance, kMargin * std::abs(right.dot(d)) / tan_x + toward,
                         kMargin * std::abs(up.dot(d)) / tan_y + toward});
  }
  view.pose = calcLookAtPose(target + distance * back, target);
  return view;
}

CameraRig::CameraRig(const Scene& scene, const std::vector<CameraMount>& cameras,
                     const std::string& task_name)
    : scene_(scene), cameras_(cameras) {
  for (const CameraMount& camera : cameras_) {
    const std::string where = (camera.source.empty() ? "" : camera.source + ": ") + "camera '" +
                              camera.spec.name + "'";
    if (camera.articulation.empty()) {
      articulations_.push_back(-1);
      links_.push_back(-2);
      continue;
    }
    const int articulation = scene_.findArticulation(camera.articulation);
    if (articulation < 0)
      throw SceneError(where + ": the scene of task '" + task_name + "' has no articulation '" +
                       camera.articulation + "' (it has " + describeArticulations(scene_) + ")");
    int link = -1;
    if (!camera.link.empty()) {
      link = scene_.findLink(articulation, camera.link);
      if (link < 0)
        throw SceneError(where + ": articulation '" + camera.articulation + "' has no link '" +
                         camera.link + "'");
    }
    articulations_.push_back(articulation);
    links_.push_back(link);
  }
}

Pose CameraRig::calcCameraPose(std::size_t index) const {
  const CameraMount& camera = cameras_.at(index);
  const int link = links_.at(index);
  if (link == -2) return camera.pose;
  const Pose mount =
      link >= 0 ? scene_.getLinkPose(link) : scene_.getRootPose(articulations_.at(index));
  return composePoses(mount, camera.pose);
}

}  // namespace manibench
