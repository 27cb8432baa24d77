// URDF snippets and helpers shared by the scene tests (scene_test.cpp,
// scene_dynamics_test.cpp).
#pragma once

#include <gtest/gtest.h>
#include <manibench/sdk/numbers.hpp>
#include <manibench/scene.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace manibench {
namespace scene_testing {

using sdk::kPi;
constexpr double kG = 9.81;

// --- URDF snippets -----------------------------------------------------------

inline std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

inline std::string vec3(double x, double y, double z) {
  return num(x) + " " + num(y) + " " + num(z);
}

// <inertial> with the central inertia given in a frame rotated by rpy.
inline std::string inertial(double mass, const std::string& xyz, double ixx,
                     double iyy, double izz, const std::string& rpy = "0 0 0",
                     double ixy = 0, double ixz = 0, double iyz = 0) {
  return "<inertial><origin xyz='" + xyz + "' rpy='" + rpy + "'/><mass value='" +
         num(mass) + "'/><inertia ixx='" + num(ixx) + "' ixy='" + num(ixy) +
         "' ixz='" + num(ixz) + "' iyy='" + num(iyy) + "' iyz='" + num(iyz) +
         "' izz='" + num(izz) + "'/></inertial>";
}

inline std::string link(const std::string& name, const std::string& body = "") {
  return "<link name='" + name + "'>" + body + "</link>";
}

inline std::string joint(const std::string& name, const std::string& type,
                  const std::string& parent, const std::string& child,
                  const std::string& xyz, const std::string& axis,
                  const std::string& extra = "", const std::string& rpy = "0 0 0") {
  std::string j = "<joint name='" + name + "' type='" + type + "'><parent link='" +
                  parent + "'/><child link='" + child + "'/><origin xyz='" + xyz +
                  "' rpy='" + rpy + "'/>";
  if (!axis.empty()) j += "<axis xyz='" + axis + "'/>";
  return j + extra + "</joint>";
}

inline std::string robot(const std::string& name, const std::string& body) {
  return "<?xml version='1.0'?><robot name='" + name + "'>" + body + "</robot>";
}

inline std::string sphereCollision(double r) {
  return "<collision><geometry><sphere radius='" + num(r) + "'/></geometry></collision>";
}

const std::string kLimit = "<limit lower='-3' upper='3' effort='0' velocity='10'/>";

// A free sphere of radius r, mass from default_density.
inline std::string ballUrdf(double r) {
  return robot("ball", link("ball", sphereCollision(r)));
}

// Two-link planar arm turning about y; links of mass m with their mass at
// (L/2, 0, 0) (horizontal at q = 0), optionally a 5 cm ball on each link.
inline std::string armUrdf(double m = 1, double L = 0.5, bool with_collision = false) {
  const double I = m * L * L / 12;
  const std::string ball =
      with_collision ? "<collision><origin xyz='0.1 0 0'/><geometry><sphere radius='0.05'/>"
                       "</geometry></collision>"
                     : "";
  return robot(
      "arm", link("base") +
                 joint("shoulder", "revolute", "base", "upper", "0 0 0", "0 1 0", kLimit) +
                 link("upper", inertial(m, vec3(L / 2, 0, 0), 1e-4, I, I) + ball) +
                 joint("elbow", "revolute", "upper", "fore", vec3(L, 0, 0), "0 1 0", kLimit) +
                 link("fore", inertial(m, vec3(L / 2, 0, 0), 1e-4, I, I) + ball));
}

// One link spinning about the vertical z axis (no gravity torque).
inline std::string spinnerUrdf(double izz, const std::string& limit_and_dynamics) {
  return robot("spinner",
               link("base") +
                   joint("spin", "continuous", "base", "blade", "0 0 0", "0 0 1",
                         limit_and_dynamics) +
                   link("blade", inertial(1.0, "0 0 0", izz, izz, izz)));
}

inline Pose at(double x, double y, double z) {
  Pose p;
  p.position = Eigen::Vector3d(x, y, z);
  return p;
}

inline std::string writeTempFile(const std::string& stem, const std::string& content) {
  char dir_template[] = "/tmp/scene_test_XXXXXX";
  const char* dir = mkdtemp(dir_template);
  EXPECT_NE(dir, nullptr);
  const std::string path = std::string(dir) + "/" + stem;
  std::ofstream(path) << content;
  return path;
}

// Mean period of each joint of `articulation` from the upward zero
// crossings of its angle, sampled every millisecond for `duration` seconds
// and interpolated linearly (NaN with fewer than two crossings).
inline Eigen::VectorXd measurePeriods(Scene& scene, int articulation, double duration) {
  const double dt = 1e-3;
  Eigen::VectorXd previous = scene.getJointPositions(articulation);
  std::vector<std::vector<double>> up(previous.size());
  const int ticks = static_cast<int>(std::lround(duration / dt));
  for (int k = 1; k <= ticks; ++k) {
    const double t0 = scene.getTime();
    scene.advance(dt);
    const Eigen::VectorXd q = scene.getJointPositions(articulation);
    for (Eigen::Index j = 0; j < q.size(); ++j)
      if (previous[j] < 0 && q[j] >= 0)
        up[j].push_back(t0 + dt * -previous[j] / (q[j] - previous[j]));
    previous = q;
  }
  Eigen::VectorXd periods(previous.size());
  for (Eigen::Index j = 0; j < periods.size(); ++j)
    periods[j] = up[j].size() < 2 ? NAN
                                  : (up[j].back() - up[j].front()) / static_cast<double>(up[j].size() - 1);
  return periods;
}

inline PhysicsSettings zeroGravity() {
  PhysicsSettings settings;
  settings.gravity_z = 0;
  return settings;
}

inline PhysicsSettings preciseSettings() {
  PhysicsSettings settings;
  settings.integrator = Integrator::RkMerson;
  settings.accuracy = 1e-8;
  settings.gravity_z = -kG;
  return settings;
}

}  // namespace scene_testing
}  // namespace manibench
