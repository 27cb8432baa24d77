// Contact against real Simbody: every supported shape pair carries a 1 kg
// body at rest, friction holds and slides on a slope as Coulomb says,
// filtering, stacks, materials, and bit-identical replays of a
// contact-rich scene. Meshes and capsules: contact_mesh_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <manibench/scene.hpp>
#include <string>
#include <vector>

#include "contact_scenes.hpp"

namespace manibench {
namespace {

using namespace contact_scenes;

// --- the contact-pair matrix ---------------------------------------------------------

// A 1 kg body that can rest on a flat top: its collision XML and the height
// of its origin above the top it rests on.
struct Rester {
  std::string name;
  std::string collision;
  double rest_height;
};

std::vector<Rester> getResters() {
  const Eigen::Vector3d along_x(0, kPi / 2, 0);  // turns a z-axis shape to lie along x
  return {
      {"sphere", collision(sphere(0.05)), 0.05},
      {"box", collision(box(0.1, 0.1, 0.1)), 0.05},
      {"capsule_lying", collision(capsule(0.025, 0.1), Eigen::Vector3d::Zero(), along_x), 0.025},
      {"cylinder_upright", collision(cylinder(0.04, 0.1)), 0.05},
      {"cylinder_lying", collision(cylinder(0.04, 0.1), Eigen::Vector3d::Zero(), along_x), 0.04},
      {"mesh_prism", collision(mesh(writePrismObj("hexagon", 6, 0.05, 0.08))), 0.04},
      {"mesh_frustum", collision(mesh(writeFrustumStl("frustum", 0.1, 0.06, 0.08))), 0.04},
  };
}

// What a body rests on; its top is at z = 0 (x, y near 0).
struct Support {
  std::string name;
  std::string collision;             // "" for the ground plane
  std::vector<std::string> resters;  // which resters fit on it
};

std::vector<Support> getSupports() {
  const Eigen::Vector3d along_x(0, kPi / 2, 0);
  const std::vector<std::string> all = {
      "sphere",         "box",        "capsule_lying", "cylinder_upright",
      "cylinder_lying", "mesh_prism", "mesh_frustum"};
  return {
      {"floor", "", all},
      {"table", collision(box(0.4, 0.4, 0.1), Eigen::Vector3d(0, 0, -0.05)), all},
      {"fixed_cylinder",
       collision(cylinder(0.08, 0.1), Eigen::Vector3d(0, 0, -0.05)),
       {"sphere", "box", "capsule_lying", "cylinder_upright", "cylinder_lying", "mesh_prism"}},
      {"fixed_mesh",
       collision(mesh(writePrismObj("big_hexagon", 6, 0.15, 0.1)), Eigen::Vector3d(0, 0, -0.05)),
       all},
      // Two parallel rails along x; what rests on them spans both.
      {"capsule_rails",
       collision(capsule(0.02, 0.3), Eigen::Vector3d(0, 0.03, -0.02), along_x) +
           collision(capsule(0.02, 0.3), Eigen::Vector3d(0, -0.03, -0.02), along_x),
       {"box", "mesh_prism"}},
  };
}

struct RestResult {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // on the body from the support
  double drift = 0;                                 // origin movement between t = 0.5 s and t = 1 s
  double turn = 0;                                  // rotation over the same time, rad
  double height = 0;                                // origin height at t = 1 s
};

RestResult simulateRest(const Support& support, const Rester& rester,
                        const std::string& integrator) {
  PhysicsSettings settings;
  settings.integrator = parseIntegrator(integrator);
  Scene scene(settings);
  int support_link = -1;
  int support_art = -1;
  if (support.collision.empty())
    scene.addGround(0);
  else
    support_art =
        scene.addUrdfString(singleLink("support", support.collision), "", "support", Pose(), true);
  // Resting on its own contact springs from 0.5 mm above.
  const int body = scene.addUrdfString(singleLink("body", inertial() + rester.collision), "",
                                       "body", at(0.002, -0.001, rester.rest_height + 5e-4), false);
  scene.finalize();
  if (support_art >= 0) support_link = scene.findLink(support_art, "support");
  const int link = scene.findLink(body, "body");
  Pose half_way;
  for (int k = 0; k < 100; ++k) {
    scene.advance(0.01);
    if (k == 49) half_way = scene.getRootPose(body);
  }
  RestResult r;
  const Pose end = scene.getRootPose(body);
  r.force = scene.calcContactForce(link, support_link);
  r.drift = (end.position - half_way.position).norm();
  r.turn = end.orientation.angularDistance(half_way.orientation);
  r.height = end.position.z();
  return r;
}

class ContactMatrixTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ContactMatrixTest, EveryPairCarriesARestingBody) {
  const std::string integrator = GetParam();
  int pairs = 0;
  for (const Support& support : getSupports()) {
    for (const Rester& rester : getResters()) {
      if (std::find(support.resters.begin(), support.resters.end(), rester.name) ==
          support.resters.end())
        continue;
      ++pairs;
      SCOPED_TRACE(rester.name + " on " + support.name + " (" + integrator + ")");
      const RestResult r = simulateRest(support, rester, integrator);
      std::printf(
          "%-17s on %-15s Fz %.4f N  |Fxy| %.1e N  drift %.1e m  turn %.1e rad  sink %+.2e m\n",
          rester.name.c_str(), support.name.c_str(), r.force.z(), r.force.head<2>().norm(), r.drift,
          r.turn, r.height - rester.rest_height);
      EXPECT_NEAR(r.force.z(), kG, 0.02 * kG);
      EXPECT_LT(r.force.head<2>().norm(), 0.02 * kG);
      EXPECT_LT(r.drift, 1e-4);
      EXPECT_LT(r.turn, 1e-3);
      // Penetration of the contact springs, well under a millimetre.
      EXPECT_NEAR(r.height, rester.rest_height, 1e-3);
    }
  }
  EXPECT_EQ(pairs, 29);
}

INSTANTIATE_TEST_SUITE_P(Integrators, ContactMatrixTest,
                         ::testing::Values("implicit_euler", "cpodes", "semi_explicit_euler"));

// --- friction ----------------------------------------------------------------------

// A 1 kg, 10 cm box on a 20 degree slope (a fixed 3 m board), both with
// friction mu (static = dynamic). Returns the box's velocity along the
// slope (downhill positive) at 0.5 s and 1.0 s after release.
struct SlopeRun {
  double v_early = 0, v_late = 0, t_early = 0, t_late = 0;
  double creep = 0;  // mean downhill speed between the two
};

// `drop`: how far above its resting height the box starts (its contact
// then begins after the integrator has started).
SlopeRun runSlope(double mu, const std::string& integrator, double drop = 0) {
  const double theta = 20 * kPi / 180;
  PhysicsSettings settings;
  settings.integrator = parseIntegrator(integrator);
  Scene scene(settings);
  ContactMaterial material;
  material.static_friction = material.dynamic_friction = mu;
  // The board's top face passes through the origin, rising towards +y.
  const Eigen::Vector3d rpy(theta, 0, 0);
  const int board = scene.addUrdfString(
      singleLink("board", collision(box(0.5, 3, 0.1), Eigen::Vector3d(0, 0, -0.05))), "", "board",
      at(0, 0, 0, rpy), true);
  const Eigen::Matrix3d R = at(0, 0, 0, rpy).orientation.toRotationMatrix();
  const Eigen::Vector3d normal = R.col(2), downhill = R * Eigen::Vector3d(0, -1, 0);
  // High up the board, 25 um into it (about its resting penetration).
  const Eigen::Vector3d start = R * Eigen::Vector3d(0, 1.0, 0.05 - 2.5e-5 + drop);
  const int body =
      scene.addUrdfString(singleLink("box", inertial() + collision(box(0.1, 0.1, 0.1))), "", "box",
                          at(start.x(), start.y(), start.z(), rpy), false);
  scene.setContactMaterial(board, "", material);
  scene.setContactMaterial(body, "box", material);
  scene.finalize();
  const int link = scene.findLink(body, "box");
  SlopeRun run;
  Eigen::Vector3d x_early = Eigen::Vector3d::Zero();
  for (int k = 1; k <= 100; ++k) {
    scene.advance(0.01);
    if (k == 50) {
      run.t_early = scene.getTime();
      run.v_early = scene.getLinkTwist(link).linear.dot(downhill);
      x_early = scene.getRootPose(body).position;
    }
  }
  run.t_late = scene.getTime();
  run.v_late = scene.getLinkTwist(link).linear.dot(downhill);
  run.creep =
      (scene.getRootPose(body).position - x_early).dot(downhill) / (run.t_late - run.t_early);
  // It stays on the board's surface either way.
  EXPECT_NEAR((scene.getRootPose(body).position).dot(normal), 0.05, 1e-3);
  return run;
}

class FrictionTest : public ::testing::TestWithParam<std::string> {};

TEST_P(FrictionTest, BoxHoldsOnA20DegreeSlopeAtMu08) {
  const SlopeRun run = runSlope(0.8, GetParam());
  std::printf("mu 0.8 (%s): creep %.3e m/s, v(1 s) %.3e m/s\n", GetParam().c_str(), run.creep,
              run.v_late);
  EXPECT_LT(std::abs(run.creep), 1e-3);
  EXPECT_LT(std::abs(run.v_late), 1e-3);
}

// Stiction needs friction anchors made while the simulation runs, not only
// those of the initial state.
TEST_P(FrictionTest, ABoxDroppedOnTheSlopeHoldsToo) {
  const SlopeRun run = runSlope(0.8, GetParam(), 0.02);
  std::printf("mu 0.8, dropped 2 cm (%s): creep %.3e m/s, v(1 s) %.3e m/s\n",
              GetParam().c_str(), run.creep, run.v_late);
  EXPECT_LT(std::abs(run.creep), 1e-3);
  EXPECT_LT(std::abs(run.v_late), 1e-3);
}

TEST_P(FrictionTest, BoxSlidesAtMu02WithTheCoulombAcceleration) {
  const double theta = 20 * kPi / 180;
  const double expected = kG * (std::sin(theta) - 0.2 * std::cos(theta));  // 1.5115 m/s^2
  const SlopeRun run = runSlope(0.2, GetParam());
  const double a = (run.v_late - run.v_early) / (run.t_late - run.t_early);
  std::printf("mu 0.2 (%s): a %.4f m/s^2, analytic %.4f (%+.2f%%)\n", GetParam().c_str(), a,
              expected, 100 * (a - expected) / expected);
  EXPECT_NEAR(a, expected, 0.05 * expected);
}

INSTANTIATE_TEST_SUITE_P(Integrators, FrictionTest,
                         ::testing::Values("implicit_euler", "cpodes", "semi_explicit_euler"));

TEST_P(FrictionTest, ASlidingBallStartsRollingAtFiveSeventhsOfItsSpeed) {
  // Solid ball, no spin, 1 m/s: friction slows it to 5/7 m/s, then it rolls
  // (v = w r) without slipping.
  const double r = 0.05;
  PhysicsSettings settings;
  settings.integrator = parseIntegrator(GetParam());
  Scene scene(settings);
  scene.addGround(0);
  const int ball =
      scene.addUrdfString(singleLink("ball", inertial(1, 0.4 * r * r) + collision(sphere(r))), "",
                          "ball", at(0, 0, r - 1e-4), false);
  scene.finalize();
  Twist twist;
  twist.linear = Eigen::Vector3d(1, 0, 0);
  scene.setRootTwist(ball, twist);
  for (int k = 0; k < 100; ++k) scene.advance(0.01);
  const Twist end = scene.getLinkTwist(scene.findLink(ball, "ball"));
  std::printf("rolling ball (%s): v %.4f m/s (5/7 = %.4f), w r %.4f\n", GetParam().c_str(),
              end.linear.x(), 5.0 / 7.0, end.angular.y() * r);
  EXPECT_NEAR(end.linear.x(), 5.0 / 7.0, 0.01 * 5.0 / 7.0);
  EXPECT_NEAR(end.angular.y() * r, end.linear.x(), 0.01 * 5.0 / 7.0);
  EXPECT_THROW(scene.setRootTwist(7, twist), SceneError);
}

TEST_P(FrictionTest, LightObjectsComeToRestToo) {
  // 1 g to 27 g cubes: faster contact oscillations than a 5e-4 s step or
  // CPodes' 1 mm absolute tolerance follow at the material stiffness; the
  // contact frequency limit for light free bodies keeps them down.
  for (double size : {0.01, 0.02, 0.03}) {
    PhysicsSettings settings;
    settings.integrator = parseIntegrator(GetParam());
    Scene scene(settings);
    scene.addGround(0);
    const int cube = scene.addUrdfString(singleLink("cube", collision(box(size, size, size))), "",
                                         "cube", at(0, 0, size / 2 + 1e-3), false);
    scene.finalize();
    for (int k = 0; k < 100; ++k) scene.advance(0.01);
    const double weight = 1000 * size * size * size * kG;
    SCOPED_TRACE("cube of " + num(size) + " m");
    EXPECT_NEAR(scene.getRootPose(cube).position.z(), size / 2, 1e-5);
    EXPECT_NEAR(scene.calcContactForce(scene.findLink(cube, "cube"), -1).z(), weight, 0.02 * weight);
    EXPECT_LT(scene.getLinkTwist(scene.findLink(cube, "cube")).linear.norm(), 1e-4);
  }
}

// A caster's wheel: 20 g, 7.2e-6 kg m^2, pressed on the floor by a 1.5 kg
// carriage on a vertical slider and spun at 48 rad/s. Its sliding friction
// (0.5 x 14.9 N at 3 cm) stops it within one 2 ms step; stepped as a
// constant capped force it overshot and flipped the wheel between about
// +48 and 0 rad/s every step for ever (the stick law's anchor, moved for
// the slide, kicked it back). implicit_euler checks at the step's end
// whether the point sticks.
TEST(ContactTest, ALightWheelPressedOnTheFloorStopsSpinningWithoutChatter) {
  const double r = 0.03;
  const std::string urdf =
      "<?xml version='1.0'?><robot name='caster'><link name='rig'/>"
      "<joint name='drop' type='prismatic'><parent link='rig'/><child link='carriage'/>"
      "<axis xyz='0 0 1'/><limit lower='-0.1' upper='0.1' effort='1000' velocity='10'/></joint>"
      "<link name='carriage'>" +
      inertial(1.5, 1e-3) +
      "</link><joint name='axle' type='continuous'><parent link='carriage'/><child link='wheel'/>"
      "<axis xyz='0 1 0'/></joint>"
      "<link name='wheel'>" +
      inertial(0.02, 0.4 * 0.02 * r * r) + collision(sphere(r)) + "</link></robot>";
  Scene scene;
  scene.addGround(0);
  const int caster = scene.addUrdfString(urdf, "", "caster", at(0, 0, r - 1e-4), true);
  ContactMaterial ground;
  ground.static_friction = ground.dynamic_friction = 0.5;
  scene.setGroundMaterial(ground);
  scene.finalize();
  for (int k = 0; k < 20; ++k) scene.advance(0.01);  // settles on the floor
  scene.setJointVelocities(caster, Eigen::Vector2d(0, 48));
  double most = 0;
  for (int k = 0; k < 50; ++k) {
    scene.advance(0.002);
    if (k >= 2) most = std::max(most, std::abs(scene.getJointVelocities(caster)[1]));
  }
  std::printf("light wheel: fastest after 4 ms %.3g rad/s\n", most);
  EXPECT_LT(most, 0.1);
  EXPECT_NEAR(scene.calcContactForce(scene.findLink(caster, "wheel"), -1).z(), 1.52 * kG, 0.01 * 1.52 * kG);
}

// --- filtering -----------------------------------------------------------------------

// A fixed base with a box beside x = 0.3; link l1 turns about z at the
// origin and carries a ball at x = 0.3; l2 turns about z at x = 0.3 on l1
// and carries a ball there too. All three overlap at rest.
std::string overlappingArm() {
  const std::string ball = collision(sphere(0.06), Eigen::Vector3d(0.3, 0, 0));
  return "<?xml version='1.0'?><robot name='arm'>"
         "<link name='base'>" +
         collision(box(0.1, 0.1, 0.1), Eigen::Vector3d(0.3, 0.08, 0)) +
         "</link>"
         "<joint name='j1' type='continuous'><parent link='base'/><child link='l1'/>"
         "<origin xyz='0 0 0'/><axis xyz='0 0 1'/></joint>"
         "<link name='l1'>" +
         inertial() + ball +
         "</link>"
         "<joint name='j2' type='continuous'><parent link='l1'/><child link='l2'/>"
         "<origin xyz='0.3 0 0'/><axis xyz='0 0 1'/></joint>"
         "<link name='l2'>" +
         inertial() + collision(sphere(0.06)) + "</link></robot>";
}

TEST(ContactTest, LinksOfAnArticulationTouchOnlyWithSelfCollisionAndNeverAcrossAJoint) {
  for (bool self_collision : {false, true}) {
    PhysicsSettings settings;
    settings.gravity_z = 0;
    Scene scene(settings);
    const int arm = scene.addUrdfString(overlappingArm(), "", "arm", Pose(), true);
    if (self_collision) scene.setSelfCollision(arm, true);
    scene.finalize();
    const int base = scene.findLink(arm, "base"), l1 = scene.findLink(arm, "l1"),
              l2 = scene.findLink(arm, "l2");
    SCOPED_TRACE(self_collision ? "self collision on" : "self collision off");
    // Joined by a joint: never.
    EXPECT_EQ(scene.calcContactForce(l1, base), Eigen::Vector3d::Zero());
    EXPECT_EQ(scene.calcContactForce(l2, l1), Eigen::Vector3d::Zero());
    // Two joints apart: only when asked.
    const Eigen::Vector3d push = scene.calcContactForce(l2, base);
    if (self_collision) {
      EXPECT_GT(push.norm(), 100.0);
      EXPECT_EQ(scene.calcContactForce(base, l2), -push);
      scene.advance(0.05);
      EXPECT_GT(scene.getJointPositions(arm).norm(), 1e-3);
    } else {
      EXPECT_EQ(push, Eigen::Vector3d::Zero());
      scene.advance(0.05);
      EXPECT_EQ(scene.getJointPositions(arm), Eigen::VectorXd::Zero(2));
    }
  }
}

// The broad phase reuses boxes grown by a margin until a body has moved
// farther than that margin, counting rotation: a shape 0.8 m out on an arm
// that only turns about its joint must still meet a post in its way.
TEST(ContactTest, AnArmThatOnlyTurnsStillMeetsThePostInItsWay) {
  for (const std::string integrator : {"implicit_euler", "cpodes", "semi_explicit_euler"}) {
    SCOPED_TRACE(integrator);
    PhysicsSettings settings;
    settings.integrator = parseIntegrator(integrator);
    Scene scene(settings);
    const std::string pendulum =
        "<?xml version='1.0'?><robot name='pendulum'><link name='base'/>"
        "<joint name='hinge' type='continuous'><parent link='base'/><child link='arm'/>"
        "<axis xyz='0 1 0'/></joint>"
        "<link name='arm'><inertial><origin xyz='0.8 0 0'/><mass value='1'/>"
        "<inertia ixx='2e-3' ixy='0' ixz='0' iyy='2e-3' iyz='0' izz='2e-3'/></inertial>" +
        collision(box(0.1, 0.1, 0.1), Eigen::Vector3d(0.8, 0, 0)) +
        "</link></robot>";
    const int arm = scene.addUrdfString(pendulum, "", "pendulum", at(0, 0, 1), true);
    const int post = scene.addUrdfString(
        singleLink("post", collision(box(0.1, 0.4, 0.2))), "", "post", at(0.62, 0, 0.3), true);
    scene.finalize();
    const int arm_link = scene.findLink(arm, "arm"), post_link = scene.findLink(post, "post");
    double largest_angle = 0;
    for (int k = 0; k < 150; ++k) {
      scene.advance(0.01);
      largest_angle = std::max(largest_angle, scene.getJointPositions(arm)[0]);
    }
    // Free, it would swing through pi; the post stops it near 0.7 rad.
    EXPECT_GT(largest_angle, 0.5);
    EXPECT_LT(largest_angle, 0.9);
    EXPECT_GT(scene.calcContactForce(post_link, arm_link).norm(), 1.0);
  }
}

TEST(ContactTest, SelfCollisionIsABuildTimeSetting) {
  Scene scene;
  const int arm = scene.addUrdfString(overlappingArm(), "", "arm", Pose(), true);
  EXPECT_THROW(scene.setSelfCollision(3, true), SceneError);
  scene.finalize();
  EXPECT_THROW(scene.setSelfCollision(arm, true), SceneError);
}

// --- stacks ----------------------------------------------------------------------------

class StackTest : public ::testing::TestWithParam<std::string> {};

TEST_P(StackTest, FourBoxesStandStill) {
  PhysicsSettings settings;
  settings.integrator = parseIntegrator(GetParam());
  Scene scene(settings);
  scene.addGround(0);
  std::vector<int> boxes;
  for (int i = 0; i < 4; ++i)
    boxes.push_back(scene.addUrdfString(
        singleLink("box", inertial() + collision(box(0.1, 0.1, 0.1))), "",
        "box" + std::to_string(i), at(0.003 * (i % 2), -0.002 * (i % 3), 0.05 + 0.1 * i), false));
  scene.finalize();
  std::vector<int> links;
  for (int b : boxes) links.push_back(scene.findLink(b, "box"));
  Eigen::Vector3d top_at_1s = Eigen::Vector3d::Zero();
  for (int k = 1; k <= 300; ++k) {
    scene.advance(0.01);
    if (k == 100) top_at_1s = scene.getRootPose(boxes.back()).position;
  }
  const Eigen::Vector3d top = scene.getRootPose(boxes.back()).position;
  std::printf("stack of 4 (%s): top drift 1..3 s %.2e m, top z %.5f\n", GetParam().c_str(),
              (top - top_at_1s).norm(), top.z());
  EXPECT_LT((top - top_at_1s).norm(), 1e-4);
  EXPECT_NEAR(top.z(), 0.35, 1e-3);
  // Each box carries the ones above it; in sum every box's contacts hold
  // its own weight.
  for (int i = 1; i < 4; ++i)
    EXPECT_NEAR(scene.calcContactForce(links[i], links[i - 1]).z(), (4 - i) * kG,
                0.02 * (4 - i) * kG);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(scene.calcContactForce(links[i], -1).z(), kG, 0.02 * kG);
}

INSTANTIATE_TEST_SUITE_P(Integrators, StackTest,
                         ::testing::Values("implicit_euler", "cpodes", "semi_explicit_euler"));

// --- determinism ---------------------------------------------------------------------------

// The fixed-step integrators here; CPodes in contact_scenario_test.cpp (the
// pile takes it ~45 s).
TEST(DeterminismTest, AContactRichPileIsBitIdenticalInTwoScenes) {
  expectPileIsBitIdentical("implicit_euler", 1000);
  expectPileIsBitIdentical("semi_explicit_euler", 1000);
}

TEST(DeterminismTest, RestoringAStateReplaysThePileBitIdentically) {
  expectPileReplays("implicit_euler");
  expectPileReplays("semi_explicit_euler");
}

// --- materials -----------------------------------------------------------------------------

// A 1 kg ball resting on the floor: its penetration is m g / k for the
// pair's stiffness k (one contact point).
double calcBallPenetration(const PhysicsSettings& settings, const ContactMaterial* ball,
                           const ContactMaterial* ground) {
  Scene scene(settings);
  scene.addGround(0);
  const int b = scene.addUrdfString(singleLink("ball", inertial() + collision(sphere(0.05))), "",
                                    "ball", at(0, 0, 0.05), false);
  if (ball != nullptr) scene.setContactMaterial(b, "ball", *ball);
  if (ground != nullptr) scene.setGroundMaterial(*ground);
  scene.finalize();
  for (int k = 0; k < 100; ++k) scene.advance(0.01);
  return 0.05 - scene.getRootPose(b).position.z();
}

TEST(ContactTest, StiffnessCombinesInSeries) {
  PhysicsSettings settings;
  ContactMaterial soft, hard;
  soft.stiffness = 1e5;
  hard.stiffness = 3e5;
  // Defaults: 2e5 and 2e5 in series.
  EXPECT_NEAR(calcBallPenetration(settings, nullptr, nullptr), kG / 1e5, 1e-3 * kG / 1e5);
  // 1e5 and 3e5 in series: 7.5e4.
  EXPECT_NEAR(calcBallPenetration(settings, &soft, &hard), kG / 7.5e4, 1e-3 * kG / 7.5e4);
  settings.default_material.stiffness = 4e5;
  EXPECT_NEAR(calcBallPenetration(settings, nullptr, nullptr), kG / 2e5, 1e-3 * kG / 2e5);
}

TEST(ContactTest, FrictionCombinesByGeometricMean) {
  // Box mu 0.2 on a board of mu 0.8: sqrt(0.16) = 0.4 > tan 20 deg holds;
  // box mu 0.1: sqrt(0.08) = 0.283 slides with g (sin - 0.283 cos).
  const double theta = 20 * kPi / 180;
  for (double box_mu : {0.2, 0.1}) {
    Scene scene;
    const Eigen::Vector3d rpy(theta, 0, 0);
    const Eigen::Matrix3d R = at(0, 0, 0, rpy).orientation.toRotationMatrix();
    const int board = scene.addUrdfString(
        singleLink("board", collision(box(0.5, 3, 0.1), Eigen::Vector3d(0, 0, -0.05))), "", "board",
        at(0, 0, 0, rpy), true);
    const Eigen::Vector3d start = R * Eigen::Vector3d(0, 1.0, 0.05 - 2.5e-5);
    const int body =
        scene.addUrdfString(singleLink("box", inertial() + collision(box(0.1, 0.1, 0.1))), "",
                            "box", at(start.x(), start.y(), start.z(), rpy), false);
    ContactMaterial board_material, box_material;
    board_material.static_friction = board_material.dynamic_friction = 0.8;
    box_material.static_friction = box_material.dynamic_friction = box_mu;
    scene.setContactMaterial(board, "board", board_material);
    scene.setContactMaterial(body, "", box_material);
    scene.finalize();
    const Eigen::Vector3d downhill = R * Eigen::Vector3d(0, -1, 0);
    const int link = scene.findLink(body, "box");
    for (int k = 0; k < 50; ++k) scene.advance(0.01);
    const double v1 = scene.getLinkTwist(link).linear.dot(downhill);
    for (int k = 0; k < 50; ++k) scene.advance(0.01);
    const double v2 = scene.getLinkTwist(link).linear.dot(downhill);
    const double mu = std::sqrt(0.8 * box_mu);
    const double expected = std::max(0.0, kG * (std::sin(theta) - mu * std::cos(theta)));
    EXPECT_NEAR((v2 - v1) / 0.5, expected, 0.03 * expected + 1e-3) << "box mu " << box_mu;
    if (expected == 0) {
      EXPECT_LT(std::abs(v2), 1e-3);
    }
  }
}

TEST(ContactTest, BadMaterialsAndSettingsAreSceneErrors) {
  Scene scene;
  const int b =
      scene.addUrdfString(singleLink("ball", collision(sphere(0.05))), "", "ball", Pose(), false);
  ContactMaterial bad;
  bad.static_friction = 0.1;
  bad.dynamic_friction = 0.5;
  expectSceneError([&] { scene.setContactMaterial(b, "ball", bad); },
                   {"articulation 'ball'", "link 'ball'", "static_friction"});
  expectSceneError([&] { scene.setContactMaterial(b, "nope", ContactMaterial()); },
                   {"has no link 'nope'"});
  expectSceneError([&] { scene.setContactMaterial(7, "", ContactMaterial()); },
                   {"no articulation 7"});
  bad = ContactMaterial();
  bad.stiffness = 0;
  expectSceneError([&] { scene.setGroundMaterial(bad); }, {"stiffness"});
  scene.finalize();
  expectSceneError([&] { scene.setContactMaterial(b, "", ContactMaterial()); },
                   {"already finalized"});

  PhysicsSettings settings;
  expectSceneError([&] { parseIntegrator("euler"); }, {"'euler'", "semi_explicit_euler"});
  settings.implicit_step = 0;
  expectSceneError([&] { Scene s(settings); }, {"implicit_step"});
  settings = PhysicsSettings();
  settings.fixed_step = 0;
  expectSceneError([&] { Scene s(settings); }, {"fixed_step"});
  settings = PhysicsSettings();
  settings.default_material.dissipation = -1;
  expectSceneError([&] { Scene s(settings); }, {"default_material", "dissipation"});
}

TEST(ContactTest, SemiExplicitEulerLandsOnEveryControlTick) {
  PhysicsSettings settings;
  settings.integrator = Integrator::SemiExplicitEuler;
  settings.fixed_step = 3e-4;  // does not divide 10 ms
  Scene scene(settings);
  scene.addGround(0);
  const int ball = scene.addUrdfString(singleLink("ball", inertial() + collision(sphere(0.05))), "",
                                       "ball", at(0, 0, 0.3), false);
  scene.finalize();
  for (int k = 1; k <= 50; ++k) {
    scene.advance(0.01);
    ASSERT_NEAR(scene.getTime(), 0.01 * k, 1e-12);
  }
  EXPECT_NEAR(scene.getRootPose(ball).position.z(), 0.05, 1e-3);
}

}  // namespace
}  // namespace manibench
