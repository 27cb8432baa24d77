// Scene::calcLinkJacobian (and the ABI's calc_link_jacobian behind
// SceneView::calcLinkJacobian) against central finite differences of
// Scene::getLinkPose on the real mobile Panda robots (assets/robots/).
#include <gtest/gtest.h>
#include <manibench/plugin_instances.hpp>
#include <manibench/scene.hpp>
#include <manibench/sdk/scene_view.hpp>

#include <Eigen/Geometry>
#include <random>
#include <string>

namespace manibench {
namespace {

const std::string kRobotDir = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/assets/robots";

struct Loaded {
  std::unique_ptr<Scene> scene;
  int robot = -1;
};

Loaded load(const std::string& name) {
  Loaded l;
  l.scene = std::make_unique<Scene>();
  // A root away from the origin and turned, so that world and robot axes differ.
  Pose root;
  root.position = Eigen::Vector3d(0.3, -0.2, 0.05);
  root.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  l.robot = l.scene->addUrdfFile(kRobotDir + "/" + name + ".urdf", "robot", root, true);
  l.scene->finalize();
  return l;
}

// A configuration inside every joint's range, away from the zero pose.
Eigen::VectorXd randomConfiguration(const Scene& scene, int robot, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.1, 0.9);
  const auto& joints = scene.getJoints(robot);
  Eigen::VectorXd q(static_cast<Eigen::Index>(joints.size()));
  for (const JointDescription& j : joints) {
    const double lower = std::isfinite(j.lower) ? j.lower : -1.0;
    const double upper = std::isfinite(j.upper) ? j.upper : 1.0;
    q[j.index] = lower + unit(rng) * (upper - lower);
  }
  return q;
}

// Central differences: column j = d(pose of `point` on `link`)/d q_j, with the
// rotation's derivative as the angular velocity it implies.
Eigen::Matrix<double, 6, Eigen::Dynamic> calcFiniteDifferences(Scene& scene, int robot, int link,
                                                              const Eigen::Vector3d& point,
                                                              const Eigen::VectorXd& q) {
  constexpr double h = 1e-6;
  Eigen::Matrix<double, 6, Eigen::Dynamic> fd(6, q.size());
  for (Eigen::Index j = 0; j < q.size(); ++j) {
    Eigen::VectorXd plus = q, minus = q;
    plus[j] += h;
    minus[j] -= h;
    scene.setJointPositions(robot, plus);
    const Pose a = scene.getLinkPose(link);
    scene.setJointPositions(robot, minus);
    const Pose b = scene.getLinkPose(link);
    const Eigen::AngleAxisd turn(a.orientation * b.orientation.inverse());
    fd.col(j).head<3>() = turn.axis() * turn.angle() / (2 * h);
    fd.col(j).tail<3>() = ((a.position + a.orientation * point) -
                           (b.position + b.orientation * point)) / (2 * h);
  }
  scene.setJointPositions(robot, q);
  return fd;
}

TEST(LinkJacobian, MatchesFiniteDifferencesOnTheSingleArmRobot) {
  Loaded l = load("mobile_panda_single");
  Scene& scene = *l.scene;
  const auto& joints = scene.getJoints(l.robot);
  for (unsigned seed : {1u, 2u, 3u}) {
    const Eigen::VectorXd q = randomConfiguration(scene, l.robot, seed);
    scene.setJointPositions(l.robot, q);
    for (const std::string link_name :
         {"right_panda_tcp", "right_panda_link4", "base_link", "body_link"}) {
      const int link = scene.findLink(l.robot, link_name);
      ASSERT_GE(link, 0) << link_name;
      const Eigen::Vector3d point(0.03, -0.02, 0.05);
      const Eigen::Matrix<double, 6, Eigen::Dynamic> jacobian =
          scene.calcLinkJacobian(l.robot, link, point);
      ASSERT_EQ(jacobian.cols(), static_cast<Eigen::Index>(joints.size()));
      const Eigen::Matrix<double, 6, Eigen::Dynamic> fd =
          calcFiniteDifferences(scene, l.robot, link, point, q);
      for (Eigen::Index j = 0; j < jacobian.cols(); ++j)
        for (int r = 0; r < 6; ++r)
          EXPECT_NEAR(jacobian(r, j), fd(r, j), 1e-6)
              << link_name << " seed " << seed << " row " << r << " joint " << joints[j].name;
    }
  }
}

TEST(LinkJacobian, ColumnsOfJointsThatDoNotMoveTheLinkAreZero) {
  Loaded l = load("mobile_panda_dual");
  Scene& scene = *l.scene;
  scene.setJointPositions(l.robot, randomConfiguration(scene, l.robot, 7));
  const Eigen::Matrix<double, 6, Eigen::Dynamic> jacobian =
      scene.calcLinkJacobian(l.robot, scene.findLink(l.robot, "right_panda_tcp"));
  for (const JointDescription& j : scene.getJoints(l.robot)) {
    const bool moves = j.name.rfind("left_", 0) != 0 && j.name.find("finger") == std::string::npos;
    if (moves)
      EXPECT_GT(jacobian.col(j.index).norm(), 1e-3) << j.name;
    else
      EXPECT_EQ(jacobian.col(j.index).norm(), 0.0) << j.name;
  }
  // The base's yaw turns the TCP about world z: angular column (0, 0, 1).
  const int yaw = scene.findJoint(l.robot, "root_yaw");
  EXPECT_NEAR((jacobian.col(yaw).head<3>() - Eigen::Vector3d::UnitZ()).norm(), 0, 1e-12);
}

TEST(LinkJacobian, RejectsBadArguments) {
  Loaded l = load("mobile_panda_single");
  Scene& scene = *l.scene;
  const int tcp = scene.findLink(l.robot, "right_panda_tcp");
  EXPECT_THROW(scene.calcLinkJacobian(5, tcp), SceneError);
  EXPECT_THROW(scene.calcLinkJacobian(l.robot, 10000), SceneError);
  try {
    scene.calcLinkJacobian(l.robot, tcp, Eigen::Vector3d(0, std::nan(""), 0));
    FAIL() << "a NaN point was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("right_panda_tcp"), std::string::npos) << e.what();
  }
  Scene unfinalized;
  EXPECT_THROW(unfinalized.calcLinkJacobian(0, 0), SceneError);
}

// What a plugin sees: the ABI's calc_link_jacobian (row-major) through the
// SDK's SceneView is the scene's Jacobian; a wrong count is an error.
TEST(LinkJacobian, ThePluginsViewIsTheScenes) {
  Loaded l = load("mobile_panda_dual");
  Scene& scene = *l.scene;
  scene.setJointPositions(l.robot, randomConfiguration(scene, l.robot, 11));
  SceneBridge bridge(scene);
  const sdk::SceneView view(SceneBridge::getApi(), bridge.getHandle());
  const int tcp = scene.findLink(l.robot, "left_panda_tcp");
  const Eigen::Vector3d point(0.01, 0.02, -0.03);
  const Eigen::MatrixXd through_abi = view.calcLinkJacobian(l.robot, tcp, point);
  const Eigen::Matrix<double, 6, Eigen::Dynamic> direct = scene.calcLinkJacobian(l.robot, tcp, point);
  ASSERT_EQ(through_abi.rows(), 6);
  ASSERT_EQ(through_abi.cols(), direct.cols());
  EXPECT_EQ(through_abi, Eigen::MatrixXd(direct));
  EXPECT_GT(direct.norm(), 1.0);

  std::vector<double> out(6 * 5);
  char message[256] = {};
  mb_error err{message, sizeof(message)};
  const double origin[3] = {0, 0, 0};
  EXPECT_EQ(SceneBridge::getApi()->calc_link_jacobian(bridge.getHandle(), l.robot, tcp, origin,
                                                      out.data(), 5, &err),
            MB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(message).find("has 22 joints, the call passed 5"), std::string::npos) << message;
}

}  // namespace
}  // namespace manibench
