// The physics scene's dynamics against real Simbody: analytic pendulum
// periods, fixed-joint merging, joint limits, drives, balancing, damping
// and friction, bodies resting in contact.
#include "scene_urdf.hpp"

namespace manibench {
namespace {

using namespace scene_testing;

// --- pendulums -----------------------------------------------------------------

// Two point masses m on massless rods of length L, both joints about +y.
// Normal modes (absolute angles): w^2 = (2 -+ sqrt 2) g / L with
// phi2 / phi1 = +-sqrt 2; the joint angles are q1 = phi1, q2 = phi2 - phi1.
TEST(SceneTest, DoublePendulumNormalModePeriodsMatchAnalytic) {
  const double m = 1.0, L = 1.0, amplitude = 0.01;
  const std::string urdf = robot(
      "dp", link("base") +
                joint("j1", "revolute", "base", "l1", "0 0 0", "0 1 0", kLimit) +
                link("l1", inertial(m, vec3(0, 0, -L), 0, 0, 0)) +
                joint("j2", "revolute", "l1", "l2", vec3(0, 0, -L), "0 1 0", kLimit) +
                link("l2", inertial(m, vec3(0, 0, -L), 0, 0, 0)));
  for (int mode = 0; mode < 2; ++mode) {
    const double sign = mode == 0 ? 1 : -1;
    const double w2 = (2 - sign * std::sqrt(2.0)) * kG / L;
    const double analytic = 2 * kPi / std::sqrt(w2);

    Scene scene(preciseSettings());
    const int dp = scene.addUrdfString(urdf, "", "dp", at(0, 0, 3), true);
    scene.finalize();
    Eigen::VectorXd q(2);
    q << amplitude, amplitude * (sign * std::sqrt(2.0) - 1);
    scene.setJointPositions(dp, q);
    // About three periods of the slow mode. A pure mode keeps its shape:
    // both joints swing with the mode's period.
    const Eigen::VectorXd periods = measurePeriods(scene, dp, 8.0);
    EXPECT_NEAR(periods[0], analytic, 1e-3 * analytic) << "mode " << mode + 1;
    EXPECT_NEAR(periods[1], analytic, 1e-3 * analytic) << "mode " << mode + 1;
    std::printf("double pendulum mode %d: period %.6f s, analytic %.6f s, relative error %.1e\n",
                mode + 1, periods[0], analytic, std::abs(periods[0] - analytic) / analytic);
  }
}

// A rod (inertia given in a rotated inertial frame) with a tip mass on a
// fixed joint: one compound pendulum whose period needs the merged mass.
std::string compoundPendulumUrdf(bool with_tip) {
  const double m = 1.0, L = 1.0;
  // Central rod inertia in link axes diag(mL^2/12, mL^2/12, 1e-4),
  // re-expressed in an inertial frame turned by rpy = (a, b, c).
  const double a = 0.3, b = -0.2, c = 0.4;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(c, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(b, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Matrix3d I_link = Eigen::Vector3d(m * L * L / 12, m * L * L / 12, 1e-4).asDiagonal();
  const Eigen::Matrix3d I = R.transpose() * I_link * R;
  std::string body =
      link("base") +
      joint("hinge", "revolute", "base", "rod", "0 0 0", "0 1 0", kLimit) +
      link("rod", inertial(m, vec3(0, 0, -L / 2), I(0, 0), I(1, 1), I(2, 2),
                           vec3(a, b, c), I(0, 1), I(0, 2), I(1, 2)));
  if (with_tip)
    body += joint("tip_mount", "fixed", "rod", "tip", vec3(0, 0, -L), "", "",
                  "0.3 0.2 0.1") +
            link("tip", inertial(0.5, "0 0 0", 1e-4, 1e-4, 1e-4)) +
            joint("marker_mount", "fixed", "tip", "marker", "0 0 -0.1", "") +
            link("marker");
  return robot("compound", body);
}

TEST(SceneTest, FixedJointMergesMassAndKeepsLinkPose) {
  const double m = 1.0, L = 1.0, m_tip = 0.5;
  // About the hinge: rod m L^2 / 3, tip m_tip L^2 + its own 1e-4.
  const double I_with = m * L * L / 3 + m_tip * L * L + 1e-4;
  const double I_without = m * L * L / 3;
  const double T_with = 2 * kPi * std::sqrt(I_with / (kG * (m * L / 2 + m_tip * L)));
  const double T_without = 2 * kPi * std::sqrt(I_without / (kG * m * L / 2));
  ASSERT_GT(std::abs(T_with - T_without) / T_without, 0.01);

  for (bool with_tip : {true, false}) {
    Scene scene(preciseSettings());
    const int p = scene.addUrdfString(compoundPendulumUrdf(with_tip), "", "p",
                                      at(1, 2, 3), true);
    scene.finalize();
    scene.setJointPositions(p, Eigen::VectorXd::Constant(1, 0.01));
    const double T = measurePeriods(scene, p, 6.0)[0];
    const double expected = with_tip ? T_with : T_without;
    EXPECT_NEAR(T, expected, 1e-3 * expected) << (with_tip ? "with tip" : "without tip");
  }

  // The merged links keep ids, names and their own frames.
  Scene scene;
  const int p = scene.addUrdfString(compoundPendulumUrdf(true), "", "p", at(1, 2, 3), true);
  const int tip = scene.findLink(p, "tip");
  const int marker = scene.findLink(p, "marker");
  ASSERT_GE(tip, 0);
  ASSERT_GE(marker, 0);
  EXPECT_EQ(scene.getLinkName(tip), "tip");
  EXPECT_EQ(scene.getJoints(p).size(), 1u);  // fixed joints are not joints
  scene.finalize();
  EXPECT_EQ(scene.getRootPose(p).position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(scene.getLinkPose(scene.findLink(p, "base")).position, Eigen::Vector3d(1, 2, 3));
  scene.setJointPositions(p, Eigen::VectorXd::Constant(1, 0.5));
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d R_tip = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Pose tip_pose = scene.getLinkPose(tip);
  EXPECT_LT((tip_pose.position - (Eigen::Vector3d(1, 2, 3) + Ry * Eigen::Vector3d(0, 0, -1))).norm(), 1e-12);
  EXPECT_LT((tip_pose.orientation.toRotationMatrix() - Ry * R_tip).norm(), 1e-12);
  const Pose marker_pose = scene.getLinkPose(marker);
  EXPECT_LT((marker_pose.position -
             (tip_pose.position + Ry * R_tip * Eigen::Vector3d(0, 0, -0.1))).norm(), 1e-12);
  // Twist of the link origin: w x r about the hinge.
  Eigen::VectorXd qdot = Eigen::VectorXd::Constant(1, 2.0);
  scene.setJointVelocities(p, qdot);
  const Twist twist = scene.getLinkTwist(tip);
  EXPECT_LT((twist.angular - Eigen::Vector3d(0, 2, 0)).norm(), 1e-12);
  EXPECT_LT((twist.linear - Eigen::Vector3d(0, 2, 0).cross(tip_pose.position - Eigen::Vector3d(1, 2, 3))).norm(), 1e-12);
}

// --- joints ---------------------------------------------------------------------

TEST(SceneTest, PrismaticJointStopsAtItsLowerLimit) {
  const std::string urdf = robot(
      "lift", link("base") +
                  joint("slide", "prismatic", "base", "cart", "0 0 0", "0 0 1",
                        "<limit lower='-0.5' upper='0.5' effort='0' velocity='1'/>") +
                  link("cart", inertial(1.0, "0 0 0", 0.01, 0.01, 0.01)));
  Scene scene;
  const int lift = scene.addUrdfString(urdf, "", "lift", at(0, 0, 1), true);
  scene.finalize();
  EXPECT_EQ(scene.getJointPositions(lift)[0], 0.0);
  for (int k = 0; k < 200; ++k) scene.advance(0.01);
  EXPECT_NEAR(scene.getJointPositions(lift)[0], -0.5, 3e-3);
  EXPECT_NEAR(scene.getJointVelocities(lift)[0], 0.0, 1e-3);
  EXPECT_NEAR(scene.getLinkPose(scene.findLink(lift, "cart")).position.z(), 0.5, 3e-3);
}

TEST(SceneTest, JointsStartAtZeroClampedIntoTheirLimits) {
  const std::string urdf = robot(
      "r", link("base") +
               joint("a", "revolute", "base", "l1", "0 0 0", "0 0 1",
                     "<limit lower='0.2' upper='1' effort='0' velocity='1'/>") +
               link("l1", inertial(1, "0 0 0", 0.01, 0.01, 0.01)) +
               joint("b", "prismatic", "l1", "l2", "0 0 0", "1 0 0",
                     "<limit lower='-1' upper='-0.3' effort='0' velocity='1'/>") +
               link("l2", inertial(1, "0 0 0", 0.01, 0.01, 0.01)));
  Scene scene(zeroGravity());
  const int r = scene.addUrdfString(urdf, "", "r", Pose(), true);
  scene.finalize();
  const Eigen::VectorXd q = scene.getJointPositions(r);
  EXPECT_EQ(q[0], 0.2);
  EXPECT_EQ(q[1], -0.3);
}

TEST(SceneTest, VelocityDriveReachesItsTargetAndRespectsTheEffortLimit) {
  // Effort unlimited: first-order response with time constant I / d = 1 ms.
  {
    Scene scene;
    const int s = scene.addUrdfString(spinnerUrdf(0.1, "<limit effort='0' velocity='5'/>"),
                                      "", "s", Pose(), true);
    scene.finalize();
    DriveCommand command;
    command.velocity_target = 1.0;
    command.damping = 100;
    scene.setDriveCommands(s, {0}, {command});
    for (int k = 0; k < 50; ++k) scene.advance(0.01);
    EXPECT_NEAR(scene.getJointVelocities(s)[0], 1.0, 0.02);
  }
  // Effort 0.1 N m on I = 1 kg m^2: constant acceleration 0.1 rad/s^2.
  {
    Scene scene;
    const int s = scene.addUrdfString(spinnerUrdf(1.0, "<limit effort='0.1' velocity='5'/>"),
                                      "", "s", Pose(), true);
    scene.finalize();
    EXPECT_EQ(scene.getJoints(s)[0].effort_limit, 0.1);
    DriveCommand command;
    command.velocity_target = 1.0;
    command.damping = 100;
    scene.setDriveCommands(s, {0}, {command});
    for (int k = 0; k < 50; ++k) scene.advance(0.01);
    EXPECT_NEAR(scene.getJointVelocities(s)[0], 0.05, 0.05 * 0.02);
  }
}

TEST(SceneTest, PositionDriveHoldsTarget) {
  Scene scene;
  const int s = scene.addUrdfString(spinnerUrdf(0.1, ""), "", "s", Pose(), true);
  scene.finalize();
  DriveCommand command;
  command.position_target = 0.7;
  command.stiffness = 1000;
  command.damping = 100;
  scene.setDriveCommands(s, {0}, {command});
  for (int k = 0; k < 100; ++k) scene.advance(0.01);
  EXPECT_NEAR(scene.getJointPositions(s)[0], 0.7, 1e-3);
}

TEST(SceneTest, PassiveBalancingHoldsAHorizontalArm) {
  // Balanced, with only a zero-velocity damping drive: stays put.
  {
    Scene scene;
    const int arm = scene.addUrdfString(armUrdf(), "", "arm", at(0, 0, 1), true);
    scene.finalize();
    DriveCommand hold;
    hold.damping = 100;
    scene.setDriveCommands(arm, {0, 1}, {hold, hold});
    scene.setPassiveForceBalancing(arm, {0, 1}, true);
    for (int k = 0; k < 200; ++k) scene.advance(0.01);
    const Eigen::VectorXd q = scene.getJointPositions(arm);
    EXPECT_LT(std::abs(q[0]), 1e-3);
    EXPECT_LT(std::abs(q[1]), 1e-3);
  }
  // Not balanced, not driven: it falls (positive rotation about y turns +x
  // towards -z, so the angle grows).
  {
    Scene scene;
    const int arm = scene.addUrdfString(armUrdf(), "", "arm", at(0, 0, 1), true);
    scene.finalize();
    for (int k = 0; k < 30; ++k) scene.advance(0.01);
    EXPECT_GT(scene.getJointPositions(arm)[0], 0.1);
  }
  // Balancing only the elbow: the shoulder still falls.
  {
    Scene scene;
    const int arm = scene.addUrdfString(armUrdf(), "", "arm", at(0, 0, 1), true);
    scene.finalize();
    scene.setPassiveForceBalancing(arm, {1}, true);
    for (int k = 0; k < 30; ++k) scene.advance(0.01);
    EXPECT_GT(scene.getJointPositions(arm)[0], 0.1);
  }
}

TEST(SceneTest, JointDampingAndFrictionSlowASpinningLink) {
  // Damping from the URDF: u = u0 exp(-d t / I).
  {
    Scene scene;
    const int s = scene.addUrdfString(spinnerUrdf(1.0, "<dynamics damping='2' friction='0'/>"),
                                      "", "s", Pose(), true);
    scene.finalize();
    EXPECT_EQ(scene.getJoints(s)[0].damping, 2.0);
    scene.setJointVelocities(s, Eigen::VectorXd::Constant(1, 1.0));
    for (int k = 0; k < 50; ++k) scene.advance(0.01);
    EXPECT_NEAR(scene.getJointVelocities(s)[0], std::exp(-1.0), 0.01 * std::exp(-1.0));
  }
  // Friction set per episode: u = u0 - f t / I until it stops.
  {
    Scene scene;
    const int s = scene.addUrdfString(spinnerUrdf(1.0, ""), "", "s", Pose(), true);
    scene.finalize();
    scene.setJointDynamics(s, 0, 0.0, 0.5);
    scene.setJointVelocities(s, Eigen::VectorXd::Constant(1, 1.0));
    for (int k = 0; k < 100; ++k) scene.advance(0.01);
    EXPECT_NEAR(scene.getJointVelocities(s)[0], 0.5, 0.01);
    for (int k = 0; k < 200; ++k) scene.advance(0.01);
    EXPECT_NEAR(scene.getJointVelocities(s)[0], 0.0, 0.01);
  }
}

// A light link whose Coulomb friction stops it well within one 2 ms step
// (f h / I = 10 rad/s against 1 rad/s): it must stop and stay stopped, not
// chatter from +u to -u each step (a caster's swivel: 1e-5 kg m^2 under
// 0.05 N m). The implicit step decides, as for a drive's effort limit,
// whether friction saturates or holds at the step's end.
TEST(SceneTest, CoulombFrictionStopsALightLinkWithoutChatter) {
  Scene scene;
  const int s = scene.addUrdfString(spinnerUrdf(1e-5, ""), "", "s", Pose(), true);
  scene.finalize();
  scene.setJointDynamics(s, 0, 0.0, 0.05);
  scene.setJointVelocities(s, Eigen::VectorXd::Constant(1, 1.0));
  const double q0 = scene.getJointPositions(s)[0];
  double most = 0;
  for (int k = 0; k < 50; ++k) {
    scene.advance(0.002);
    if (k > 0) most = std::max(most, std::abs(scene.getJointVelocities(s)[0]));
  }
  EXPECT_LT(most, 1e-3) << "stopped after the first step";
  // It had 1 rad/s and stops within a step: it turns less than 2 mrad.
  EXPECT_LT(std::abs(scene.getJointPositions(s)[0] - q0), 2e-3);
}

// --- contact -------------------------------------------------------------------

TEST(SceneTest, FloatingSphereComesToRestOnTheGround) {
  const double r = 0.05, height = 0.1;
  const double mass = 1000 * 4.0 / 3.0 * kPi * r * r * r;  // default density
  Scene scene;
  scene.addGround(height);
  const int ball = scene.addUrdfString(ballUrdf(r), "", "ball", at(0.2, -0.1, 0.4), false);
  scene.finalize();
  EXPECT_EQ(scene.getJoints(ball).size(), 0u);
  const int link = scene.findLink(ball, "ball");
  EXPECT_EQ(scene.getRootPose(ball).position, Eigen::Vector3d(0.2, -0.1, 0.4));
  for (int k = 0; k < 150; ++k) scene.advance(0.01);
  const Pose pose = scene.getRootPose(ball);
  // Penetration at the default stiffness (1e5 N/m per point) is ~50 um.
  EXPECT_LT(pose.position.z(), height + r);
  EXPECT_GT(pose.position.z(), height + r - 3e-3);
  EXPECT_NEAR(pose.position.x(), 0.2, 1e-6);
  EXPECT_LT(scene.getLinkTwist(link).linear.norm(), 1e-3);
  const Eigen::Vector3d force = scene.calcContactForce(link, -1);
  EXPECT_NEAR(force.z(), mass * kG, 0.02 * mass * kG);
  EXPECT_NEAR(force.x(), 0.0, 1e-6);
  EXPECT_NEAR(force.y(), 0.0, 1e-6);
}

TEST(SceneTest, BoxRestsOnTheGround) {
  const std::string urdf = robot(
      "box", link("box", "<collision><geometry><box size='0.1 0.2 0.1'/></geometry></collision>"));
  Scene scene;
  scene.addGround(0.0);
  const int box = scene.addUrdfString(urdf, "", "box", at(0, 0, 0.1), false);
  scene.finalize();
  for (int k = 0; k < 150; ++k) scene.advance(0.01);
  EXPECT_NEAR(scene.getRootPose(box).position.z(), 0.05, 3e-3);
  const double weight = 1000 * 0.1 * 0.2 * 0.1 * kG;
  EXPECT_NEAR(scene.calcContactForce(scene.findLink(box, "box"), -1).z(), weight, 0.02 * weight);
}

TEST(SceneTest, SphereRestsOnAFixedSphereAndForcesPairUp) {
  const double r = 0.05;
  Scene scene;
  const int post = scene.addUrdfString(robot("post", link("top", sphereCollision(r))), "",
                                       "post", at(0, 0, 0.5), true);
  const int ball = scene.addUrdfString(ballUrdf(r), "", "ball", at(0, 0, 0.62), false);
  scene.finalize();
  for (int k = 0; k < 150; ++k) scene.advance(0.01);
  const int top = scene.findLink(post, "top"), b = scene.findLink(ball, "ball");
  const double weight = 1000 * 4.0 / 3.0 * kPi * r * r * r * kG;
  const Eigen::Vector3d on_ball = scene.calcContactForce(b, top);
  EXPECT_NEAR(on_ball.z(), weight, 0.02 * weight);
  EXPECT_LT((scene.calcContactForce(top, b) + on_ball).norm(), 1e-9);
  EXPECT_LT((scene.calcContactForce(b, -1) - on_ball).norm(), 1e-9);
  EXPECT_NEAR(scene.getRootPose(ball).position.z(), 0.6, 3e-3);
}

TEST(SceneTest, LinksOfOneArticulationDoNotCollide) {
  // Both links carry a ball at the elbow, overlapping deeply.
  const std::string elbow_ball =
      "<collision><origin xyz='0 0 -0.5'/><geometry><sphere radius='0.1'/></geometry></collision>";
  const std::string urdf = robot(
      "r", link("base") + joint("a", "continuous", "base", "l1", "0 0 0", "0 1 0") +
               link("l1", inertial(1, "0 0 -0.5", 0.01, 0.01, 0.01) + elbow_ball) +
               joint("b", "continuous", "l1", "l2", "0 0 -0.5", "0 1 0") +
               link("l2", inertial(1, "0 0 0", 0.01, 0.01, 0.01) +
                              "<collision><origin xyz='0.05 0 -0.05'/><geometry><sphere radius='0.1'/>"
                              "</geometry></collision>"));
  Scene scene(zeroGravity());
  const int r = scene.addUrdfString(urdf, "", "r", at(0, 0, 1), true);
  scene.finalize();
  EXPECT_EQ(scene.calcContactForce(scene.findLink(r, "l1"), -1), Eigen::Vector3d::Zero());
  for (int k = 0; k < 10; ++k) scene.advance(0.01);
  EXPECT_EQ(scene.getJointPositions(r), Eigen::VectorXd::Zero(2));
}

TEST(SceneTest, CylinderStandsOnTheGroundWithMassFromItsVolume) {
  // Simbody's own contact had no cylinder pairs; contact_test.cpp checks
  // every pair, this one the scene's wiring of mass and contact.
  const double r = 0.05, length = 0.2;
  const std::string urdf = robot(
      "can", link("can", "<collision name='body'><geometry><cylinder radius='0.05' length='0.2'/>"
                         "</geometry></collision>"));
  Scene scene;
  scene.addGround(0);
  const int can = scene.addUrdfString(urdf, "", "can", at(0, 0, length / 2 + 1e-3), false);
  scene.finalize();
  for (int k = 0; k < 100; ++k) scene.advance(0.01);
  const double weight = 1000 * kPi * r * r * length * kG;
  EXPECT_NEAR(scene.calcContactForce(scene.findLink(can, "can"), -1).z(), weight, 0.02 * weight);
  EXPECT_NEAR(scene.getRootPose(can).position.z(), length / 2, 1e-3);
  EXPECT_LT(scene.getRootPose(can).orientation.angularDistance(Eigen::Quaterniond::Identity()), 1e-6);
}

}  // namespace
}  // namespace manibench
