// The implicit step's view of the multibody system (core/scene/
// tree_structure.hpp) against Simbody's own operators: mass matrix blocks by
// the composite-rigid-body algorithm against calcM, point Jacobians against
// calcStationJacobian, on trees of pins, sliders, a massless link and free
// bodies in random configurations.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>

#include "Simbody.h"
#include "tree_structure.hpp"

namespace manibench {
namespace {

using scene_detail::TreeStructure;

struct TestSystem {
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  std::vector<SimTK::MobilizedBodyIndex> bodies;

  TestSystem() {
    auto mass = [](double m, SimTK::Vec3 com, SimTK::Vec3 moments, SimTK::Vec3 products) {
      // A proper inertia about the mass centre, shifted to the body origin.
      return SimTK::MassProperties(
          m, com, SimTK::Inertia(moments, products).shiftFromMassCenter(com, m));
    };
    const SimTK::Body::Rigid heavy(mass(2.0, SimTK::Vec3(0.1, -0.05, 0.2), SimTK::Vec3(0.3, 0.25, 0.2),
                                        SimTK::Vec3(0.01, -0.02, 0.015)));
    const SimTK::Body::Rigid light(mass(0.05, SimTK::Vec3(0, 0.02, 0.03), SimTK::Vec3(1e-4, 2e-4, 1.5e-4),
                                        SimTK::Vec3(0)));
    // A mobile base (slider, slider through a massless body, pin), an arm
    // of pins with offsets and turned axes, a finger slider, and a branch.
    SimTK::MobilizedBody::Slider x(matter.Ground(), SimTK::Transform(), SimTK::Body::Massless(),
                                   SimTK::Transform());
    SimTK::MobilizedBody::Slider y(x, SimTK::Transform(SimTK::Rotation(SimTK::Pi / 2, SimTK::ZAxis)),
                                   heavy, SimTK::Transform(SimTK::Rotation(SimTK::Pi / 2, SimTK::ZAxis)));
    SimTK::MobilizedBody::Pin yaw(y, SimTK::Transform(SimTK::Vec3(0, 0, 0.3)), heavy, SimTK::Transform());
    SimTK::MobilizedBody::Pin shoulder(
        yaw, SimTK::Transform(SimTK::Rotation(0.7, SimTK::XAxis), SimTK::Vec3(0.2, 0.1, 0.5)), heavy,
        SimTK::Transform(SimTK::Vec3(0, 0, -0.1)));
    SimTK::MobilizedBody::Pin elbow(shoulder,
                                    SimTK::Transform(SimTK::Rotation(-1.1, SimTK::YAxis), SimTK::Vec3(0.4, 0, 0)),
                                    heavy, SimTK::Transform());
    SimTK::MobilizedBody::Slider finger(elbow, SimTK::Transform(SimTK::Vec3(0.1, 0.05, 0.3)), light,
                                        SimTK::Transform());
    SimTK::MobilizedBody::Pin branch(yaw, SimTK::Transform(SimTK::Vec3(-0.3, 0, 0.2)), heavy,
                                     SimTK::Transform(SimTK::Vec3(0.05, 0, 0)));
    SimTK::MobilizedBody::Free box(matter.Ground(), SimTK::Transform(SimTK::Vec3(1, 0, 0)), heavy,
                                   SimTK::Transform());
    SimTK::MobilizedBody::Pin drawer_like(matter.Ground(), SimTK::Transform(SimTK::Vec3(0, 2, 0)), light,
                                          SimTK::Transform());
    SimTK::MobilizedBody::Free on_box(box, SimTK::Transform(SimTK::Vec3(0, 0, 0.3)), light,
                                      SimTK::Transform());
    const SimTK::MobilizedBody* all[] = {&x,      &y,      &yaw, &shoulder,    &elbow,
                                         &finger, &branch, &box, &drawer_like, &on_box};
    for (const SimTK::MobilizedBody* b : all) bodies.push_back(b->getMobilizedBodyIndex());
  }
};

void randomize(const TestSystem& test, SimTK::State& state, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.5, 1.5);
  for (int i = 0; i < state.getNQ(); ++i) state.updQ()[i] = uniform(rng);
  test.system.realize(state, SimTK::Stage::Time);
  test.matter.normalizeQuaternions(state);
  test.system.realize(state, SimTK::Stage::Position);
}

TEST(TreeStructure, TreesAreTheBodiesHangingFromGround) {
  TestSystem test;
  SimTK::State state = test.system.realizeTopology();
  test.system.realize(state, SimTK::Stage::Model);
  const TreeStructure trees(test.matter, state);
  // The base with its arm and branch; the box with the body on it; the
  // drawer-like pin.
  ASSERT_EQ(trees.getNumTrees(), 3);
  EXPECT_EQ(trees.getTreeU(0).size(), 7u);
  EXPECT_EQ(trees.getTreeU(1).size(), 12u);
  EXPECT_EQ(trees.getTreeU(2).size(), 1u);
  EXPECT_EQ(trees.getTree(SimTK::GroundIndex), -1);
  EXPECT_EQ(trees.getTree(test.bodies[5]), 0);
  EXPECT_EQ(trees.getTree(test.bodies[9]), 1);
  for (int t = 0; t < 3; ++t)
    for (std::size_t k = 0; k < trees.getTreeU(t).size(); ++k) {
      EXPECT_EQ(trees.getTreeOfU(trees.getTreeU(t)[k]), t);
      EXPECT_EQ(trees.getLocalIndexOfU(trees.getTreeU(t)[k]), static_cast<int>(k));
    }
}

TEST(TreeStructure, MassBlocksAreSimbodysMassMatrix) {
  TestSystem test;
  SimTK::State state = test.system.realizeTopology();
  test.system.realize(state, SimTK::Stage::Model);
  TreeStructure trees(test.matter, state);
  for (unsigned seed = 1; seed <= 5; ++seed) {
    randomize(test, state, seed);
    trees.update(state);
    SimTK::Matrix M;
    test.matter.calcM(state, M);
    Eigen::MatrixXd assembled = Eigen::MatrixXd::Zero(state.getNU(), state.getNU());
    for (int t = 0; t < trees.getNumTrees(); ++t) {
      const std::vector<int>& u = trees.getTreeU(t);
      Eigen::MatrixXd block(u.size(), u.size());
      trees.calcMassBlock(t, block);
      for (std::size_t r = 0; r < u.size(); ++r)
        for (std::size_t c = 0; c < u.size(); ++c) assembled(u[r], u[c]) = block(r, c);
    }
    double largest = 0;
    for (int r = 0; r < state.getNU(); ++r)
      for (int c = 0; c < state.getNU(); ++c)
        largest = std::max(largest, std::abs(assembled(r, c) - M(r, c)));
    EXPECT_LT(largest, 1e-12) << "seed " << seed;  // across trees too: zero
  }
}

TEST(TreeStructure, PointJacobiansAreSimbodysStationJacobians) {
  TestSystem test;
  SimTK::State state = test.system.realizeTopology();
  test.system.realize(state, SimTK::Stage::Model);
  TreeStructure trees(test.matter, state);
  randomize(test, state, 7);
  trees.update(state);
  const Eigen::Vector3d point(0.3, -0.2, 0.9);
  for (SimTK::MobilizedBodyIndex body : test.bodies) {
    const SimTK::MobilizedBody& mobod = test.matter.getMobilizedBody(body);
    // Simbody's Jacobian of the station at `point`, in the body frame.
    const SimTK::Vec3 station = mobod.findStationAtGroundPoint(state, SimTK::Vec3(point.x(), point.y(), point.z()));
    SimTK::Matrix JS;
    test.matter.calcStationJacobian(state, body, station, JS);
    const int tree = trees.getTree(body);
    const std::vector<int>& u = trees.getTreeU(tree);
    Eigen::Matrix<double, 3, Eigen::Dynamic> J = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, u.size());
    trees.addPointJacobian(body, point, 2.0, J);
    double largest = 0;
    for (int col = 0; col < state.getNU(); ++col) {
      const int local = trees.getTreeOfU(col) == tree ? trees.getLocalIndexOfU(col) : -1;
      for (int row = 0; row < 3; ++row)
        largest = std::max(largest, std::abs((local >= 0 ? J(row, local) / 2.0 : 0.0) - JS(row, col)));
    }
    EXPECT_LT(largest, 1e-12) << "body " << int(body);
  }
}

}  // namespace
}  // namespace manibench
