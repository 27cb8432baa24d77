// OpenCabinetDoor-v0 / OpenCabinetDrawer-v0 (plugins/open_cabinet): object
// ids and splits, generated URDFs, reset placement, reward stages, success
// flags, the random policy. The generator and reward are checked directly
// (the family's generator library and header); everything else runs the
// real plugin.
#include <gtest/gtest.h>

#include <manibench/config.hpp>
#include <manibench/environment.hpp>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <random>
#include <set>
#include <sstream>

#include "open_cabinet.hpp"
#include "test_env.hpp"

namespace {

namespace mb = manibench;
namespace oc = open_cabinet;
using L = oc::ObservationLayout;

std::unique_ptr<mb::Environment> makeEnv(const std::string& task, const std::vector<std::string>& overrides = {}) {
  return mb::testing::makeEnvironment(task, overrides);
}

std::string cabinetOf(const std::string& object_id) { return object_id.substr(0, object_id.find("_link_")); }

TEST(OpenCabinet, SameIdSameCabinetDifferentIdsDiffer) {
  EXPECT_EQ(oc::generateCabinet("1003").urdf, oc::generateCabinet("1003").urdf);
  EXPECT_EQ(oc::generateCabinet("2101").urdf, oc::generateCabinet("2101").urdf);
  std::set<std::string> urdfs;
  for (const std::string& id : oc::listGeneratedCabinets(oc::TargetKind::kDoor, "train"))
    urdfs.insert(oc::generateCabinet(id).urdf);
  EXPECT_EQ(urdfs.size(), 42u);
  EXPECT_THROW(oc::generateCabinet("1042"), manibench::sdk::Error);
  EXPECT_THROW(oc::generateCabinet("abc"), manibench::sdk::Error);
}

TEST(OpenCabinet, SplitsAreDisjointAndLargeEnough) {
  for (const std::string task : {"OpenCabinetDoor-v0", "OpenCabinetDrawer-v0"}) {
    const auto env = makeEnv(task);
    const std::vector<std::string> train = env->listObjects("train"), test = env->listObjects("test");
    std::set<std::string> train_cabinets, test_cabinets;
    for (const std::string& id : train) train_cabinets.insert(cabinetOf(id));
    for (const std::string& id : test) {
      test_cabinets.insert(cabinetOf(id));
      EXPECT_EQ(std::count(train.begin(), train.end(), id), 0) << id;
    }
    for (const std::string& c : test_cabinets) EXPECT_EQ(train_cabinets.count(c), 0u) << c;
    const bool door = task == std::string("OpenCabinetDoor-v0");
    EXPECT_GE(train_cabinets.size(), door ? 40u : 25u) << task;
    EXPECT_GE(test_cabinets.size(), 10u) << task;
    EXPECT_GT(train.size(), train_cabinets.size()) << task << ": some cabinets have several targets";
  }
}

TEST(OpenCabinet, TestSplitHoldsHandlesAndSizesTrainingNeverShows) {
  std::set<oc::HandleType> train_types, test_types;
  double train_width = 0, test_width = 0;
  for (const oc::TargetKind kind : {oc::TargetKind::kDoor, oc::TargetKind::kDrawer}) {
    for (const std::string& id : oc::listGeneratedCabinets(kind, "train")) {
      const oc::CabinetParams p = oc::getCabinetParams(id);
      train_types.insert(p.handle.type);
      train_width = std::max(train_width, p.width);
      EXPECT_FALSE(oc::generateCabinet(id).getTargets(kind).empty()) << id;
    }
    for (const std::string& id : oc::listGeneratedCabinets(kind, "test")) {
      const oc::CabinetParams p = oc::getCabinetParams(id);
      test_types.insert(p.handle.type);
      test_width = std::max(test_width, p.width);
      EXPECT_FALSE(oc::generateCabinet(id).getTargets(kind).empty()) << id;
    }
  }
  EXPECT_EQ(train_types.count(oc::HandleType::kBoxed), 0u);
  EXPECT_EQ(test_types.count(oc::HandleType::kBoxed), 1u);
  EXPECT_GT(test_width, train_width);
}

TEST(OpenCabinet, HandlesFitTheGripperAndJointRangesAreRealistic) {
  for (const oc::TargetKind kind : {oc::TargetKind::kDoor, oc::TargetKind::kDrawer})
    for (const std::string split : {"train", "test"})
      for (const std::string& id : oc::listGeneratedCabinets(kind, split)) {
        const oc::CabinetParams p = oc::getCabinetParams(id);
        // across the grip the fingers open to 2 x 0.04 m
        EXPECT_LT(p.handle.type == oc::HandleType::kKnob ? p.handle.length : p.handle.thickness, 0.07) << id;
        EXPECT_GE(p.handle.standoff - p.handle.thickness / 2, 0.03) << id << ": room behind the grip";
        for (std::size_t c = 0; c < p.cells.size(); ++c) {
          EXPECT_GE(p.door_limits[c], M_PI / 2 - 1e-9);
          EXPECT_LE(p.door_limits[c], 2 * M_PI / 3 + 1e-9);
        }
      }
}

// Every generated cabinet loads (one target link each, both splits).
TEST(OpenCabinet, GeneratedUrdfsLoad) {
  for (const std::string task : {"OpenCabinetDoor-v0", "OpenCabinetDrawer-v0"}) {
    const auto env = makeEnv(task);
    for (const std::string split : {"train", "test"}) {
      std::set<std::string> seen;
      for (const std::string& id : env->listObjects(split)) {
        if (!seen.insert(cabinetOf(id)).second) continue;
        ASSERT_NO_THROW(env->reset(id, 0)) << task << " " << id;
        const Eigen::VectorXd& obs = env->getObservation();
        EXPECT_TRUE(obs.allFinite()) << id;
        EXPECT_GT(env->getScene().findArticulation("cabinet"), -1);
      }
    }
  }
  EXPECT_THROW(makeEnv("OpenCabinetDoor-v0")->reset("1003_link_9", 0), std::exception);
  EXPECT_THROW(makeEnv("OpenCabinetDoor-v0")->reset("2003_link_0", 0), std::exception);  // drawer cabinet
}

TEST(OpenCabinet, ResetPlacesTheRobotInFrontFacingTheCabinetWithEverythingClosed) {
  const auto env = makeEnv("OpenCabinetDrawer-v0");
  const std::string object = env->listObjects("train").front();
  std::set<double> distances;
  for (uint64_t seed = 0; seed < 12; ++seed) {
    env->reset(object, seed);
    const Eigen::VectorXd s = env->getObservation();
    const Eigen::Vector2d base = s.segment<2>(mb::testing::getObservationOffset(*env, "base_position"));
    const Eigen::Vector2d centre = s.segment<2>(L::kCabinetCenter);
    const double distance = (base - centre).norm();
    EXPECT_GE(distance, 1.6) << seed;
    EXPECT_LE(distance, 1.8) << seed;
    distances.insert(distance);
    // in front (the cabinet faces -x), heading at the cabinet within 0.15 pi
    EXPECT_LT(base.x(), centre.x() - 1.4);
    const Eigen::Vector2d to_cabinet = (centre - base).normalized();
    const double heading = s[mb::testing::getObservationOffset(*env, "base_yaw")];
    EXPECT_GT(to_cabinet.dot(Eigen::Vector2d(std::cos(heading), std::sin(heading))), std::cos(0.16 * M_PI));
    EXPECT_EQ(s[L::kTargetJoint], 0.0) << "closed";
    EXPECT_EQ(s[L::kTargetJoint + 1], 0.0);
    const int cabinet = env->getScene().findArticulation("cabinet");
    EXPECT_TRUE(env->getScene().getJointPositions(cabinet).isZero());
  }
  EXPECT_GE(distances.size(), 10u) << "the placement is randomized";
  mb::testing::expectSameStartAfterAnotherObject(*env, object, env->listObjects("train").back());
}

TEST(OpenCabinet, EveryRewardStageStrictlyExceedsTheOneBefore) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  double best1 = -INFINITY, worst2 = INFINITY, best2 = -INFINITY, worst3 = INFINITY;
  for (int i = 0; i < 20000; ++i) {
    const double v = 3 * u(rng), w = 5 * u(rng);
    // stage 1: far from the handle, any opening below 90 %
    best1 = std::max(best1, oc::calcStagedReward(oc::kContactDistance + 2 * u(rng), 0.9 * u(rng), v, w));
    // stage 2: within contact range, not yet open enough
    const double r2 = oc::calcStagedReward(oc::kContactDistance * u(rng), 0.9 * u(rng) * 0.99999, v, w);
    worst2 = std::min(worst2, r2);
    best2 = std::max(best2, r2);
    // stage 3: open enough, anywhere, moving or not
    worst3 = std::min(worst3, oc::calcStagedReward(3 * u(rng), 0.9 + 0.1 * u(rng), 10 * v, 10 * w));
  }
  EXPECT_LT(best1, worst2);
  EXPECT_LT(best2, worst3);
  // boundary values
  EXPECT_LT(oc::calcStagedReward(oc::kContactDistance, 0.5, 0, 0), oc::calcStagedReward(oc::kContactDistance - 1e-9, 0, 0, 0));
  EXPECT_LT(oc::calcStagedReward(0, 0.9 - 1e-12, 0, 0), oc::calcStagedReward(5, 0.9, 1e3, 1e3));
  // smooth where approach meets opening: no jump at the boundary
  EXPECT_NEAR(oc::calcStagedReward(oc::kContactDistance + 1e-9, 0, 0, 0),
              oc::calcStagedReward(oc::kContactDistance - 1e-9, 0, 0, 0), 1e-8);
  // within a stage: closer, more open, stiller is better
  EXPECT_GT(oc::calcStagedReward(0.5, 0, 0, 0), oc::calcStagedReward(1.0, 0, 0, 0));
  EXPECT_GT(oc::calcStagedReward(0.01, 0.6, 0, 0), oc::calcStagedReward(0.01, 0.3, 0, 0));
  EXPECT_GT(oc::calcStagedReward(0.01, 0.95, 0.0, 0), oc::calcStagedReward(0.01, 0.95, 0.5, 0));
}

TEST(OpenCabinet, SuccessNeedsTheJointOpenAndStillForTenSteps) {
  const auto env = makeEnv("OpenCabinetDrawer-v0");
  const std::string object = env->listObjects("train").front();
  env->reset(object, 3);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(env->getControllerDescription().action_dim);
  mb::StepResult r = env->step(zero);
  ASSERT_EQ(r.flags.size(), 3u);
  EXPECT_FALSE(r.flags[0]);
  EXPECT_NEAR(r.values[0], 0.0, 1e-3) << "open fraction of a closed drawer";
  EXPECT_FALSE(r.success);
  EXPECT_LT(r.reward, -3.0 - 2.0 * oc::kContactDistance) << "far from the handle: stage 1";
  // Open the drawer to 95 % of its range by hand (a test-only state change).
  const int cabinet = env->getScene().findArticulation("cabinet");
  const double upper = env->getObservation()[L::kTargetJoint + 3];
  env->reset(object, 3);
  Eigen::VectorXd q = env->getScene().getJointPositions(cabinet);
  const std::string link = object.substr(object.find("_link_") + 1);
  const int joint = env->getScene().findJoint(cabinet, "joint_" + link.substr(5));
  ASSERT_GE(joint, 0);
  q[joint] = 0.95 * upper;
  env->updScene().setJointPositions(cabinet, q);
  uint32_t steps = 0;
  do {
    r = env->step(zero);
    ++steps;
    EXPECT_TRUE(r.flags[0]) << "step " << steps;
    EXPECT_NEAR(r.values[0], 0.95, 0.02);
    EXPECT_GT(r.reward, -1.2) << "stage 3";
  } while (!r.success && steps < 30);
  EXPECT_TRUE(r.success);
  EXPECT_TRUE(r.flags[1]);
  EXPECT_EQ(steps, 10u) << "success after 10 consecutive open and static steps";
  EXPECT_EQ(r.values[2], 10.0);
}

// Short episodes: random flailing is the slowest thing to simulate.
TEST(OpenCabinet, RandomPolicyNeverSucceeds) {
  for (const std::string task : {"OpenCabinetDoor-v0", "OpenCabinetDrawer-v0"}) {
    const auto env = makeEnv(task, {"episode.max_steps=40"});
    std::mt19937_64 rng(11);
    const std::vector<std::string> objects = env->listObjects("train");
    for (uint64_t seed = 0; seed < 2; ++seed) {
      env->reset(objects[seed * 7 % objects.size()], seed);
      double most_open = 0;
      const mb::StepResult r = mb::testing::runRandomEpisode(
          *env, rng, [&](const mb::StepResult& step) { most_open = std::max(most_open, step.values[0]); });
      EXPECT_FALSE(r.success) << task << " seed " << seed;
      EXPECT_LT(most_open, 0.9) << task << " seed " << seed;
    }
  }
}

TEST(OpenCabinet, ObjectsCommandListsASplit) {
  const mb::testing::CommandResult test =
      mb::testing::runCli({"objects", "OpenCabinetDoor-v0", "--split", "test", "--ids"});
  ASSERT_EQ(test.exit_code, 0) << test.err;
  const mb::testing::CommandResult train = mb::testing::runCli({"objects", "OpenCabinetDoor-v0", "--ids"});
  ASSERT_EQ(train.exit_code, 0) << train.err;
  std::istringstream lines(test.out);
  int count = 0;
  for (std::string id; std::getline(lines, id); ++count) {
    EXPECT_EQ(id.rfind("11", 0), 0u) << id << ": test door cabinets are 1100-1109";
    EXPECT_EQ(train.out.find(id + "\n"), std::string::npos) << id;
  }
  EXPECT_EQ(count, 26);
  const mb::testing::CommandResult table = mb::testing::runCli({"objects", "OpenCabinetDrawer-v0", "--split", "test"});
  EXPECT_NE(table.out.find("target links of 10 articulated objects"), std::string::npos) << table.out;
  const mb::testing::CommandResult bad = mb::testing::runCli({"objects", "OpenCabinetDoor-v0", "--split", "val"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--split must be train or test"), std::string::npos) << bad.err;
}

TEST(OpenCabinet, ExpertRefusesOtherControllers) {
  const auto env = makeEnv("OpenCabinetDrawer-v0");  // default controller mobile_panda
  try {
    mb::PolicyInstance policy(mb::testing::getBuildTreeRegistry(), "open_cabinet_expert", "",
                              env->calcPolicyLayout(mb::ObservationMode::State));
    FAIL() << "expected a refusal";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("mobile_panda_ee"), std::string::npos) << e.what();
  }
}

// The visual modes must not hand a policy the privileged object state (the
// target link, joint and handle): only the robot's own segments remain, with
// the same values as in state mode.
TEST(OpenCabinet, VisualModesPassOnlyTheRobotState) {
  const auto state_env = makeEnv("OpenCabinetDrawer-v0");
  const auto cloud_env = makeEnv("OpenCabinetDrawer-v0", {"observation.mode=pointcloud"});
  const std::string object = state_env->listObjects("test").front();
  state_env->reset(object, 3);
  cloud_env->reset(object, 3);
  const mb::PolicyLayout layout = cloud_env->calcPolicyLayout();
  const uint32_t agent_dim = state_env->getTaskDescription().agent_state_dim;
  EXPECT_LT(agent_dim, state_env->getTaskDescription().observation_dim);
  EXPECT_EQ(layout.observation_dim, agent_dim);
  ASSERT_EQ(cloud_env->getObservation().size(), Eigen::Index(agent_dim));
  EXPECT_EQ(cloud_env->getObservation(), state_env->getObservation().head(agent_dim));
  for (const mb::sdk::Segment& s : layout.observation_segments) {
    EXPECT_LE(s.offset + s.size, agent_dim) << s.name;
    EXPECT_EQ(s.name.find("target"), std::string::npos) << s.name;
    EXPECT_EQ(s.name.find("handle"), std::string::npos) << s.name;
  }
  EXPECT_EQ(state_env->calcPolicyLayout().observation_dim,
            state_env->getTaskDescription().observation_dim);
}

// Supplement B.3 masks on real renders: one world camera 0.45 m in front of
// the target handle looking at it, one 0.5 m above the gripper looking down.
// The handle's pixels carry the handle mask (and target_link: the handle is
// part of that link, as in ManiSkill) but never the robot mask; the gripper's
// pixels carry the robot mask only.
std::string calcProbeCamera(const std::string& name, const Eigen::Vector3d& eye,
                            const Eigen::Vector3d& direction) {
  const Eigen::Vector3d d = direction.normalized();
  // rpy as in URDF (R = Rz(yaw) Ry(pitch)), camera looking along its +x.
  const double pitch = -std::asin(d.z());
  const double yaw = std::atan2(d.y(), d.x());
  std::ostringstream out;
  out.precision(17);
  out << "{name: " << name << ", pose: {position: [" << eye.x() << ", " << eye.y() << ", "
      << eye.z() << "], rpy: [0, " << pitch << ", " << yaw
      << "]}, width: 48, height: 48, fovy: 0.5, near: 0.05}";
  return out.str();
}

TEST(OpenCabinet, HandleAndRobotMasksCoverTheirPixels) {
  for (const std::string task : {"OpenCabinetDrawer-v0", "OpenCabinetDoor-v0"}) {
    SCOPED_TRACE(task);
    const auto state_env = makeEnv(task);
    const std::string object = state_env->listObjects("test").front();
    state_env->reset(object, 0);
    const Eigen::VectorXd s = state_env->getObservation();
    const Eigen::Vector3d handle = s.segment<3>(L::kHandlePose);
    const Eigen::Quaterniond handle_rotation(s[L::kHandlePose + 3], s[L::kHandlePose + 4],
                                             s[L::kHandlePose + 5], s[L::kHandlePose + 6]);
    const Eigen::Vector3d front = handle_rotation * Eigen::Vector3d::UnitX();
    const Eigen::Vector3d tcp = s.segment<3>(mb::testing::getObservationOffset(*state_env, "tcp_pose"));
    const std::string cameras =
        "cameras=[" + calcProbeCamera("at_handle", handle + 0.45 * front, -front) + ", " +
        calcProbeCamera("at_gripper", tcp + Eigen::Vector3d(0.02, 0, 0.5),
                        Eigen::Vector3d(-0.02, 0, -0.5)) +
        "]";
    const auto env = makeEnv(task, {"observation.mode=rgbd", cameras});
    env->reset(object, 0);
    const mb::VisualObservation& v = env->getVisualObservation();
    ASSERT_EQ(v.camera_count, 2u);
    ASSERT_EQ(v.mask_count, 3u);  // handle, target_link, robot
    const uint32_t k = v.mask_count, cams = v.camera_count;
    auto mask = [&](uint32_t camera, uint32_t row, uint32_t col, uint32_t m) {
      return v.masks[(row * v.width + col) * k * cams + k * camera + m] != 0;
    };
    int handle_pixels = 0, gripper_robot_pixels = 0;
    for (uint32_t row = 0; row < v.height; ++row)
      for (uint32_t col = 0; col < v.width; ++col) {
        if (mask(0, row, col, 0)) {
          ++handle_pixels;
          EXPECT_TRUE(mask(0, row, col, 1)) << "handle pixel outside its link";
          EXPECT_FALSE(mask(0, row, col, 2)) << "handle pixel in the robot mask";
        }
        gripper_robot_pixels += mask(1, row, col, 2);
        EXPECT_FALSE(mask(1, row, col, 0) && mask(1, row, col, 2));
      }
    EXPECT_GT(handle_pixels, 20) << "the handle camera sees its handle";
    bool centre_handle = false;
    for (uint32_t row = v.height / 2 - 3; row <= v.height / 2 + 3; ++row)
      for (uint32_t col = v.width / 2 - 3; col <= v.width / 2 + 3; ++col)
        centre_handle = centre_handle || mask(0, row, col, 0);
    EXPECT_TRUE(centre_handle) << "the handle lies at the image centre";
    EXPECT_TRUE(mask(1, v.height / 2, v.width / 2, 2)) << "the gripper is at the image centre";
    EXPECT_FALSE(mask(1, v.height / 2, v.width / 2, 0));
    EXPECT_GT(gripper_robot_pixels, 100);
  }
}

}  // namespace
