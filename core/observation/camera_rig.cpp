// Cameras mounted on links of a scene (or fixed in the world).
#include <manibench/visual_observer.hpp>

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
  const int robot = scene.findArticulation(articulation);
  const Eigen::Vector3d target =
      (robot >= 0 ? scene.getRootPose(robot).position : Eigen::Vector3d::Zero()) + Eigen::Vector3d(0, 0, 0.6);
  view.pose = calcLookAtPose(target + Eigen::Vector3d(2.5, -2.5, 1.6), target);
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
