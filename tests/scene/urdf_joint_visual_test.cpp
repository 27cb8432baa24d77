// URDF features beyond the basic tree: visual geometry and materials for the
// renderer (primitives, named materials, OBJ meshes with MTL colors, the
// robots' meshes), planar joints and mimic joints.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <manibench/scene.hpp>
#include <sstream>
#include <string>

namespace manibench {
namespace {

const std::string kRobotDir = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/assets/robots";

std::string makeTempDir() {
  char dir_template[] = "/tmp/urdf_visual_test_XXXXXX";
  const char *dir = mkdtemp(dir_template);
  EXPECT_NE(dir, nullptr);
  return dir ? dir : "/tmp";
}

void writeFile(const std::string &path, const std::string &text) {
  std::ofstream out(path);
  out << text;
}

// A unit cube (12 triangles) whose faces use material `red` from cube.mtl.
void writeCube(const std::string &dir) {
  writeFile(dir + "/cube.mtl", "newmtl red\nKd 0.8 0.1 0.2\nd 1.0\n");
  writeFile(dir + "/cube.obj",
            "mtllib cube.mtl\n"
            "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n"
            "v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n"
            "usemtl red\n"
            "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
            "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n");
}

std::string visualUrdf() {
  return R"(<robot name='v'>
  <material name='blue'><color rgba='0 0 1 1'/></material>
  <link name='base'>
    <inertial><mass value='1'/><inertia ixx='0.1' iyy='0.1' izz='0.1' ixy='0' ixz='0' iyz='0'/></inertial>
    <visual name='red_box'>
      <origin xyz='0.1 0.2 0.3' rpy='0 0 1.5707963267948966'/>
      <geometry><box size='0.4 0.5 0.6'/></geometry>
      <material name='red'><color rgba='1 0 0 0.5'/></material>
    </visual>
    <visual name='ball'>
      <geometry><sphere radius='0.07'/></geometry>
      <material name='blue'/>
    </visual>
  </link>
  <link name='tip'>
    <visual name='pill'>
      <geometry><capsule radius='0.02' length='0.1'/></geometry>
    </visual>
    <visual name='cube'>
      <origin xyz='0 0 0.5'/>
      <geometry><mesh filename='cube.obj' scale='2 2 0.5'/></geometry>
    </visual>
    <visual name='tube'>
      <geometry><cylinder radius='0.03' length='0.2'/></geometry>
      <material name='blue'/>
    </visual>
  </link>
  <joint name='weld' type='fixed'>
    <parent link='base'/><child link='tip'/><origin xyz='0 0 1'/>
  </joint>
</robot>)";
}

TEST(UrdfVisualTest, PrimitivesMaterialsAndMeshesAreParsed) {
  const std::string dir = makeTempDir();
  writeCube(dir);
  Scene scene;
  Pose root;
  root.position = Eigen::Vector3d(3, 0, 0);
  const int a = scene.addUrdfString(visualUrdf(), dir, "v", root, true);
  const std::vector<VisualShape> &visuals = scene.getVisualShapes();
  ASSERT_EQ(visuals.size(), 5u);
  const int base = scene.findLink(a, "base"), tip = scene.findLink(a, "tip");

  const VisualShape &box = visuals[0];
  EXPECT_EQ(box.name, "red_box");
  EXPECT_EQ(box.link, base);
  EXPECT_EQ(box.kind, VisualShape::Kind::Box);
  EXPECT_TRUE(box.size.isApprox(Eigen::Vector3d(0.4, 0.5, 0.6)));
  EXPECT_TRUE(box.pose_in_link.position.isApprox(Eigen::Vector3d(0.1, 0.2, 0.3)));
  EXPECT_NEAR(box.pose_in_link.orientation.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()))),
              0, 1e-9);
  EXPECT_TRUE(box.has_material);
  EXPECT_EQ(box.material_name, "red");
  EXPECT_TRUE(box.color.isApprox(Eigen::Vector4f(1, 0, 0, 0.5f)));

  const VisualShape &ball = visuals[1];
  EXPECT_EQ(ball.kind, VisualShape::Kind::Sphere);
  EXPECT_DOUBLE_EQ(ball.size[0], 0.07);
  EXPECT_EQ(ball.material_name, "blue");  // robot-level, referenced by name
  EXPECT_TRUE(ball.color.isApprox(Eigen::Vector4f(0, 0, 1, 1)));

  // Under the fixed joint: own link id, pose relative to that link.
  const VisualShape &pill = visuals[2];
  EXPECT_EQ(pill.link, tip);
  EXPECT_EQ(pill.kind, VisualShape::Kind::Capsule);
  EXPECT_TRUE(pill.size.head<2>().isApprox(Eigen::Vector2d(0.02, 0.1)));
  EXPECT_FALSE(pill.has_material);

  const VisualShape &cube = visuals[3];
  EXPECT_EQ(cube.link, tip);
  EXPECT_EQ(cube.kind, VisualShape::Kind::Mesh);
  EXPECT_EQ(cube.mesh_file, dir + "/cube.obj");
  EXPECT_TRUE(cube.pose_in_link.position.isApprox(Eigen::Vector3d(0, 0, 0.5)));
  ASSERT_TRUE(cube.meshes);
  ASSERT_EQ(cube.meshes->size(), 1u);
  const VisualMesh &mesh = cube.meshes->front();
  EXPECT_EQ(mesh.indices.size(), 36u);
  EXPECT_TRUE(mesh.color.isApprox(Eigen::Vector4f(0.8f, 0.1f, 0.2f, 1)));
  EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
  Eigen::Vector3f lo = mesh.positions[0], hi = mesh.positions[0];
  for (const Eigen::Vector3f &p : mesh.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  EXPECT_TRUE((hi - lo).isApprox(Eigen::Vector3f(2, 2, 0.5f)));  // scale applied
  for (const Eigen::Vector3f &n : mesh.normals) EXPECT_NEAR(n.norm(), 1, 1e-5);

  const VisualShape &tube = visuals[4];
  EXPECT_EQ(tube.kind, VisualShape::Kind::Cylinder);
  EXPECT_TRUE(tube.size.head<2>().isApprox(Eigen::Vector2d(0.03, 0.2)));
  EXPECT_TRUE(tube.color.isApprox(Eigen::Vector4f(0, 0, 1, 1)));

  EXPECT_EQ(scene.calcVisualTriangleCount(), 12u);

  // The visual frame in the world: the tip link (1 m above the fixed root)
  // composed with the visual origin.
  scene.finalize();
  EXPECT_EQ(scene.getVisualShapes().size(), 5u);
  const Pose tip_pose = scene.getLinkPose(tip);
  EXPECT_TRUE((tip_pose.position + tip_pose.orientation * cube.pose_in_link.position)
                  .isApprox(Eigen::Vector3d(3, 0, 1.5)));
}

TEST(UrdfVisualTest, EachMeshFileIsLoadedOncePerScale) {
  const std::string dir = makeTempDir();
  writeCube(dir);
  const std::string urdf = R"(<robot name='m'><link name='a'>
    <visual><geometry><mesh filename='cube.obj'/></geometry></visual>
    <visual><geometry><mesh filename='cube.obj'/></geometry></visual>
    <visual><geometry><mesh filename='cube.obj' scale='2 2 2'/></geometry></visual>
    </link></robot>)";
  Scene scene;
  scene.addUrdfString(urdf, dir, "m1", Pose(), true);
  scene.addUrdfString(urdf, dir, "m2", Pose(), true);
  const std::vector<VisualShape> &v = scene.getVisualShapes();
  ASSERT_EQ(v.size(), 6u);
  EXPECT_EQ(v[0].meshes, v[1].meshes);
  EXPECT_EQ(v[0].meshes, v[3].meshes);
  EXPECT_NE(v[0].meshes, v[2].meshes);
  EXPECT_EQ(v[2].meshes, v[5].meshes);
  EXPECT_EQ(scene.calcVisualTriangleCount(), 72u);
}

TEST(UrdfVisualTest, MissingVisualMeshNamesUrdfLinkAndFile) {
  const std::string urdf = R"(<robot name='m'><link name='hand'>
    <visual name='shell'><geometry><mesh filename='nowhere.obj'/></geometry></visual>
    </link></robot>)";
  Scene scene;
  try {
    scene.addUrdfString(urdf, "/tmp", "m", Pose(), true);
    FAIL() << "no SceneError";
  } catch (const SceneError &e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("URDF <string>"), std::string::npos) << what;
    EXPECT_NE(what.find("link 'hand'"), std::string::npos) << what;
    EXPECT_NE(what.find("nowhere.obj"), std::string::npos) << what;
  }
  EXPECT_TRUE(scene.getVisualShapes().empty());
  EXPECT_EQ(scene.getArticulationCount(), 0);
}

TEST(UrdfVisualTest, RobotsHaveTheDocumentedTriangleCounts) {
  for (const auto &[file, visuals, triangles] :
       {std::tuple<std::string, std::size_t, std::size_t>{"mobile_panda_single.urdf", 19, 3112},
        {"mobile_panda_dual.urdf", 37, 6212}}) {
    Scene scene;
    scene.addUrdfFile(kRobotDir + "/" + file, "robot", Pose(), false);
    EXPECT_EQ(scene.getVisualShapes().size(), visuals) << file;
    EXPECT_EQ(scene.calcVisualTriangleCount(), triangles) << file;
    for (const VisualShape &v : scene.getVisualShapes()) {
      EXPECT_EQ(v.kind, VisualShape::Kind::Mesh) << file << " " << v.name;
      EXPECT_TRUE(v.has_material) << file << " " << v.name;
      EXPECT_GE(v.link, 0);
    }
  }
}

const char *kBlockInertial =
    "<inertial><mass value='1'/>"
    "<inertia ixx='0.01' iyy='0.01' izz='0.01' "
    "ixy='0' ixz='0' iyz='0'/></inertial>";

// A 1 kg block on a planar joint with a tilted normal (1, 1, 1) / sqrt(3).
std::string planarUrdf() {
  return std::string("<robot name='p'><link name='table'/>") +
         "<joint name='slide' type='planar'><parent link='table'/><child "
         "link='block'/>"
         "<origin xyz='0.5 0 1'/><axis xyz='1 1 1'/><dynamics "
         "damping='0'/></joint>"
         "<link name='block'>" +
         kBlockInertial + "</link></robot>";
}

TEST(UrdfJointTest, PlanarJointIsThreeJointsAndStaysInItsPlane) {
  for (const std::string integrator : {"implicit_euler", "cpodes", "semi_explicit_euler"}) {
    SCOPED_TRACE(integrator);
    PhysicsSettings settings;
    settings.gravity_z = 0;
    settings.integrator = parseIntegrator(integrator);
    // First-order fixed steps put positions h a t / 2 ahead under constant
    // acceleration (2 mm here at implicit_euler's default 2 ms; scene_test's
    // ImplicitEulerIsSemiImplicitEulerForSmoothForces): compare the joint
    // mapping at semi_explicit_euler's 0.5 ms.
    settings.implicit_step = 5e-4;
    Scene scene(settings);
    const int p = scene.addUrdfString(planarUrdf(), "", "p", Pose(), true);
    const std::vector<JointDescription> &joints = scene.getJoints(p);
    ASSERT_EQ(joints.size(), 3u);
    EXPECT_EQ(joints[0].name, "slide_x");
    EXPECT_EQ(joints[1].name, "slide_y");
    EXPECT_EQ(joints[2].name, "slide_yaw");
    EXPECT_EQ(joints[0].type, JointType::Prismatic);
    EXPECT_EQ(joints[1].type, JointType::Prismatic);
    EXPECT_EQ(joints[2].type, JointType::Continuous);
    scene.finalize();
    const int block = scene.findLink(p, "block");
    const Eigen::Vector3d origin(0.5, 0, 1), n = Eigen::Vector3d(1, 1, 1).normalized();
    EXPECT_TRUE(scene.getLinkPose(block).position.isApprox(origin));

    // Push: 2 N along x, 1 N along y, 0.01 N m about the normal, for 1 s.
    DriveCommand fx, fy, tz;
    fx.force = 2;
    fy.force = 1;
    tz.force = 0.01;
    scene.setDriveCommands(p, {0, 1, 2}, {fx, fy, tz});
    for (int tick = 0; tick < 50; ++tick) {
      scene.advance(0.02);
      const Pose pose = scene.getLinkPose(block);
      EXPECT_NEAR((pose.position - origin).dot(n), 0, 1e-9) << "tick " << tick;
      EXPECT_NEAR((pose.orientation * n - n).norm(), 0, 1e-9) << "tick " << tick;
    }
    const Eigen::VectorXd q = scene.getJointPositions(p);
    // Free of gravity and damping: q = F t^2 / (2 m), angle = tau t^2 / (2 I).
    EXPECT_NEAR(q[0], 1.0, 1e-3);
    EXPECT_NEAR(q[1], 0.5, 1e-3);
    EXPECT_NEAR(q[2], 0.5, 1e-3);
    const Eigen::Vector3d moved = scene.getLinkPose(block).position - origin;
    EXPECT_NEAR(moved.norm(), std::sqrt(1.25), 1e-3);
    // The in-plane directions are orthonormal: q_x and q_y are the
    // displacement's components along them.
    EXPECT_NEAR(moved.dot(n), 0, 1e-9);
  }
}

TEST(UrdfJointTest, PlanarJointAboutZUsesXAndYDirections) {
  PhysicsSettings settings;
  settings.gravity_z = 0;
  Scene scene(settings);
  const std::string urdf = std::string("<robot name='p'><link name='table'/>") +
                           "<joint name='base' type='planar'><parent link='table'/>"
                           "<child link='block'/><axis xyz='0 0 1'/></joint>"
                           "<link name='block'>" +
                           kBlockInertial + "</link></robot>";
  const int p = scene.addUrdfString(urdf, "", "p", Pose(), true);
  scene.finalize();
  Eigen::VectorXd q(3);
  q << 0.3, -0.2, 0.4;
  scene.setJointPositions(p, q);
  const Pose pose = scene.getLinkPose(scene.findLink(p, "block"));
  EXPECT_TRUE(pose.position.isApprox(Eigen::Vector3d(0.3, -0.2, 0)));
  EXPECT_NEAR(pose.orientation.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()))),
              0, 1e-12);
}

// Two spinning disks about z; `follower` mimics `leader` (declared after it
// in the file, to exercise forward references).
std::string mimicUrdf(double multiplier, double offset) {
  std::ostringstream s;
  s << "<robot name='m'><link name='base'/>"
    << "<joint name='follower' type='revolute'><parent link='base'/><child "
       "link='b'/>"
    << "<origin xyz='0.5 0 0'/><axis xyz='0 0 1'/>"
    << "<limit lower='-3' upper='3' effort='0' velocity='10'/>"
    << "<mimic joint='leader' multiplier='" << multiplier << "' offset='" << offset << "'/>"
    << "</joint><link name='b'>" << kBlockInertial << "</link>"
    << "<joint name='leader' type='revolute'><parent link='base'/><child "
       "link='a'/>"
    << "<axis xyz='0 0 1'/><limit lower='-3' upper='3' effort='0' "
       "velocity='10'/></joint>"
    << "<link name='a'>" << kBlockInertial << "</link></robot>";
  return s.str();
}

TEST(UrdfJointTest, MimicJointFollowsItsLeader) {
  for (const std::string integrator : {"implicit_euler", "cpodes", "semi_explicit_euler", "rk_merson"}) {
    PhysicsSettings settings;
    settings.integrator = parseIntegrator(integrator);
    Scene scene(settings);
    const int m = scene.addUrdfString(mimicUrdf(-0.5, 0.1), "", "m", Pose(), true);
    const std::vector<JointDescription> &joints = scene.getJoints(m);
    ASSERT_EQ(joints.size(), 2u);
    EXPECT_EQ(joints[0].name, "follower");
    EXPECT_EQ(joints[0].mimic, 1);
    EXPECT_DOUBLE_EQ(joints[0].mimic_multiplier, -0.5);
    EXPECT_DOUBLE_EQ(joints[0].mimic_offset, 0.1);
    EXPECT_EQ(joints[1].mimic, -1);
    scene.finalize();
    EXPECT_NEAR(scene.getJointPositions(m)[0], 0.1, 1e-12) << integrator;

    DriveCommand hold;
    hold.position_target = 1.0;
    hold.stiffness = 5;
    hold.damping = 1;
    scene.setDriveCommands(m, {1}, {hold});
    for (int tick = 0; tick < 100; ++tick) {
      scene.advance(0.02);
      const Eigen::VectorXd q = scene.getJointPositions(m);
      EXPECT_NEAR(q[0], -0.5 * q[1] + 0.1, 1e-6) << integrator << " tick " << tick;
    }
    const Eigen::VectorXd q = scene.getJointPositions(m);
    EXPECT_NEAR(q[1], 1.0, 1e-2) << integrator;
    EXPECT_NEAR(q[0], -0.4, 1e-2) << integrator;
    const Eigen::VectorXd qdot = scene.getJointVelocities(m);
    EXPECT_NEAR(qdot[0], -0.5 * qdot[1], 1e-6) << integrator;

    // Setting the leader moves the follower with it.
    Eigen::VectorXd set(2);
    set << 0, -1;
    scene.setJointPositions(m, set);
    EXPECT_NEAR(scene.getJointPositions(m)[0], 0.6, 1e-12) << integrator;
  }
}

TEST(UrdfJointTest, MimicOfAnUnknownJointIsAnError) {
  Scene scene;
  std::string urdf = mimicUrdf(1, 0);
  urdf.replace(urdf.find("mimic joint='leader'"), 20, "mimic joint='ghost'");
  try {
    scene.addUrdfString(urdf, "", "m", Pose(), true);
    FAIL() << "no SceneError";
  } catch (const SceneError &e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("joint 'follower' mimics joint 'ghost', which does not exist"),
              std::string::npos)
        << what;
  }
}

}  // namespace
}  // namespace manibench
