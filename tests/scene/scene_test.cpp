// The physics scene against real Simbody: determinism, save/restore,
// divergence reports, the implicit Euler step's stability and order, lookups
// and input errors.
#include "scene_urdf.hpp"

namespace manibench {
namespace {

using namespace scene_testing;

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

// The spinner alone, finalized, its drive pulling to q = 1 with stiffness
// 1e30 (h^2 k / I = 4e25 at 10 ms); returns its articulation.
int addAbsurdlyDrivenSpinner(Scene& scene) {
  const int s = scene.addUrdfString(spinnerUrdf(0.1, ""), "", "spinner", Pose(), true);
  scene.finalize();
  DriveCommand absurd;
  absurd.position_target = 1;
  absurd.stiffness = 1e30;
  scene.setDriveCommands(s, {0}, {absurd});
  return s;
}

TEST(SceneTest, AbsurdDriveStiffnessDivergesNamingTheLink) {
  // implicit_euler takes drive stiffness into its step and stays stable at
  // any stiffness (ImplicitEulerIsStableAtAbsurdStiffness below).
  for (const char* integrator : {"cpodes", "rk_merson", "semi_explicit_euler"}) {
    PhysicsSettings settings;
    settings.integrator = parseIntegrator(integrator);
    Scene scene(settings);
    const int s = addAbsurdlyDrivenSpinner(scene);
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
  // The drive lands on its target in one step and holds it.
  const int s = addAbsurdlyDrivenSpinner(scene);
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
