// What the renderer's test programs share (renderer_test: images;
// renderer_fork_test: EGL across fork): a box scene and a hit count.
#pragma once

#include <manibench/renderer.hpp>
#include <manibench/scene.hpp>

#include <algorithm>
#include <sstream>
#include <string>

namespace manibench::render_test {

inline std::string inertial() {
  return "<inertial><mass value='1'/><inertia ixx='0.01' iyy='0.01' izz='0.01' ixy='0' "
         "ixz='0' iyz='0'/></inertial>";
}

// One link with one box visual of full extents (x, y, z) and color.
inline std::string boxUrdf(const std::string& name, double x, double y, double z,
                           const std::string& rgba = "0.8 0.8 0.8 1") {
  std::ostringstream s;
  s << "<robot name='" << name << "'><link name='" << name << "'>" << inertial()
    << "<visual><geometry><box size='" << x << " " << y << " " << z
    << "'/></geometry><material name='" << name << "_color'><color rgba='" << rgba
    << "'/></material></visual></link></robot>";
  return s.str();
}

inline Pose at(double x, double y, double z, double yaw = 0) {
  Pose p;
  p.position = Eigen::Vector3d(x, y, z);
  p.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return p;
}

// A finalized scene of one plate, 10 m square and 2 cm thick, centred 2 m
// along x: a camera at the origin looking along x sees nothing else.
struct PlateScene {
  Scene scene;
  PlateScene() {
    scene.addUrdfString(boxUrdf("plate", 0.02, 10, 10), "", "plate", at(2, 0, 0), true);
    scene.finalize();
  }
};

inline int countHits(const CameraImages& images) {
  return static_cast<int>(std::count_if(images.visual.begin(), images.visual.end(),
                                        [](int v) { return v >= 0; }));
}

}  // namespace manibench::render_test
