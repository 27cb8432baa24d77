// Expert episodes of OpenCabinetDoor-v0 / OpenCabinetDrawer-v0 with the
// mobile_panda_ee controller (plugins/open_cabinet), on train and test
// objects and on the PartNet-Mobility fixture (tests/fixtures/partnet_mini,
// modelled in metres: task.partnet_scale=1 keeps it at that size).
// The full success-rate sweep is docs/tasks/open_cabinet.md's table.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>

#include "test_env.hpp"

namespace {

namespace mb = manibench;

using mb::testing::ExpertSetup;

ExpertSetup makeExpertSetup(const std::string& task, const std::vector<std::string>& overrides = {}) {
  return mb::testing::makeExpertSetup(task, "open_cabinet_expert", overrides);
}

void expectExpertSucceeds(ExpertSetup& s, const std::string& object, uint64_t seed) {
  const mb::EpisodeResult r = mb::runEpisode(*s.env, *s.expert, object, seed);
  EXPECT_TRUE(r.success) << object << " seed " << seed << ": " << r.steps << " steps, opened "
                         << r.final_values[0] << " of the range";
  EXPECT_LT(r.steps, 200u) << object;
  EXPECT_GE(r.final_values[0], 0.9) << object;
}

TEST(OpenCabinetScenario, ExpertOpensDrawersOfBothSplits) {
  ExpertSetup s = makeExpertSetup("OpenCabinetDrawer-v0");
  expectExpertSucceeds(s, s.env->listObjects("train")[3], 1);
  expectExpertSucceeds(s, s.env->listObjects("test")[5], 2);
}

TEST(OpenCabinetScenario, ExpertOpensDoorsOfBothSplits) {
  ExpertSetup s = makeExpertSetup("OpenCabinetDoor-v0");
  expectExpertSucceeds(s, "1028_link_1", 0);
  expectExpertSucceeds(s, s.env->listObjects("test")[0], 1);
}

TEST(OpenCabinetScenario, SameSeedSameTrajectory) {
  ExpertSetup a = makeExpertSetup("OpenCabinetDrawer-v0");
  ExpertSetup b = makeExpertSetup("OpenCabinetDrawer-v0");
  const std::string object = a.env->listObjects("test")[1];
  const mb::EpisodeResult ra = mb::runEpisode(*a.env, *a.expert, object, 4);
  const mb::EpisodeResult rb = mb::runEpisode(*b.env, *b.expert, object, 4);
  EXPECT_EQ(ra.steps, rb.steps);
  EXPECT_EQ(ra.total_reward, rb.total_reward);
  EXPECT_EQ(a.env->getObservation(), b.env->getObservation());
}

TEST(OpenCabinetScenario, PartNetFolderReplacesTheGenerator) {
  const std::string dir = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/tests/fixtures/partnet_mini";
  ExpertSetup s = makeExpertSetup("OpenCabinetDrawer-v0", {"task.partnet_dir=" + dir, "task.partnet_scale=1"});
  EXPECT_EQ(s.env->listObjects("train"), std::vector<std::string>{"100001_link_1"});
  EXPECT_EQ(s.env->listObjects("test"), std::vector<std::string>{"100002_link_1"});
  ExpertSetup d = makeExpertSetup("OpenCabinetDoor-v0", {"task.partnet_dir=" + dir, "task.partnet_scale=1"});
  EXPECT_EQ(d.env->listObjects("train"), std::vector<std::string>{"100001_link_0"});
  // The handle's grasp frame faces the robot (-x) and sits in front of the
  // cabinet, the cabinet stands on the ground.
  d.env->reset("100001_link_0", 0);
  const Eigen::VectorXd o = d.env->getObservation();
  const Eigen::Quaterniond handle(o[72], o[73], o[74], o[75]);
  EXPECT_GT((handle * Eigen::Vector3d::UnitX()).dot(-Eigen::Vector3d::UnitX()), 0.99);
  EXPECT_LT(o[69], o[77] - 0.2) << "handle in front of the cabinet centre";
  EXPECT_NEAR(o[79], 0.405, 1e-6) << "centre height: half of 0.8 m, the bottom 5 mm above the ground";
  EXPECT_NEAR(o[76], 0.08, 1e-6) << "half the grip length";
  expectExpertSucceeds(s, "100001_link_1", 1);
  expectExpertSucceeds(d, "100001_link_0", 1);  // 5 of seeds 0-5 succeed (3 with the fingers wide open): mesh handles slip more
}

// A flap hinged at its bottom edge turns its front below the hinge, 1 cm
// above the ground: at B.4's 90 % (81 degrees) its handle would stand in
// the ground, so it is no target, and the listing says why. Hinged at its
// top edge the same flap is a target, and the expert opens it (the lift
// follows the handle up; the base keeps facing the cabinet).
TEST(OpenCabinetScenario, AFlapThatWouldOpenIntoTheGroundIsNoTargetAndOneHingedAtItsTopOpens) {
  mb::testing::FixtureCopy bottom("partnet_mini");
  mb::testing::makeFlap(bottom, true);
  ::testing::internal::CaptureStderr();
  ExpertSetup b = makeExpertSetup("OpenCabinetDoor-v0", {"task.partnet_dir=" + bottom.folder(), "task.partnet_scale=1"});
  EXPECT_TRUE(b.env->listObjects("train").empty());
  ExpertSetup drawer = makeExpertSetup("OpenCabinetDrawer-v0", {"task.partnet_dir=" + bottom.folder(), "task.partnet_scale=1"});
  EXPECT_EQ(drawer.env->listObjects("train"), std::vector<std::string>{"100001_link_1"});
  const std::string warnings = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(warnings.find("OpenCabinetDoor: PartNet cabinet 100001 (" + bottom.folder() + "/100001): leaving out link_0: it reaches "),
            std::string::npos) << warnings;
  EXPECT_NE(warnings.find(" cm into the ground before it opens 90 %"), std::string::npos) << warnings;
  EXPECT_EQ(warnings.find("OpenCabinetDrawer: PartNet cabinet 100001"), std::string::npos) << "a door is no drawer: " << warnings;

  mb::testing::FixtureCopy top("partnet_mini");
  mb::testing::makeFlap(top, false);
  ::testing::internal::CaptureStderr();
  ExpertSetup t = makeExpertSetup("OpenCabinetDoor-v0", {"task.partnet_dir=" + top.folder(), "task.partnet_scale=1"});
  EXPECT_EQ(t.env->listObjects("train"), std::vector<std::string>{"100001_link_0"});
  EXPECT_EQ(::testing::internal::GetCapturedStderr().find("leaving out"), std::string::npos);
  expectExpertSucceeds(t, "100001_link_0", 1);
}

// A user's folder with test objects only (every id in test.txt): the test
// split runs; only the train split is empty.
TEST(OpenCabinetScenario, APartNetFolderOfTestObjectsOnlyRuns) {
  const mb::testing::FixtureCopy copy("partnet_mini");
  const std::filesystem::path dir = copy.folder();
  std::ofstream(dir / "test.txt") << "100001\n100002\n";
  ExpertSetup s = makeExpertSetup("OpenCabinetDrawer-v0", {"task.partnet_dir=" + dir.string(), "task.partnet_scale=1"});
  EXPECT_TRUE(s.env->listObjects("train").empty());
  EXPECT_EQ(s.env->listObjects("test"), (std::vector<std::string>{"100001_link_1", "100002_link_1"}));
  s.env->reset("100002_link_1", 0);
  EXPECT_EQ(s.env->getObjectId(), "100002_link_1");
}

// A user's folder: semantics.txt decides what a handled part is, and a
// malformed object is skipped with its reason while the others load.
TEST(OpenCabinetScenario, PartNetSemanticsDecideTargetsAndABrokenObjectIsSkipped) {
  const mb::testing::FixtureCopy copy("partnet_mini");
  const std::filesystem::path dir = copy.folder();
  // 100001's hinged part is a lid now (it keeps its handle): no door.
  std::ofstream(dir / "100001" / "semantics.txt") << "link_0 hinge lid\nlink_1 slider drawer\nlink_2 heavy cabinet_body\n";
  std::filesystem::create_directories(dir / "100003");
  std::ofstream(dir / "100003" / "mobility.urdf") << "<robot name=\"broken\">\n  <link name=\"base\">\n";

  ::testing::internal::CaptureStderr();
  ExpertSetup drawer = makeExpertSetup("OpenCabinetDrawer-v0", {"task.partnet_dir=" + dir.string(), "task.partnet_scale=1"});
  const std::vector<std::string> drawers = drawer.env->listObjects("train");
  ExpertSetup door = makeExpertSetup("OpenCabinetDoor-v0", {"task.partnet_dir=" + dir.string(), "task.partnet_scale=1"});
  const std::vector<std::string> doors = door.env->listObjects("train");
  const std::vector<std::string> test_doors = door.env->listObjects("test");
  const std::string warnings = ::testing::internal::GetCapturedStderr();

  EXPECT_EQ(drawers, (std::vector<std::string>{"100001_link_1"}));
  EXPECT_TRUE(doors.empty()) << doors.front();
  EXPECT_EQ(test_doors, (std::vector<std::string>{"100002_link_0"}));
  EXPECT_NE(warnings.find("skipping PartNet cabinet 100003 (" + (dir / "100003").string() + ")"), std::string::npos)
      << warnings;
  EXPECT_NE(warnings.find("mobility.urdf"), std::string::npos) << warnings;
  EXPECT_EQ(warnings.find("100001"), std::string::npos) << "100001 has a drawer: " << warnings;
  // The skipped object's fixed-object environment says why.
  EXPECT_THROW(drawer.env->reset("100003_link_1", 0), std::exception);
}

// An object the kit reads but whose scene the host refuses (here a
// collision mesh that is not there, which only the scene loads) is skipped
// when the environment is made, with the file in the reason; the next
// object is built instead and the listing leaves the first out.
TEST(OpenCabinetScenario, AnObjectWhoseSceneDoesNotBuildIsSkipped) {
  mb::testing::FixtureCopy copy("partnet_mini");
  const std::filesystem::path dir = copy.folder();
  std::filesystem::remove(dir / "test.txt");
  copy.replace("100001/mobility.urdf", "<visual name=\"cabinet_body-1\">",
               "<collision><geometry><mesh filename=\"textured_objs/missing.obj\"/></geometry></collision>"
               "<visual name=\"cabinet_body-1\">");
  ::testing::internal::CaptureStderr();
  ExpertSetup s = makeExpertSetup("OpenCabinetDrawer-v0", {"task.partnet_dir=" + dir.string(), "task.partnet_scale=1"});
  const std::string warnings = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(s.env->getObjectId(), "100002_link_1");
  ASSERT_EQ(s.env->getSkippedObjects().count("100001_link_1"), 1u);
  EXPECT_NE(s.env->getSkippedObjects().at("100001_link_1").find("missing.obj"), std::string::npos)
      << s.env->getSkippedObjects().at("100001_link_1");
  EXPECT_NE(warnings.find("skipping object 100001_link_1"), std::string::npos) << warnings;
  EXPECT_EQ(s.env->listObjects("train"), std::vector<std::string>{"100002_link_1"});
  expectExpertSucceeds(s, "100002_link_1", 1);
}

}  // namespace
