// Scene building blocks shared by the contact test programs: URDF snippets,
// mesh files written on the fly, and a contact-rich pile with a driven arm.
#pragma once

#include <gtest/gtest.h>
#include <manibench/scene.hpp>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "../scene/scene_urdf.hpp"

namespace manibench {
namespace contact_scenes {

// The scene tests' constants and number format (scene/scene_urdf.hpp).
using scene_testing::kG;
using scene_testing::kPi;
using scene_testing::num;

// --- URDF building blocks -------------------------------------------------------

inline std::string origin(const Eigen::Vector3d& xyz,
                          const Eigen::Vector3d& rpy = Eigen::Vector3d::Zero()) {
  return "<origin xyz='" + num(xyz.x()) + " " + num(xyz.y()) + " " + num(xyz.z()) + "' rpy='" +
         num(rpy.x()) + " " + num(rpy.y()) + " " + num(rpy.z()) + "'/>";
}

// A collision element: `geometry` is the inner XML of <geometry>.
inline std::string collision(const std::string& geometry,
                             const Eigen::Vector3d& xyz = Eigen::Vector3d::Zero(),
                             const Eigen::Vector3d& rpy = Eigen::Vector3d::Zero()) {
  return "<collision>" + origin(xyz, rpy) + "<geometry>" + geometry + "</geometry></collision>";
}

inline std::string box(double x, double y, double z) {
  return "<box size='" + num(x) + " " + num(y) + " " + num(z) + "'/>";
}
inline std::string sphere(double r) { return "<sphere radius='" + num(r) + "'/>"; }
inline std::string cylinder(double r, double length) {
  return "<cylinder radius='" + num(r) + "' length='" + num(length) + "'/>";
}
inline std::string capsule(double r, double length) {
  return "<capsule radius='" + num(r) + "' length='" + num(length) + "'/>";
}
inline std::string mesh(const std::string& file, double scale = 1) {
  return "<mesh filename='" + file + "' scale='" + num(scale) + " " + num(scale) + " " +
         num(scale) + "'/>";
}

// 1 kg (or `mass`), centre of mass at the link origin.
inline std::string inertial(double mass = 1, double moment = 2e-3) {
  return "<inertial><origin xyz='0 0 0'/><mass value='" + num(mass) + "'/><inertia ixx='" +
         num(moment) + "' ixy='0' ixz='0' iyy='" + num(moment) + "' iyz='0' izz='" + num(moment) +
         "'/></inertial>";
}

inline std::string singleLink(const std::string& name, const std::string& body) {
  return "<?xml version='1.0'?><robot name='" + name + "'><link name='" + name + "'>" + body +
         "</link></robot>";
}

inline Pose at(double x, double y, double z, const Eigen::Vector3d& rpy = Eigen::Vector3d::Zero()) {
  Pose p;
  p.position = Eigen::Vector3d(x, y, z);
  p.orientation = Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX());
  return p;
}

// --- mesh files -------------------------------------------------------------------

inline std::string makeTempDir() {
  char dir_template[] = "/tmp/contact_test_XXXXXX";
  const char* dir = mkdtemp(dir_template);
  EXPECT_NE(dir, nullptr);
  return dir;
}

inline const std::string& getMeshDir() {
  static const std::string dir = makeTempDir();
  return dir;
}

// A right prism with a regular n-gon (circumradius r) as its cross
// section, from z = -h/2 to h/2, as an OBJ file. Its faces are split into
// triangles and fans, as exporters do; the hull merges them again.
inline std::string writePrismObj(const std::string& name, int n, double r, double h) {
  const std::string path = getMeshDir() + "/" + name + ".obj";
  std::ofstream out(path);
  out << "# prism\n";
  for (int k = 0; k < n; ++k) {
    const double a = 2 * kPi * k / n;
    out << "v " << num(r * std::cos(a)) << " " << num(r * std::sin(a)) << " " << num(-h / 2)
        << "\n";
    out << "v " << num(r * std::cos(a)) << " " << num(r * std::sin(a)) << " " << num(h / 2) << "\n";
  }
  for (int k = 0; k < n; ++k) {
    const int b0 = 2 * k + 1, t0 = 2 * k + 2, b1 = 2 * ((k + 1) % n) + 1,
              t1 = 2 * ((k + 1) % n) + 2;
    out << "f " << b0 << " " << b1 << " " << t1 << "\nf " << b0 << " " << t1 << " " << t0 << "\n";
  }
  for (int k = 1; k + 1 < n; ++k) {
    out << "f 1 " << 2 * (k + 1) + 1 << " " << 2 * k + 1 << "\n";
    out << "f 2 " << 2 * k + 2 << " " << 2 * (k + 1) + 2 << "\n";
  }
  return path;
}

// A square frustum (base side `bottom` at z = -h/2, top side `top` at
// z = h/2) as an ASCII STL file.
inline std::string writeFrustumStl(const std::string& name, double bottom, double top, double h) {
  const std::string path = getMeshDir() + "/" + name + ".stl";
  std::vector<Eigen::Vector3d> v;
  for (int k = 0; k < 4; ++k) {
    const double sx = (k == 0 || k == 3) ? 1 : -1, sy = k < 2 ? 1 : -1;
    v.emplace_back(sx * bottom / 2, sy * bottom / 2, -h / 2);
  }
  for (int k = 0; k < 4; ++k) {
    const double sx = (k == 0 || k == 3) ? 1 : -1, sy = k < 2 ? 1 : -1;
    v.emplace_back(sx * top / 2, sy * top / 2, h / 2);
  }
  const int tris[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                           {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::ofstream out(path);
  out << "solid frustum\n";
  for (const auto& t : tris) {
    out << " facet normal 0 0 0\n  outer loop\n";
    for (int i : t)
      out << "   vertex " << num(v[i].x()) << " " << num(v[i].y()) << " " << num(v[i].z()) << "\n";
    out << "  endloop\n endfacet\n";
  }
  out << "endsolid frustum\n";
  return path;
}

// --- a contact-rich scene ----------------------------------------------------------------

// Boxes, spheres, capsules, cylinders and a mesh dropped in a heap onto a
// floor and a two-link arm (capsule links) that sweeps through them.
struct PileScene {
  explicit PileScene(const std::string& integrator) : scene(makeSettings(integrator)) {
    scene.addGround(0);
    const std::string link_capsule =
        collision(capsule(0.03, 0.4), Eigen::Vector3d(0.2, 0, 0), Eigen::Vector3d(0, kPi / 2, 0));
    const std::string arm_urdf =
        "<?xml version='1.0'?><robot name='arm'><link name='base'/>"
        "<joint name='shoulder' type='revolute'><parent link='base'/><child link='upper'/>"
        "<origin xyz='0 0 0'/><axis xyz='0 0 1'/><limit lower='-3' upper='3' effort='0' "
        "velocity='10'/></joint>"
        "<link name='upper'>" +
        inertial(2, 0.05) + link_capsule +
        "</link>"
        "<joint name='elbow' type='revolute'><parent link='upper'/><child link='fore'/>"
        "<origin xyz='0.4 0 0'/><axis xyz='0 0 1'/><limit lower='-3' upper='3' effort='0' "
        "velocity='10'/></joint>"
        "<link name='fore'>" +
        inertial(1, 0.02) + link_capsule + "</link></robot>";
    arm = scene.addUrdfString(arm_urdf, "", "arm", at(0, 0, 0.05), true);
    const std::vector<std::string> shapes = {
        collision(box(0.08, 0.08, 0.08)),
        collision(sphere(0.04)),
        collision(capsule(0.03, 0.08), Eigen::Vector3d::Zero(), Eigen::Vector3d(0.3, 1.2, 0)),
        collision(cylinder(0.04, 0.08), Eigen::Vector3d::Zero(), Eigen::Vector3d(0.5, 0, 0)),
        collision(box(0.12, 0.05, 0.05)),
        collision(mesh(writePrismObj("pile_prism", 7, 0.045, 0.06))),
    };
    for (int i = 0; i < 12; ++i) {
      const double angle = 0.9 * i;
      bodies.push_back(
          scene.addUrdfString(singleLink("body", inertial(0.5, 1e-3) + shapes[i % shapes.size()]),
                              "", "body" + std::to_string(i),
                              at(0.45 + 0.07 * std::cos(angle), 0.07 * std::sin(angle),
                                 calcStartHeight(i), Eigen::Vector3d(0.1 * i, 0.2 * i, 0.3 * i)),
                              false));
    }
    scene.finalize();
  }
  static double calcStartHeight(int i) { return 0.15 + 0.11 * i; }
  static PhysicsSettings makeSettings(const std::string& integrator) {
    PhysicsSettings settings;
    settings.integrator = parseIntegrator(integrator);
    return settings;
  }
  void tick(int k) {
    DriveCommand shoulder, elbow;
    shoulder.stiffness = elbow.stiffness = 400;
    shoulder.damping = elbow.damping = 40;
    shoulder.position_target = 0.8 * std::sin(0.01 * k);
    elbow.position_target = -1.0 * std::sin(0.013 * k);
    scene.setDriveCommands(arm, {0, 1}, {shoulder, elbow});
    scene.advance(0.01);
  }
  std::vector<double> snapshot() const {
    std::vector<double> values;
    auto append = [&values](const auto& v) {
      values.insert(values.end(), v.data(), v.data() + v.size());
    };
    append(scene.getJointPositions(arm));
    append(scene.getJointVelocities(arm));
    for (int b : bodies) {
      const Pose pose = scene.getRootPose(b);
      const Twist twist = scene.getLinkTwist(scene.findLink(b, "body"));
      append(pose.position);
      append(pose.orientation.coeffs());
      append(twist.angular);
      append(twist.linear);
    }
    values.push_back(scene.getTime());
    return values;
  }
  Scene scene;
  int arm = -1;
  std::vector<int> bodies;
};

inline bool isBitIdentical(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// Runs two identical piles for `ticks` control ticks and compares every
// coordinate bit for bit.
inline void expectPileIsBitIdentical(const std::string& integrator, int ticks) {
  PileScene first(integrator), second(integrator);
  const std::vector<double> start = first.snapshot();
  for (int k = 0; k < ticks; ++k) {
    first.tick(k);
    second.tick(k);
  }
  const std::vector<double> a = first.snapshot(), b = second.snapshot();
  EXPECT_TRUE(isBitIdentical(a, b)) << integrator;
  // It was contact-rich: everything fell and came to rest on something.
  // Below where it started, not below a fixed height: the bodies are
  // dropped in a column, and whether it topples within the run is chaotic
  // (on some CPUs a body rests on an unfallen tower at 0.98 m after 3 s
  // of CPodes, where elsewhere all lay below 0.6 m).
  int resting = 0;
  for (size_t i = 0; i < first.bodies.size(); ++i) {
    const int body = first.bodies[i];
    const double z = first.scene.getRootPose(body).position.z();
    EXPECT_LT(z, PileScene::calcStartHeight(static_cast<int>(i))) << integrator << " body " << i;
    EXPECT_GT(z, 0.0) << integrator;
    if (first.scene.calcContactForce(first.scene.findLink(body, "body"), -1).norm() > 0) ++resting;
  }
  EXPECT_GE(resting, 6) << integrator;
  for (double v : a) ASSERT_TRUE(std::isfinite(v)) << integrator;
  EXPECT_NE(a, start) << integrator;
}

// Saves the pile mid-fall, runs on, restores and runs again: both runs
// (friction anchors included) are bit-identical.
inline void expectPileReplays(const std::string& integrator) {
  PileScene pile(integrator);
  for (int k = 0; k < 150; ++k) pile.tick(k);
  const SceneState saved = pile.scene.saveState();
  for (int k = 150; k < 250; ++k) pile.tick(k);
  const std::vector<double> first = pile.snapshot();
  pile.scene.restoreState(saved);
  for (int k = 150; k < 250; ++k) pile.tick(k);
  EXPECT_TRUE(isBitIdentical(first, pile.snapshot())) << integrator;
}

// Expects `call` to throw a SceneError mentioning every one of `needles`.
inline void expectSceneError(const std::function<void()>& call, const std::vector<std::string>& needles) {
  try {
    call();
    ADD_FAILURE() << "no SceneError";
  } catch (const SceneError& e) {
    for (const std::string& needle : needles)
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

}  // namespace contact_scenes
}  // namespace manibench
