// URDF files as users meet them: graphs that are not trees, numbers that
// are not finite, files that are not XML, <limit> without effort or
// velocity, PyBullet-style package:// paths. Each loads and is sane, or is
// refused naming the file, the element and the reason; none crashes.
#include <manibench/scene.hpp>
#include <manibench/scene_bridge.hpp>
#include <manibench/sdk/scene_view.hpp>

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "test_support.hpp"

namespace manibench {
namespace {

using testing::catchMessage;
using testing::expectMentions;

std::string robot(const std::string& body) { return "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n" + body + "</robot>\n"; }

std::string link(const std::string& name, const std::string& inner = "") {
  return "  <link name=\"" + name + "\">" + inner + "</link>\n";
}
std::string inertial(const std::string& ixx = "1e-3") {
  return "<inertial><mass value=\"1\"/><inertia ixx=\"" + ixx +
         "\" ixy=\"0\" ixz=\"0\" iyy=\"1e-3\" iyz=\"0\" izz=\"1e-3\"/></inertial>";
}
std::string joint(const std::string& name, const std::string& parent, const std::string& child,
                  const std::string& limit = "<limit lower=\"-1\" upper=\"1\" effort=\"10\" velocity=\"1\"/>") {
  return "  <joint name=\"" + name + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" + child +
         "\"/><axis xyz=\"0 0 1\"/>" + limit + "</joint>\n";
}

std::string loadError(const std::string& urdf) {
  return catchMessage<SceneError>([&] {
    Scene scene;
    scene.addUrdfString(urdf, "", "robot", Pose(), true);
    scene.finalize();
  });
}

TEST(UrdfRobustness, GraphsThatAreNotTreesAreRefusedNamingTheJoints) {
  // A cycle below a valid root: b -> c -> b, root a.
  expectMentions(loadError(robot(link("a", inertial()) + link("b", inertial()) + link("c", inertial()) +
                                 joint("ab", "a", "b") + joint("bc", "b", "c") + joint("cb", "c", "b"))),
                 {"link 'b' has two parent joints", "'ab'", "'cb'"});
  expectMentions(loadError(robot(link("a", inertial()) + link("b", inertial()) + link("c", inertial()) +
                                 joint("bc", "b", "c") + joint("cb", "c", "b"))),
                 {"form a cycle", "'bc'", "'cb'"});
  expectMentions(loadError(robot(link("a", inertial()) + link("b", inertial()) + joint("ab", "a", "b") +
                                 joint("bb", "b", "b"))),
                 {"joint 'bb' connects link 'b' to itself", "line"});
}

TEST(UrdfRobustness, NumbersThatAreNotFiniteAreRefusedNamingTheElement) {
  const std::string box = "<geometry><box size=\"0.1 0.1 0.1\"/></geometry>";
  expectMentions(loadError(robot(link("a", inertial() + "<visual><origin xyz=\"0 nan 0\"/>" + box + "</visual>"))),
                 {"<origin> of <visual> of <link> 'a'", "xyz", "not a finite number", "line"});
  expectMentions(loadError(robot(link("a", inertial() + "<collision><origin rpy=\"inf 0 0\"/>" + box + "</collision>"))),
                 {"<origin> of <collision> of <link> 'a'", "rpy"});
  expectMentions(loadError(robot(link("a", inertial("nan")))), {"<inertia>", "'a'", "ixx"});
}

TEST(UrdfRobustness, FilesThatAreNotUrdfSayWhatTheyAre) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("manibench_urdf_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string random = (dir / "random.urdf").string();
  {
    std::ofstream out(random, std::ios::binary);
    uint64_t x = 88172645463325252ull;
    for (int i = 0; i < 100000; ++i) {
      x ^= x << 13, x ^= x >> 7, x ^= x << 17;
      out.put(char(x & 0xff));
    }
  }
  auto load = [](const std::string& path) {
    return catchMessage<SceneError>([&] {
      Scene scene;
      scene.addUrdfFile(path, "robot", Pose(), true);
    });
  };
  expectMentions(load(random), {random, "not an XML file"});
  expectMentions(load(dir.string()), {dir.string(), "is a directory"});
  std::filesystem::remove_all(dir);
}

TEST(UrdfRobustness, LimitsWithoutEffortOrVelocityLoadUnlimited) {
  Scene scene;
  const int r = scene.addUrdfString(robot(link("a", inertial()) + link("b", inertial()) +
                                          joint("ab", "a", "b", "<limit lower=\"-0.5\" upper=\"0.5\"/>")),
                                    "", "robot", Pose(), true);
  scene.finalize();
  ASSERT_EQ(scene.getJoints(r).size(), 1u);
  const JointDescription& j = scene.getJoints(r)[0];
  EXPECT_EQ(j.effort_limit, 0.0);  // not limited
  EXPECT_EQ(j.lower, -0.5);        // the position limits apply
  EXPECT_EQ(j.upper, 0.5);
}

TEST(UrdfRobustness, PyBulletStylePackagePathsAndMissingMeshesListTheCandidates) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("manibench_pybullet_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes" / "cube.obj") << "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nv 0.1 0.1 0\n"
                                                "v 0.1 0 0.1\nv 0 0.1 0.1\nv 0.1 0.1 0.1\n"
                                                "f 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 5 6\nf 3 5 7\nf 4 6 7\nf 5 6 8\nf 6 7 8\n";
  auto write = [&](const std::string& file, const std::string& mesh) {
    std::ofstream(dir / file) << robot(link("a", inertial() + "<collision><geometry><mesh filename=\"" + mesh +
                                                   "\"/></geometry></collision>"));
    return (dir / file).string();
  };
  {
    Scene scene;
    const int r = scene.addUrdfFile(write("ok.urdf", "package://meshes/cube.obj"), "robot", Pose(), true);
    scene.finalize();
    EXPECT_GE(r, 0);
  }
  const std::string missing = write("missing.urdf", "package://meshes/sphere.obj");
  const std::string message = catchMessage<SceneError>([&] {
    Scene scene;
    scene.addUrdfFile(missing, "robot", Pose(), true);
  });
  expectMentions(message, {missing, "link 'a'", "sphere.obj' not found; tried", (dir / "meshes" / "sphere.obj").string(),
                           (dir / "sphere.obj").string()});
  std::filesystem::remove_all(dir);
}

// physics.default_joint_damping: joints without <dynamics> get it, the
// others keep theirs.
TEST(UrdfRobustness, JointsWithoutDynamicsGetTheDefaultDamping) {
  PhysicsSettings settings;
  settings.default_joint_damping = 2.5;
  Scene scene(settings);
  const std::string damped = "<dynamics damping=\"0.5\"/></joint>";
  std::string with_dynamics = joint("bc", "b", "c");
  with_dynamics.replace(with_dynamics.find("</joint>"), 8, damped);
  const int r = scene.addUrdfString(robot(link("a", inertial()) + link("b", inertial()) + link("c", inertial()) +
                                          joint("ab", "a", "b") + with_dynamics),
                                    "", "robot", Pose(), true);
  scene.finalize();
  ASSERT_EQ(scene.getJoints(r).size(), 2u);
  EXPECT_EQ(scene.getJoints(r)[0].damping, 2.5);
  EXPECT_EQ(scene.getJoints(r)[1].damping, 0.5);
}

// A rigid object (no movable joint) through the plugin's view: empty joint
// vectors, not an "output array is null" error.
TEST(UrdfRobustness, ARigidObjectHasEmptyJointVectorsInThePluginsView) {
  Scene scene;
  const int box = scene.addUrdfString(robot(link("a", inertial())), "", "box", Pose(), false);
  scene.finalize();
  SceneBridge bridge(scene);
  const sdk::SceneView view(SceneBridge::getApi(), bridge.getHandle());
  EXPECT_EQ(view.getJointPositions(box).size(), 0);
  EXPECT_EQ(view.getJointVelocities(box).size(), 0);
}

// ABI 1.3: the root link and a floating root's twist through the plugin's
// view, without the URDF's link names.
TEST(UrdfRobustness, ThePluginsViewGivesTheRootLinkAndSetsTheRootTwist) {
  PhysicsSettings settings;
  settings.gravity_z = 0;
  Scene scene(settings);
  const int fixed = scene.addUrdfString(robot(link("a", inertial()) + link("b", inertial()) + joint("ab", "a", "b")),
                                        "", "arm", Pose(), true);
  std::string floating_urdf = robot(link("hull", inertial()) + link("mast", inertial()) + joint("hm", "hull", "mast"));
  const int boat = scene.addUrdfString(floating_urdf, "", "boat", Pose(), false);
  scene.finalize();
  SceneBridge bridge(scene);
  sdk::SceneView view(SceneBridge::getApi(), bridge.getHandle());
  EXPECT_EQ(scene.getLinkName(int(view.getRootLink(fixed))), "a");
  const mb_id hull = view.getRootLink(boat);
  EXPECT_EQ(hull, scene.findLink(boat, "hull"));
  sdk::Twist twist;
  twist.angular = Eigen::Vector3d(0, 0, 0.5);
  twist.linear = Eigen::Vector3d(1.0, -2.0, 0.25);
  bridge.setStateChangesAllowed(true);  // as in a task's reset
  view.setRootTwist(boat, twist);
  const sdk::Twist back = view.getRootTwist(boat);
  EXPECT_TRUE(back.angular.isApprox(twist.angular, 1e-12)) << back.angular.transpose();
  EXPECT_TRUE(back.linear.isApprox(twist.linear, 1e-12)) << back.linear.transpose();
  scene.advance(0.1);  // no gravity, no contact: it coasts
  EXPECT_NEAR(view.getRootPose(boat).position.x(), 0.1, 1e-6);
  EXPECT_NEAR(view.getRootPose(boat).position.y(), -0.2, 1e-6);
  // A fixed base has no twist to set; a non-finite one is refused.
  EXPECT_THROW(view.setRootTwist(fixed, twist), sdk::Error);
  twist.linear.x() = std::nan("");
  expectMentions(catchMessage<sdk::Error>([&] { view.setRootTwist(boat, twist); }), {"'boat'", "not finite"});
}

// A free body with no collision shape falls through the ground: the scene
// says so, naming the link, instead of letting it fall for ever.
// A camera as a widely used quadruped's URDF writes it: principal moments
// that violate the triangle inequality (8.7e-6 + 6.7e-4 < 1.4e-3), welded
// to its parent by a fixed joint. Only the merged body's inertia means
// anything, and it is valid: the file loads. The same camera on a joint of
// its own is a body with that inertia: refused, naming the link.
TEST(UrdfRobustness, AWeldedLinkCountsOnlyMergedIntoItsBody) {
  const std::string camera =
      link("camera", "<inertial><mass value=\"0.05\"/><inertia ixx=\"8.7e-6\" ixy=\"0\" ixz=\"0\" "
                     "iyy=\"6.7e-4\" iyz=\"0\" izz=\"1.4e-3\"/></inertial>");
  const std::string welded = "  <joint name=\"mount\" type=\"fixed\"><parent link=\"base\"/><child link=\"camera\"/>"
                             "<origin xyz=\"0.1 0 0\"/></joint>\n";
  Scene scene;
  const int r = scene.addUrdfString(robot(link("base", inertial()) + camera + welded), "", "robot", Pose(), false);
  scene.finalize();
  EXPECT_EQ(scene.getJoints(r).size(), 0u);
  expectMentions(loadError(robot(link("base", inertial()) + camera + joint("mount", "base", "camera"))),
                 {"link 'camera' has an invalid inertia (ixx 8.7e-06", "triangle inequality"});
}

// A link that moves but has no mass (no <inertial>, no collision geometry,
// nothing welded to it, nothing below it) loaded and fell through the
// ground at t = 1.46 s; it is refused at load, naming the link and its joint.
TEST(UrdfRobustness, AMovingLinkWithoutMassIsRefusedNamingIt) {
  expectMentions(loadError(robot(link("a", inertial()) + link("b") + joint("ab", "a", "b"))),
                 {"link 'b' moves (joint 'ab') but neither it nor anything below it has mass"});
  // A massless chain ending without mass is refused at its first link.
  expectMentions(loadError(robot(link("a", inertial()) + link("b") + link("c") + joint("ab", "a", "b") +
                                 joint("bc", "b", "c"))),
                 {"link 'b' moves (joint 'ab') but neither"});
  // Massless but welded to a link with mass: fine.
  Scene scene;
  const std::string weld = "  <joint name=\"w\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>\n";
  scene.addUrdfString(robot(link("a", inertial()) + link("b") + link("c", inertial()) + joint("ab", "a", "b") + weld),
                      "", "robot", Pose(), true);
  scene.finalize();
}

// PartNet writes a massless link_N_helper between the two joints of a
// slider+ part (a seat that slides up and down and turns): the helper's
// slider carries the seat's mass. It loads, and under gravity the seat
// slides down its vertical slider to the stop, turning freely about it.
TEST(UrdfRobustness, AMasslessLinkWithMassBelowItLoadsAndMoves) {
  const std::string slider =
      "  <joint name=\"slide\" type=\"prismatic\"><parent link=\"base\"/><child link=\"helper\"/>"
      "<axis xyz=\"0 0 1\"/><limit lower=\"-0.1\" upper=\"0.1\"/></joint>\n";
  const std::string urdf = robot(link("base", inertial()) + link("helper") + link("seat", inertial()) + slider +
                                 joint("turn", "helper", "seat"));
  Scene scene;
  const int r = scene.addUrdfString(urdf, "", "chair", Pose(), true);
  scene.finalize();
  ASSERT_EQ(scene.getJoints(r).size(), 2u);
  for (int i = 0; i < 100; ++i) scene.advance(0.01);
  const Eigen::VectorXd q = scene.getJointPositions(r);
  EXPECT_NEAR(q[0], -0.1, 0.01);  // at the lower stop
  EXPECT_TRUE(q.allFinite());
}

TEST(UrdfRobustness, ABodyFallingThroughTheGroundIsADivergenceNamingIt) {
  Scene scene;
  scene.addGround(0);
  Pose above;
  above.position.z() = 0.5;
  scene.addUrdfString(robot(link("ghost", inertial())), "", "ghost", above, false);
  scene.finalize();
  const std::string message = catchMessage<SimulationDiverged>([&] {
    for (int i = 0; i < 400; ++i) scene.advance(0.01);
  });
  expectMentions(message, {"link 'ghost'", "fell through the ground"});
}

// A light dexterous hand as published descriptions write it: 24 revolute
// joints, no <inertial> (masses from 3 g collision boxes) and no
// <dynamics>. Thrown into its joint limits at 5 rad/s under gravity, it
// stays within its limits and the integrator's work per step stays that
// of a smooth motion (before: CPODES gave up after 40 s at step 133).
TEST(UrdfRobustness, ALightHandWithoutDynamicsStaysWithinItsLimits) {
  const std::string box =
      "<collision><origin xyz=\"0 0 0.015\"/><geometry><box size=\"0.01 0.01 0.03\"/></geometry></collision>";
  std::string body = link("palm", "<collision><geometry><box size=\"0.08 0.08 0.02\"/></geometry></collision>");
  int joints = 0;
  for (int finger = 0; finger < 6; ++finger) {
    std::string parent = "palm";
    for (int segment = 0; segment < 4; ++segment) {
      const std::string name = "f" + std::to_string(finger) + "_" + std::to_string(segment);
      const std::string origin = segment == 0 ? "<origin xyz=\"" + std::to_string(-0.03 + 0.012 * finger) + " 0 0.01\"/>"
                                              : "<origin xyz=\"0 0 0.03\"/>";
      const std::string axis = segment == 0 ? "1 0 0" : "0 1 0";
      body += link(name, box);
      body += "  <joint name=\"" + name + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" +
              name + "\"/>" + origin + "<axis xyz=\"" + axis +
              "\"/><limit lower=\"-0.3\" upper=\"1.5\" effort=\"1\" velocity=\"2\"/></joint>\n";
      parent = name;
      ++joints;
    }
  }
  ASSERT_EQ(joints, 24);
  Scene scene;
  const int hand = scene.addUrdfString(robot(body), "", "hand", Pose(), true);
  scene.finalize();
  ASSERT_EQ(scene.getJoints(hand).size(), 24u);
  Eigen::VectorXd qdot(24);
  for (int j = 0; j < 24; ++j) qdot[j] = j % 2 == 0 ? 5.0 : -5.0;
  scene.setJointVelocities(hand, qdot);
  const IntegratorStatistics before = scene.getIntegratorStatistics();
  const int steps = 200;  // 2 s of 10 ms env steps
  for (int i = 0; i < steps; ++i) ASSERT_NO_THROW(scene.advance(0.01)) << "at step " << i;
  const IntegratorStatistics after = scene.getIntegratorStatistics();
  const Eigen::VectorXd q = scene.getJointPositions(hand);
  ASSERT_TRUE(q.allFinite());
  for (int j = 0; j < 24; ++j) {
    EXPECT_GE(q[j], -0.3 - 0.05) << scene.getJoints(hand)[std::size_t(j)].name;
    EXPECT_LE(q[j], 1.5 + 0.05) << scene.getJoints(hand)[std::size_t(j)].name;
  }
  EXPECT_LT(scene.getJointVelocities(hand).cwiseAbs().maxCoeff(), 5.0) << "the stops took energy out";
  const double realizations_per_step = double(after.realizations - before.realizations) / steps;
  EXPECT_LT(realizations_per_step, 20) << "the integrator struggles: " << realizations_per_step
                                       << " evaluations of the dynamics per 10 ms";
}

// An integrator that gives up on a finite state: an explicit one (RK-Merson)
// on a 0.1 mg link whose joint damping (1 N m s/rad) makes a time constant
// of 1e-10 s while gravity keeps it moving. The divergence names the link
// with the largest acceleration.
TEST(UrdfRobustness, AnIntegratorThatGivesUpNamesTheLinkWithTheLargestAcceleration) {
  PhysicsSettings settings;
  settings.integrator = Integrator::RkMerson;
  settings.default_joint_damping = 1;
  Scene scene(settings);
  const std::string tiny =
      "<inertial><origin xyz=\"0.01 0 0\"/><mass value=\"1e-7\"/><inertia ixx=\"1e-10\" ixy=\"0\" ixz=\"0\" "
      "iyy=\"1e-10\" iyz=\"0\" izz=\"1e-10\"/></inertial>";
  std::string hinge = joint("hop", "base", "flea", "<limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/>");
  hinge.replace(hinge.find("0 0 1"), 5, "0 1 0");
  scene.addUrdfString(robot(link("base", inertial()) + link("flea", tiny) + hinge), "", "robot", Pose(), true);
  scene.finalize();
  const std::string message = catchMessage<SimulationDiverged>([&] {
    for (int i = 0; i < 100; ++i) scene.advance(0.01);
  });
  expectMentions(message, {"flea", "the largest acceleration"});
}

}  // namespace
}  // namespace manibench
