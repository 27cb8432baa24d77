// The physics scene against real Simbody: analytic pendulum periods, joint
// limits, drives, balancing, fixed-joint merging, contact, determinism,
// save/restore, divergence reports and input errors.
#include <gtest/gtest.h>
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
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

// --- URDF snippets -----------------------------------------------------------

std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string vec3(double x, double y, double z) {
  return num(x) + " " + num(y) + " " + num(z);
}

// <inertial> with the central inertia given in a frame rotated by rpy.
std::string inertial(double mass, const std::string& xyz, double ixx,
                     double iyy, double izz, const std::string& rpy = "0 0 0",
                     double ixy = 0, double ixz = 0, double iyz = 0) {
  return "<inertial><origin xyz='" + xyz + "' rpy='" + rpy + "'/><mass value='" +
         num(mass) + "'/><inertia ixx='" + num(ixx) + "' ixy='" + num(ixy) +
         "' ixz='" + num(ixz) + "' iyy='" + num(iyy) + "' iyz='" + num(iyz) +
         "' izz='" + num(izz) + "'/></inertial>";
}

std::string link(const std::string& name, const std::string& body = "") {
  return "<link name='" + name + "'>" + body + "</link>";
}

std::string joint(const std::string& name, const std::string& type,
                  const std::string& parent, const std::string& child,
                  const std::string& xyz, const std::string& axis,
                  const std::string& extra = "", const std::string& rpy = "0 0 0") {
  std::string j = "<joint name='" + name + "' type='" + type + "'><parent link='" +
                  parent + "'/><child link='" + child + "'/><origin xyz='" + xyz +
                  "' rpy='" + rpy + "'/>";
  if (!axis.empty()) j += "<axis xyz='" + axis + "'/>";
  return j + extra + "</joint>";
}

std::string robot(const std::string& name, const std::string& body) {
  return "<?xml version='1.0'?><robot name='" + name + "'>" + body + "</robot>";
}

std::string sphereCollision(double r) {
  return "<collision><geometry><sphere radius='" + num(r) + "'/></geometry></collision>";
}

const std::string kLimit = "<limit lower='-3' upper='3' effort='0' velocity='10'/>";

// A free sphere of radius r, mass from default_density.
std::string ballUrdf(double r) {
  return robot("ball", link("ball", sphereCollision(r)));
}

// Two-link planar arm turning about y; links of mass m with their mass at
// (L/2, 0, 0) (horizontal at q = 0), optionally a 5 cm ball on each link.
std::string armUrdf(double m = 1, double L = 0.5, bool with_collision = false) {
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
std::string spinnerUrdf(double izz, const std::string& limit_and_dynamics) {
  return robot("spinner",
               link("base") +
                   joint("spin", "continuous", "base", "blade", "0 0 0", "0 0 1",
                         limit_and_dynamics) +
                   link("blade", inertial(1.0, "0 0 0", izz, izz, izz)));
}

Pose at(double x, double y, double z) {
  Pose p;
  p.position = Eigen::Vector3d(x, y, z);
  return p;
}

std::string writeTempFile(const std::string& stem, const std::string& content) {
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
Eigen::VectorXd measurePeriods(Scene& scene, int articulation, double duration) {
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

PhysicsSettings zeroGravity() {
  PhysicsSettings settings;
  settings.gravity_z = 0;
  return settings;
}

PhysicsSettings preciseSettings() {
  PhysicsSettings settings;
  settings.integrator = Integrator::RkMerson;
  settings.accuracy = 1e-8;
  settings.gravity_z = -kG;
  return settings;
}

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
  const Eigen::Vector3d force = scene.getContactForce(link, -1);
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
  EXPECT_NEAR(scene.getContactForce(scene.findLink(box, "box"), -1).z(), weight, 0.02 * weight);
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
  const Eigen::Vector3d on_ball = scene.getContactForce(b, top);
  EXPECT_NEAR(on_ball.z(), weight, 0.02 * weight);
  EXPECT_LT((scene.getContactForce(top, b) + on_ball).norm(), 1e-9);
  EXPECT_LT((scene.getContactForce(b, -1) - on_ball).norm(), 1e-9);
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
  EXPECT_EQ(scene.getContactForce(scene.findLink(r, "l1"), -1), Eigen::Vector3d::Zero());
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
  EXPECT_NEAR(scene.getContactForce(scene.findLink(can, "can"), -1).z(), weight, 0.02 * weight);
  EXPECT_NEAR(scene.getRootPose(can).position.z(), length / 2, 1e-3);
  EXPECT_LT(scene.getRootPose(can).orientation.angularDistance(Eigen::Quaterniond::Identity()), 1e-6);
}

// --- determinism, save/restore ----------------------------------------------------

struct Snapshot {
  std::vector<double> values;
  bool operator==(const Snapshot& other) const {
    return values.size() == other.values.size() &&
           std::memcmp(values.data(), other.values.data(), values.size() * sizeof(double)) == 0;
  }
};

// Three balls falling onto the ground, each other and a driven arm (b0
// lands on the forearm's ball, b1 on b0).
struct ContactScene {
  explicit ContactScene(const std::string& integrator = "cpodes") : scene(makeSettings(integrator)) {
    scene.addGround(0);
    arm = scene.addUrdfString(armUrdf(1, 0.5, true), "", "arm", at(0, 0, 0.3), true);
    balls.push_back(scene.addUrdfString(ballUrdf(0.05), "", "b0", at(0.6, 0, 0.4), false));
    balls.push_back(scene.addUrdfString(ballUrdf(0.05), "", "b1", at(0.62, 0.01, 0.55), false));
    balls.push_back(scene.addUrdfString(ballUrdf(0.04), "", "b2", at(0.3, 0.0, 0.2), false));
    scene.finalize();
  }
  static PhysicsSettings makeSettings(const std::string& integrator) {
    PhysicsSettings settings;
    settings.integrator = parseIntegrator(integrator);
    // Explicit Euler needs h < 2 m/c: the arm's drive damping (100) on its
    // lightest mode (0.017 kg m^2) allows 3.4e-4 s, not the default 5e-4.
    settings.fixed_step = 1e-4;
    return settings;
  }
  void tick(int k) {
    DriveCommand shoulder, elbow;
    shoulder.stiffness = elbow.stiffness = 1000;
    shoulder.damping = elbow.damping = 100;
    shoulder.position_target = 0.4 * std::sin(0.05 * k);
    elbow.position_target = -0.3 * std::sin(0.03 * k);
    scene.setDriveCommands(arm, {0, 1}, {shoulder, elbow});
    scene.advance(0.01);
  }
  Snapshot snapshot() const {
    Snapshot s;
    auto append = [&s](const Eigen::VectorXd& v) { s.values.insert(s.values.end(), v.data(), v.data() + v.size()); };
    append(scene.getJointPositions(arm));
    append(scene.getJointVelocities(arm));
    for (int ball : balls) {
      const Pose pose = scene.getRootPose(ball);
      const Twist twist = scene.getLinkTwist(scene.findLink(ball, "ball"));
      append(pose.position);
      append(pose.orientation.coeffs());
      append(twist.angular);
      append(twist.linear);
    }
    s.values.push_back(scene.getTime());
    return s;
  }
  Scene scene;
  int arm = -1;
  std::vector<int> balls;
};

TEST(SceneTest, TwoScenesWithTheSameInputsAreBitIdentical) {
  for (const char* integrator : {"implicit_euler", "cpodes", "rk_merson", "semi_explicit_euler"}) {
    ContactScene a(integrator), b(integrator);
    for (int k = 0; k < 200; ++k) {
      a.tick(k);
      b.tick(k);
    }
    EXPECT_TRUE(a.snapshot() == b.snapshot()) << integrator;
    // Something happened: the balls landed, and b0 and b1, which fell onto
    // the arm and each other, were knocked sideways (b2 fell straight).
    for (int ball : a.balls)
      EXPECT_LT(a.scene.getRootPose(ball).position.z(), 0.05) << integrator;
    EXPECT_GT(std::abs(a.scene.getRootPose(a.balls[0]).position.y()), 0.05) << integrator;
    EXPECT_GT(std::abs(a.scene.getRootPose(a.balls[1]).position.y()), 0.05) << integrator;
    EXPECT_NEAR(a.scene.getRootPose(a.balls[2]).position.y(), 0.0, 1e-9) << integrator;
  }
}

TEST(SceneTest, RestoreStateReplaysBitIdentically) {
  ContactScene s;
  for (int k = 0; k < 20; ++k) s.tick(k);
  const SceneState saved = s.scene.saveState();
  // After the save: hold a command for 25 ticks, then switch it.
  auto run = [&s] {
    std::vector<Snapshot> trace;
    for (int k = 0; k < 50; ++k) {
      if (k == 25) s.tick(k);
      else s.scene.advance(0.01);
      trace.push_back(s.snapshot());
    }
    return trace;
  };
  const std::vector<Snapshot> first = run();
  s.scene.restoreState(saved);
  EXPECT_NEAR(s.scene.getTime(), 0.2, 1e-12);
  const std::vector<Snapshot> second = run();
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t k = 0; k < first.size(); ++k) EXPECT_TRUE(first[k] == second[k]) << "tick " << k;

  // A copy restores as well, and states do not cross scenes.
  const SceneState copy = saved;
  s.scene.restoreState(copy);
  EXPECT_NEAR(s.scene.getTime(), 0.2, 1e-12);
  ContactScene other;
  EXPECT_THROW(other.scene.restoreState(saved), SceneError);
  EXPECT_THROW(other.scene.restoreState(SceneState()), SceneError);
}

// --- divergence --------------------------------------------------------------------

TEST(SceneTest, NaNDriveForceDivergesNamingTheLink) {
  Scene scene;
  const int s = scene.addUrdfString(spinnerUrdf(0.1, ""), "", "spinner", Pose(), true);
  scene.finalize();
  scene.advance(0.01);
  const SceneState saved = scene.saveState();
  DriveCommand bad;
  bad.force = NAN;
  scene.setDriveCommands(s, {0}, {bad});
  try {
    scene.advance(0.01);
    FAIL() << "no SimulationDiverged";
  } catch (const SimulationDiverged& e) {
    EXPECT_EQ(e.body(), "blade");
    EXPECT_NE(std::string(e.what()).find("link 'blade' of articulation 'spinner'"), std::string::npos)
        << e.what();
    EXPECT_GE(e.time(), 0.01);
  }
  // Usable again after a restore.
  scene.restoreState(saved);
  scene.advance(0.01);
  EXPECT_NEAR(scene.getTime(), 0.02, 1e-12);
  EXPECT_TRUE(scene.getJointPositions(s).allFinite());
}

TEST(SceneTest, AbsurdDriveStiffnessDivergesNamingTheLink) {
  // implicit_euler takes drive stiffness into its step and stays stable at
  // any stiffness (ImplicitEulerIsStableAtAbsurdStiffness below).
  for (const char* integrator : {"cpodes", "rk_merson", "semi_explicit_euler"}) {
    PhysicsSettings settings;
    settings.integrator = parseIntegrator(integrator);
    Scene scene(settings);
    const int s = scene.addUrdfString(spinnerUrdf(0.1, ""), "", "spinner", Pose(), true);
    scene.finalize();
    DriveCommand absurd;
    absurd.position_target = 1;
    absurd.stiffness = 1e30;
    scene.setDriveCommands(s, {0}, {absurd});
    try {
      scene.advance(0.01);
      FAIL() << integrator << ": no SimulationDiverged";
    } catch (const SimulationDiverged& e) {
      EXPECT_EQ(e.body(), "blade") << integrator << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find("blade"), std::string::npos) << e.what();
    }
    // A setter repairs it.
    scene.setDriveCommands(s, {0}, {DriveCommand()});
    scene.setJointPositions(s, Eigen::VectorXd::Zero(1));
    scene.setJointVelocities(s, Eigen::VectorXd::Zero(1));
    EXPECT_NO_THROW(scene.advance(0.01)) << integrator;
  }
}

TEST(SceneTest, ImplicitEulerIsStableAtAbsurdStiffnessAndDivergesOnAbsurdForce) {
  PhysicsSettings settings;
  settings.integrator = Integrator::ImplicitEuler;
  Scene scene(settings);
  const int s = scene.addUrdfString(spinnerUrdf(0.1, ""), "", "spinner", Pose(), true);
  scene.finalize();
  // Stiffness 1e30 (h^2 k / I = 4e25): the drive lands on its target in
  // one step and holds it.
  DriveCommand absurd;
  absurd.position_target = 1;
  absurd.stiffness = 1e30;
  scene.setDriveCommands(s, {0}, {absurd});
  for (int k = 0; k < 10; ++k) scene.advance(0.01);
  EXPECT_NEAR(scene.getJointPositions(s)[0], 1.0, 1e-9);
  EXPECT_NEAR(scene.getJointVelocities(s)[0], 0.0, 1e-6);
  // A force of 1e30 N m is explicit: the speed explodes and the link is named.
  DriveCommand push;
  push.force = 1e30;
  scene.setDriveCommands(s, {0}, {push});
  try {
    scene.advance(0.01);
    FAIL() << "no SimulationDiverged";
  } catch (const SimulationDiverged& e) {
    EXPECT_EQ(e.body(), "blade") << e.what();
    EXPECT_NE(std::string(e.what()).find("link 'blade' of articulation 'spinner'"),
              std::string::npos)
        << e.what();
  }
}

// Without stiff forces the step is semi-implicit (symplectic) Euler:
// u+ = u + h a, q+ = q + h u+. Under a constant force from rest that gives
// q(t) = a t^2 / 2 (1 + h / t) exactly: positions lead by h a t / 2 (first
// order, like MuJoCo's and PhysX's default steps), speeds are exact.
TEST(SceneTest, ImplicitEulerIsSemiImplicitEulerForSmoothForces) {
  for (double h : {2e-3, 1e-3}) {
    PhysicsSettings settings = zeroGravity();
    settings.integrator = Integrator::ImplicitEuler;
    settings.implicit_step = h;
    Scene scene(settings);
    const int s = scene.addUrdfString(spinnerUrdf(0.5, ""), "", "s", Pose(), true);
    scene.finalize();
    DriveCommand push;
    push.force = 1.0;  // a = 2 rad/s^2
    scene.setDriveCommands(s, {0}, {push});
    for (int k = 0; k < 100; ++k) scene.advance(0.01);
    const double a = 2.0, t = 1.0;
    EXPECT_NEAR(scene.getJointVelocities(s)[0], a * t, 1e-12) << h;
    EXPECT_NEAR(scene.getJointPositions(s)[0], a * t * t / 2 * (1 + h / t), 1e-12) << h;
  }
}

// --- lookups and input errors ------------------------------------------------------

TEST(SceneTest, JointsAreDepthFirstInFileOrderAndCarryUrdfData) {
  // Joint names in reverse alphabetical order; the branch joint comes second
  // in the file but after the chain below the first joint.
  const std::string urdf = robot(
      "r", link("base") +
               joint("z_first", "revolute", "base", "l1", "0 0 0", "0 0 1",
                     "<limit lower='-1' upper='2' effort='30' velocity='4'/>"
                     "<dynamics damping='0.5' friction='0.25'/>") +
               joint("b_branch", "continuous", "base", "l4", "0 0 0", "0 0 1") +
               link("l1", inertial(1, "0 0 0", 0.01, 0.01, 0.01)) +
               joint("m_second", "prismatic", "l1", "l2", "0 0 0", "1 0 0",
                     "<limit lower='0' upper='0.1' effort='100' velocity='0.2'/>") +
               link("l2", inertial(1, "0 0 0", 0.01, 0.01, 0.01)) +
               joint("a_third", "continuous", "l2", "l3", "0 0 0", "0 1 0") +
               link("l3", inertial(1, "0 0 0", 0.01, 0.01, 0.01)) +
               link("l4", inertial(1, "0 0 0", 0.01, 0.01, 0.01)));
  Scene scene;
  const int r = scene.addUrdfString(urdf, "", "r", Pose(), true);
  const std::vector<JointDescription>& joints = scene.getJoints(r);
  ASSERT_EQ(joints.size(), 4u);
  EXPECT_EQ(joints[0].name, "z_first");
  EXPECT_EQ(joints[1].name, "m_second");
  EXPECT_EQ(joints[2].name, "a_third");
  EXPECT_EQ(joints[3].name, "b_branch");
  EXPECT_EQ(scene.getLinkName(scene.findLink(r, "l4")), "l4");
  EXPECT_EQ(joints[0].type, JointType::Revolute);
  EXPECT_EQ(joints[1].type, JointType::Prismatic);
  EXPECT_EQ(joints[2].type, JointType::Continuous);
  for (int j = 0; j < 4; ++j) EXPECT_EQ(joints[j].index, j);
  EXPECT_EQ(joints[0].lower, -1);
  EXPECT_EQ(joints[0].upper, 2);
  EXPECT_EQ(joints[0].effort_limit, 30);
  EXPECT_EQ(joints[0].velocity_limit, 4);
  EXPECT_EQ(joints[0].damping, 0.5);
  EXPECT_EQ(joints[0].friction, 0.25);
  EXPECT_TRUE(std::isinf(joints[2].lower));
  EXPECT_EQ(scene.findJoint(r, "a_third"), 2);
  EXPECT_EQ(scene.findJoint(r, "nope"), -1);
  EXPECT_EQ(scene.findLink(r, "nope"), -1);
  EXPECT_EQ(scene.findArticulation("r"), r);
  EXPECT_EQ(scene.findArticulation("nope"), -1);
  EXPECT_EQ(scene.getArticulationCount(), 1);
  EXPECT_EQ(scene.getArticulationName(r), "r");
}

TEST(SceneTest, ArticulationSourceIsWhatWasAdded) {
  const std::string text = ballUrdf(0.1);
  const std::string path = writeTempFile("ball.urdf", text);
  Scene scene;
  const int fixed = scene.addUrdfString(armUrdf(), "/some/dir", "arm", at(1, 2, 3), true);
  const int file = scene.addUrdfFile(path, "ball", at(0, 0, 1), false);
  const ArticulationSource& arm = scene.getArticulationSource(fixed);
  EXPECT_EQ(arm.urdf, armUrdf());
  EXPECT_EQ(arm.base_dir, "/some/dir");
  EXPECT_EQ(arm.root.position, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(arm.fixed_base);
  const ArticulationSource& ball = scene.getArticulationSource(file);
  EXPECT_EQ(ball.urdf, text);
  EXPECT_EQ(ball.base_dir, path.substr(0, path.rfind('/')));
  EXPECT_FALSE(ball.fixed_base);
  EXPECT_THROW(scene.getArticulationSource(2), SceneError);
}

TEST(SceneTest, RevoluteJointWithoutAxisTurnsAboutX) {
  const std::string urdf = robot(
      "r", link("base") + joint("j", "revolute", "base", "l1", "0 0 0", "", kLimit) +
               link("l1", inertial(1, "0 0 0", 0.01, 0.01, 0.01)) +
               joint("f", "fixed", "l1", "end", "0 0 -1", "") + link("end"));
  Scene scene;
  const int r = scene.addUrdfString(urdf, "", "r", at(0, 0, 2), true);
  scene.finalize();
  scene.setJointPositions(r, Eigen::VectorXd::Constant(1, kPi / 2));
  const Eigen::Vector3d end = scene.getLinkPose(scene.findLink(r, "end")).position;
  EXPECT_LT((end - Eigen::Vector3d(0, 1, 2)).norm(), 1e-12);
}

TEST(SceneTest, SceneWithoutMovingBodiesStillKeepsTime) {
  Scene scene;
  scene.addGround(0);
  const int post = scene.addUrdfString(robot("post", link("top", sphereCollision(0.1))), "", "post",
                                       at(0, 0, 0.5), true);
  scene.finalize();
  scene.advance(0.01);
  scene.advance(0.01);
  EXPECT_NEAR(scene.getTime(), 0.02, 1e-15);
  EXPECT_EQ(scene.getLinkPose(scene.findLink(post, "top")).position, Eigen::Vector3d(0, 0, 0.5));
  EXPECT_EQ(scene.calcKineticEnergy(), 0.0);
}

TEST(SceneTest, FloatingRootPoseCanBeSetAndRead) {
  Scene scene(zeroGravity());
  const int ball = scene.addUrdfString(ballUrdf(0.1), "", "ball", at(1, 2, 3), false);
  scene.finalize();
  Pose pose = at(-1, 0.5, 2);
  pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  scene.setRootPose(ball, pose);
  const Pose read = scene.getRootPose(ball);
  EXPECT_LT((read.position - pose.position).norm(), 1e-12);
  EXPECT_LT(read.orientation.angularDistance(pose.orientation), 1e-12);
  scene.advance(0.05);
  EXPECT_LT((scene.getRootPose(ball).position - pose.position).norm(), 1e-9);
}

void expectSceneError(const std::function<void()>& call, const std::string& needle) {
  try {
    call();
    ADD_FAILURE() << "no SceneError (expected one mentioning \"" << needle << "\")";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(SceneTest, BadUrdfIsASceneErrorNamingTheSource) {
  const std::string path = writeTempFile("broken_robot.urdf", "<robot name='x'><link name='a'></robot>");
  {
    Scene scene;
    expectSceneError([&] { scene.addUrdfFile(path, "x", Pose(), true); }, "broken_robot.urdf");
    expectSceneError([&] { scene.addUrdfFile(path, "x", Pose(), true); }, "malformed XML");
    expectSceneError([&] { scene.addUrdfFile("/nonexistent/r.urdf", "x", Pose(), true); },
                     "/nonexistent/r.urdf");
    EXPECT_EQ(scene.getArticulationCount(), 0);
  }
  {
    const std::string good = writeTempFile("good.urdf", armUrdf());
    Scene scene;
    EXPECT_EQ(scene.addUrdfFile(good, "arm", Pose(), true), 0);
    EXPECT_EQ(scene.getJoints(0).size(), 2u);
  }
  Scene scene;
  expectSceneError(
      [&] {
        scene.addUrdfString(robot("r", link("a") + joint("j", "revolute", "nope", "a", "0 0 0",
                                                          "0 0 1", kLimit)),
                            "", "robot", Pose(), true);
      },
      "nope");
  expectSceneError([&] { scene.addUrdfString("<robot name='r'><link", "", "robot", Pose(), true); },
                   "<string> of articulation 'robot'");
  expectSceneError(
      [&] {
        scene.addUrdfString(robot("r", link("a") + joint("flat", "planar", "a", "b", "0 0 0", "0 0 1",
                                                         "<mimic joint='other'/>") +
                                           link("b", inertial(1, "0 0 0", 1, 1, 1))),
                            "", "robot", Pose(), true);
      },
      "joint 'flat' is planar and cannot mimic another joint");
  expectSceneError(
      [&] {
        scene.addUrdfString(robot("r", link("a") + joint("free", "floating", "a", "b", "0 0 0", "") +
                                           link("b", inertial(1, "0 0 0", 1, 1, 1))),
                            "", "robot", Pose(), true);
      },
      "joint 'free' is floating");
  expectSceneError(
      [&] {
        scene.addUrdfString(robot("r", link("a", inertial(1, "0 0 0", 1, 1, 3))), "", "robot",
                            Pose(), false);
      },
      "link 'a' has an invalid inertia");
  EXPECT_EQ(scene.getArticulationCount(), 0);
}

TEST(SceneTest, MisuseIsASceneError) {
  Scene scene;
  const int arm = scene.addUrdfString(armUrdf(), "", "arm", Pose(), true);
  expectSceneError([&] { scene.addUrdfString(armUrdf(), "", "arm", Pose(), true); },
                   "'arm' already exists");
  expectSceneError([&] { scene.getJointPositions(arm); }, "not finalized");
  expectSceneError([&] { scene.advance(0.01); }, "not finalized");
  scene.finalize();
  expectSceneError([&] { scene.addGround(0); }, "already finalized");
  expectSceneError([&] { scene.addUrdfString(ballUrdf(0.1), "", "b", Pose(), false); },
                   "already finalized");
  expectSceneError([&] { scene.setJointPositions(arm, Eigen::VectorXd::Zero(3)); },
                   "articulation 'arm' has 2 joints, got 3 values");
  expectSceneError([&] { scene.setJointVelocities(arm, Eigen::VectorXd::Zero(1)); },
                   "has 2 joints, got 1 values");
  expectSceneError([&] { scene.setDriveCommands(arm, {0, 1}, {DriveCommand()}); }, "2 joints but 1");
  expectSceneError([&] { scene.setDriveCommands(arm, {2}, {DriveCommand()}); }, "has no joint 2");
  expectSceneError([&] { scene.setRootPose(arm, Pose()); }, "fixed base");
  expectSceneError([&] { scene.getJoints(5); }, "no articulation 5");
  expectSceneError([&] { scene.getLinkPose(99); }, "no link 99");
  expectSceneError([&] { scene.advance(-1); }, "dt must be positive");
  expectSceneError([&] { scene.setJointDynamics(arm, 0, -1, 0); }, "non-negative");
  EXPECT_THROW(parseIntegrator("euler"), SceneError);
}

}  // namespace
}  // namespace manibench
