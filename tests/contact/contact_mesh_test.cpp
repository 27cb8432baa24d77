// Collision meshes and capsules against real Simbody: a mesh collides as
// its convex hull and gives its link mass from the hull's volume, STL and
// COLLADA load with their units and axes, mesh paths resolve relative and
// as package URLs, bad meshes are errors naming link and file, flat ones
// are skipped with a note.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <manibench/scene.hpp>
#include <string>
#include <vector>

#include "contact_scenes.hpp"

namespace manibench {
namespace {

using namespace contact_scenes;

// --- meshes, capsules, mass from geometry ---------------------------------------------------

// Drops a link without <inertial> (mass from its collision volume at the
// default density, 1000 kg/m^3) on the floor; returns the resting contact
// force and the link origin's height.
std::pair<double, double> restOnFloor(const std::string& collisions, double z0,
                                      const std::string& base_dir = "") {
  Scene scene;
  scene.addGround(0);
  const int body =
      scene.addUrdfString(singleLink("body", collisions), base_dir, "body", at(0, 0, z0), false);
  scene.finalize();
  for (int k = 0; k < 100; ++k) scene.advance(0.01);
  return {scene.calcContactForce(scene.findLink(body, "body"), -1).z(),
          scene.getRootPose(body).position.z()};
}

TEST(ContactTest, MeshLinksGetMassFromTheirHullVolume) {
  // Hexagonal prism: volume (3 sqrt(3) / 2) r^2 h.
  const double r = 0.05, h = 0.08;
  const double volume = 3 * std::sqrt(3.0) / 2 * r * r * h;
  const auto [force, z] = restOnFloor(collision(mesh(writePrismObj("mass_prism", 6, r, h))), h / 2);
  EXPECT_NEAR(force, 1000 * volume * kG, 1e-3 * 1000 * volume * kG);
  EXPECT_NEAR(z, h / 2, 1e-3);
  // Scaled by 2 in every axis: 8 times the mass.
  const auto [force2, z2] =
      restOnFloor(collision(mesh(writePrismObj("mass_prism", 6, r, h), 2)), h);
  EXPECT_NEAR(force2, 8000 * volume * kG, 1e-3 * 8000 * volume * kG);
  EXPECT_NEAR(z2, h, 1e-3);
}

TEST(ContactTest, ConcaveMeshesCollideAsTheirConvexHull) {
  // A U-shaped channel 0.2 wide with a 0.1 wide, 0.1 deep notch on top.
  const std::string path = getMeshDir() + "/channel.obj";
  {
    std::ofstream out(path);
    // Profile in x-z (counterclockwise), extruded along y from -0.1 to 0.1.
    const double profile[8][2] = {{-0.1, 0},   {0.1, 0},     {0.1, 0.2},   {0.05, 0.2},
                                  {0.05, 0.1}, {-0.05, 0.1}, {-0.05, 0.2}, {-0.1, 0.2}};
    for (double y : {-0.1, 0.1})
      for (const auto& p : profile) out << "v " << p[0] << " " << y << " " << p[1] << "\n";
    for (int k = 0; k < 8; ++k) {
      const int a = k + 1, b = (k + 1) % 8 + 1;
      out << "f " << a << " " << b << " " << b + 8 << "\nf " << a << " " << b + 8 << " " << a + 8
          << "\n";
    }
  }
  Scene scene;
  const int channel = scene.addUrdfString(singleLink("channel", collision(mesh(path))), "",
                                          "channel", Pose(), true);
  // A ball above the notch rests on the hull's top (z = 0.2), not in the notch.
  const int ball = scene.addUrdfString(singleLink("ball", inertial() + collision(sphere(0.03))), "",
                                       "ball", at(0, 0, 0.235), false);
  scene.finalize();
  for (int k = 0; k < 100; ++k) scene.advance(0.01);
  EXPECT_NEAR(scene.getRootPose(ball).position.z(), 0.23, 1e-3);
  EXPECT_NEAR(
      scene.calcContactForce(scene.findLink(ball, "ball"), scene.findLink(channel, "channel")).z(),
      kG, 0.02 * kG);
}

TEST(ContactTest, StlAndColladaMeshesLoadWithTheirUnitsAndAxes) {
  // STL: the frustum, volume h/3 (A1 + A2 + sqrt(A1 A2)).
  const double b = 0.1, t = 0.06, h = 0.08;
  const double volume = h / 3 * (b * b + t * t + b * t);
  const auto [force, z] =
      restOnFloor(collision(mesh(writeFrustumStl("mass_frustum", b, t, h))), h / 2);
  EXPECT_NEAR(force, 1000 * volume * kG, 1e-3 * 1000 * volume * kG);
  EXPECT_NEAR(z, h / 2, 1e-3);

  // Collada in centimetres, Z up: a 10 x 20 x 4 cm box, which must lie
  // 4 cm high (the authored axes, as ROS tools load it) and weigh 0.8 kg.
  const std::string dae = getMeshDir() + "/box.dae";
  {
    std::ofstream out(dae);
    out << "<?xml version='1.0' encoding='utf-8'?>\n"
           "<COLLADA xmlns='http://www.collada.org/2005/11/COLLADASchema' version='1.4.1'>\n"
           "<asset><unit name='centimeter' meter='0.01'/><up_axis>Z_UP</up_axis></asset>\n"
           "<library_geometries><geometry id='box-mesh' name='box'><mesh>\n"
           "<source id='box-positions'><float_array id='box-positions-array' count='24'>";
    for (int i = 0; i < 8; ++i)
      out << (i & 1 ? 5 : -5) << " " << (i & 2 ? 10 : -10) << " " << (i & 4 ? 2 : -2) << " ";
    out << "</float_array><technique_common><accessor source='#box-positions-array' count='8' "
           "stride='3'>"
           "<param name='X' type='float'/><param name='Y' type='float'/><param name='Z' "
           "type='float'/>"
           "</accessor></technique_common></source>\n"
           "<vertices id='box-vertices'><input semantic='POSITION' "
           "source='#box-positions'/></vertices>\n"
           "<triangles count='12'><input semantic='VERTEX' source='#box-vertices' offset='0'/><p>"
           "0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5"
           "</p></triangles>\n</mesh></geometry></library_geometries>\n"
           "<library_visual_scenes><visual_scene id='Scene' name='Scene'><node id='box' name='box' "
           "type='NODE'>"
           "<instance_geometry url='#box-mesh'/></node></visual_scene></library_visual_scenes>\n"
           "<scene><instance_visual_scene url='#Scene'/></scene></COLLADA>\n";
  }
  const auto [dae_force, dae_z] = restOnFloor(collision(mesh(dae)), 0.02);
  EXPECT_NEAR(dae_force, 0.8 * kG, 1e-3 * 0.8 * kG);
  EXPECT_NEAR(dae_z, 0.02, 1e-3);
}

TEST(ContactTest, MeshPathsResolveRelativeAndPackageUrls) {
  const std::string root = makeTempDir();
  ASSERT_EQ(system(("mkdir -p " + root + "/my_robot/meshes " + root + "/my_robot/urdf").c_str()),
            0);
  const std::string mesh_file = root + "/my_robot/meshes/part.obj";
  std::rename(writePrismObj("part", 6, 0.05, 0.08).c_str(), mesh_file.c_str());
  const std::string urdf_dir = root + "/my_robot/urdf";
  for (const std::string& name :
       {std::string("package://my_robot/meshes/part.obj"), std::string("../meshes/part.obj"),
        "file://" + mesh_file, mesh_file}) {
    SCOPED_TRACE(name);
    const auto [force, z] = restOnFloor(inertial() + collision(mesh(name)), 0.04, urdf_dir);
    EXPECT_NEAR(force, kG, 0.02 * kG);
    EXPECT_NEAR(z, 0.04, 1e-3);
  }
}

TEST(ContactTest, BadMeshesAreErrorsNamingLinkAndFile) {
  Scene scene;
  expectSceneError(
      [&] {
        scene.addUrdfString(singleLink("part", collision(mesh("nowhere/missing.obj"))), "/tmp", "a",
                            Pose(), false);
      },
      {"link 'part'", "nowhere/missing.obj", "not found"});
  const std::string garbage = getMeshDir() + "/garbage.stl";
  std::ofstream(garbage) << "this is not a mesh\n";
  expectSceneError(
      [&] {
        scene.addUrdfString(singleLink("part", collision(mesh(garbage))), "", "b", Pose(), false);
      },
      {"link 'part'", "garbage.stl"});
  expectSceneError(
      [&] {
        scene.addUrdfString(
            singleLink("part", collision(mesh(writePrismObj("p0", 6, 0.05, 0.08), 0))), "", "c",
            Pose(), false);
      },
      {"link 'part'", "scale"});
  EXPECT_EQ(scene.getArticulationCount(), 0);
}

// PartNet models panels as single planes: a flat mesh becomes a solid
// kMinHullThickness (1 cm) thick about its plane, so it carries contact.
// A sheet in z = 0 (Qhull: a singular simplex) rests on the floor at half
// that; one in x = 0.2 (Qhull's QH6013: every point the same x), turned to
// lie flat, too; a 2 mm plate grows to 1 cm.
TEST(ContactTest, FlatMeshesBecomeThinSolids) {
  const std::string dir = getMeshDir();
  // Centred on the link's origin, where its mass is (a corner would tip).
  std::ofstream(dir + "/flat.obj") << "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\nf 1 2 3\nf 1 3 4\n";
  std::ofstream(dir + "/flat_x.obj") << "v 0.2 -0.5 -0.5\nv 0.2 0.5 -0.5\nv 0.2 0.5 0.5\nv 0.2 -0.5 0.5\nf 1 2 3\nf 1 3 4\n";
  std::ofstream(dir + "/plate.obj") << "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\nv -0.5 -0.5 0.002\n"
                                    << "v 0.5 -0.5 0.002\nv 0.5 0.5 0.002\nv -0.5 0.5 0.002\nf 1 2 3\nf 5 6 7\n";
  const Eigen::Vector3d flat_x(0, kPi / 2, 0);  // turns the x = 0.2 plane to z = -0.2
  struct Case {
    std::string file;
    Eigen::Vector3d rpy;
    double rest;  // the link origin's height at rest, m
  };
  for (const Case& c : {Case{"flat.obj", Eigen::Vector3d::Zero(), 0.005}, Case{"flat_x.obj", flat_x, 0.205},
                        Case{"plate.obj", Eigen::Vector3d::Zero(), 0.004}}) {
    Scene scene;
    scene.addGround(0);
    ::testing::internal::CaptureStderr();
    const int a = scene.addUrdfString(
        singleLink("sheet", inertial() + collision(mesh(dir + "/" + c.file), Eigen::Vector3d::Zero(), c.rpy)), "",
        "sheet", at(0, 0, c.rest + 0.05), false);
    const std::string note = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(note, "") << c.file << ": nothing is left unsimulated";
    scene.finalize();
    for (int k = 0; k < 100; ++k) scene.advance(0.01);
    EXPECT_NEAR(scene.getRootPose(a).position.z(), c.rest, 5e-4) << c.file;
  }
}

TEST(ContactTest, CapsulesAreParsedAlongsideOtherShapes) {
  // urdfdom alone drops every collision of a link with a <capsule>.
  const double r = 0.03, length = 0.1;
  const double volume = kPi * r * r * length + 4.0 / 3.0 * kPi * r * r * r;
  const Eigen::Vector3d along_x(0, kPi / 2, 0);
  const auto [force, z] =
      restOnFloor(collision(capsule(r, length), Eigen::Vector3d::Zero(), along_x), r);
  EXPECT_NEAR(force, 1000 * volume * kG, 1e-3 * 1000 * volume * kG);
  EXPECT_NEAR(z, r, 1e-3);
  // With a sphere hanging below it, the link rests on the sphere.
  const auto [force2, z2] =
      restOnFloor(collision(capsule(r, length), Eigen::Vector3d::Zero(), along_x) +
                      collision(sphere(0.05), Eigen::Vector3d(0, 0, -0.1)),
                  0.15);
  EXPECT_NEAR(z2, 0.15, 1e-3);
  EXPECT_GT(force2, force);
}

}  // namespace
}  // namespace manibench
