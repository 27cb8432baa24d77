// The SDK's PartNet-Mobility reader (sdk/include/manibench/kit/partnet.hpp)
// on the hand-made fixture tests/fixtures/partnet_mini and on broken copies
// of it: folders and splits, the URDF as a kinematic model, semantics,
// completed and scaled URDF text (which the real scene must load), and
// errors that name the file and the element.
#include <manibench/scene.hpp>
#include <manibench/kit/partnet.hpp>

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
namespace partnet = manibench::kit::partnet;
using manibench::sdk::Error;

const std::string kMini = std::string(MANIBENCH_TEST_SOURCE_DIR) + "/tests/fixtures/partnet_mini";

using manibench::testing::readFile;

// A copy of partnet_mini in a fresh temporary folder, to break.
struct BrokenCopy : manibench::testing::FixtureCopy {
  BrokenCopy() : FixtureCopy("partnet_mini") {}
};

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PartNet, ListsObjectFoldersAndSplits) {
  EXPECT_EQ(partnet::listObjectIds(kMini), (std::vector<std::string>{"100001", "100002"}));
  EXPECT_EQ(partnet::listObjectIds(kMini, "train"), std::vector<std::string>{"100001"});
  EXPECT_EQ(partnet::listObjectIds(kMini, "test"), std::vector<std::string>{"100002"});
  EXPECT_THROW(partnet::listObjectIds(kMini, "val"), Error);
  EXPECT_NE(errorOf([] { partnet::listObjectIds(kMini + "/nothing"); }).find("is not a folder"), std::string::npos);
  BrokenCopy copy;
  std::ofstream(copy.file("test.txt")) << "100002\n\n100003\n";
  const std::string error = errorOf([&] { partnet::listObjectIds(copy.folder(), "test"); });
  EXPECT_NE(error.find("test.txt:3: no object folder '100003'"), std::string::npos) << error;
}

TEST(PartNet, ReadsTheUrdfAsAKinematicModel) {
  const partnet::Object o = partnet::loadObject(kMini, "100001");
  EXPECT_EQ(o.id, "100001");
  EXPECT_EQ(o.getRoot().name, "base");
  ASSERT_EQ(o.links.size(), 4u);
  ASSERT_EQ(o.joints.size(), 3u);
  // parents before children
  for (std::size_t i = 1; i < o.links.size(); ++i) {
    const partnet::Joint* j = o.findParentJoint(o.links[i].name);
    ASSERT_NE(j, nullptr);
    EXPECT_LT(std::find_if(o.links.begin(), o.links.end(), [&](const partnet::Link& l) { return l.name == j->parent; }) -
                  o.links.begin(),
              std::ptrdiff_t(i));
  }
  const partnet::Joint* door = o.findJoint("joint_0");
  ASSERT_NE(door, nullptr);
  EXPECT_EQ(door->type, partnet::JointType::kRevolute);
  EXPECT_EQ(door->parent, "link_2");
  EXPECT_EQ(door->child, "link_0");
  EXPECT_TRUE(door->axis.isApprox(Eigen::Vector3d(0, -1, 0)));
  EXPECT_TRUE(door->limited);
  EXPECT_DOUBLE_EQ(door->upper, 1.57);
  EXPECT_TRUE(door->origin.translation().isApprox(Eigen::Vector3d(-0.295, 0, 0.22)));
  EXPECT_EQ(o.findJoint("joint_1")->type, partnet::JointType::kPrismatic);
  EXPECT_DOUBLE_EQ(o.findJoint("joint_1")->upper, 0.3);
  EXPECT_FALSE(o.findJoint("joint_2")->isMovable());
  // Y-up turned Z-up by the base joint: the body link's y axis is world z.
  const auto pose = o.calcLinkPoses();
  EXPECT_TRUE((pose.at("link_2").linear() * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_TRUE(pose.at("link_0").isApprox(pose.at("link_2") * door->origin));
  // visuals, named as PartNet names them, with their mesh vertices
  const partnet::Link* drawer = o.findLink("link_1");
  ASSERT_EQ(drawer->visuals.size(), 3u);
  EXPECT_EQ(drawer->visuals[2].name, "handle-7");
  EXPECT_EQ(drawer->visuals[2].geometry.kind, partnet::Geometry::Kind::kMesh);
  EXPECT_EQ(drawer->collisions.size(), 3u);
  EXPECT_FALSE(o.calcShapePoints(drawer->visuals[2]).empty());
  const partnet::Bounds all = o.calcVisualBounds();
  EXPECT_NEAR(all.extent().z(), 0.8, 1e-6) << "the cabinet is 0.8 m tall once Z-up";
  // semantics.txt
  ASSERT_EQ(o.semantics.size(), 3u);
  EXPECT_EQ(o.findSemantic("link_0")->kind, "hinge");
  EXPECT_EQ(o.findSemantic("link_1")->label, "drawer");
  EXPECT_EQ(o.findSemantic("base"), nullptr);
}

TEST(PartNet, CompletesLimitsAndTheSceneLoadsTheText) {
  const partnet::Object o = partnet::loadObject(kMini, "100001");
  EXPECT_EQ(readFile(kMini + "/100001/mobility.urdf").find("effort"), std::string::npos);
  const std::regex limit(R"(<limit[^>]*>)");
  int limits = 0;
  for (auto it = std::sregex_iterator(o.urdf.begin(), o.urdf.end(), limit); it != std::sregex_iterator(); ++it) {
    ++limits;
    EXPECT_NE(it->str().find("effort=\"100\""), std::string::npos) << it->str();
    EXPECT_NE(it->str().find("velocity=\"1\""), std::string::npos) << it->str();
  }
  EXPECT_EQ(limits, 2);
  manibench::Scene scene;
  scene.addGround(0);
  const int a = scene.addUrdfString(o.urdf, o.dir, "cabinet", manibench::Pose(), true);
  scene.finalize();
  EXPECT_EQ(scene.getJoints(a).size(), 2u);
  EXPECT_GE(scene.findJoint(a, "joint_1"), 0);
}

TEST(PartNet, ScalesEveryLength) {
  const partnet::Object full = partnet::loadObject(kMini, "100001");
  const partnet::Object half = partnet::loadObject(kMini, "100001", 0.5);
  EXPECT_EQ(half.scale, 0.5);
  EXPECT_DOUBLE_EQ(half.findJoint("joint_1")->upper, 0.15) << "prismatic limits are lengths";
  EXPECT_DOUBLE_EQ(half.findJoint("joint_0")->upper, 1.57) << "revolute limits are not";
  EXPECT_TRUE(half.findJoint("joint_0")->origin.translation().isApprox(
      0.5 * full.findJoint("joint_0")->origin.translation()));
  const partnet::Bounds a = full.calcVisualBounds(), b = half.calcVisualBounds();
  EXPECT_TRUE(b.lo.isApprox(0.5 * a.lo, 1e-9));
  EXPECT_TRUE(b.hi.isApprox(0.5 * a.hi, 1e-9));
  EXPECT_NE(half.urdf.find("scale=\"0.5 0.5 0.5\""), std::string::npos);
  // The scene agrees: half the drawer's travel.
  manibench::Scene scene;
  const int id = scene.addUrdfString(half.urdf, half.dir, "cabinet", manibench::Pose(), true);
  scene.finalize();
  EXPECT_DOUBLE_EQ(scene.getJoints(id)[std::size_t(scene.findJoint(id, "joint_1"))].upper, 0.15);
  EXPECT_THROW(partnet::loadObject(kMini, "100001", 0.0), Error);
}

TEST(PartNet, CorruptLimitNumbersKeepTheirLeadingNumber) {
  BrokenCopy copy;
  copy.replace("100001/mobility.urdf", "upper=\"1.57\"", "upper=\"1.57.0\"");
  const partnet::Object o = partnet::loadObject(copy.folder(), "100001");
  EXPECT_DOUBLE_EQ(o.findJoint("joint_0")->upper, 1.57);
  EXPECT_EQ(o.urdf.find("1.57.0"), std::string::npos) << "rewritten clean for the host's URDF reader";
}

// PartNet's joint kinds in full (slider+: a seat on a slider with a hinge
// on it), and older files whose visuals are unnamed: result.json's part of
// each mesh names them, in the URDF the host reads too.
TEST(PartNet, ReadsSliderPlusAndNamesUnnamedVisualsFromResultJson) {
  BrokenCopy copy;
  copy.replace("100001/semantics.txt", "link_1 slider drawer", "link_1 slider+ drawer");
  copy.replace("100001/mobility.urdf", "<visual name=\"handle-4\">", "<visual>");
  std::ofstream(copy.file("100001/result.json"))
      << R"([{"text": "Cabinet", "name": "cabinet", "children": [{"text": "Door", "name": "door", "children": [)"
      << R"({"text": "Handle", "name": "handle", "objs": ["original-door_handle"]}]}]}])";
  const partnet::Object o = partnet::loadObject(copy.folder(), "100001");
  ASSERT_NE(o.findSemantic("link_1"), nullptr);
  EXPECT_EQ(o.findSemantic("link_1")->kind, "slider+");
  bool named = false;
  for (const partnet::Link& l : o.links)
    for (const partnet::Shape& v : l.visuals) named |= v.name == "handle";
  EXPECT_TRUE(named);
  EXPECT_NE(o.urdf.find("<visual name=\"handle\""), std::string::npos);
  std::ofstream(copy.file("100001/result.json")) << "[{\"text\": ";
  const std::string error = errorOf([&] { partnet::loadObject(copy.folder(), "100001"); });
  EXPECT_NE(error.find("result.json:1"), std::string::npos) << error;
}

// A folder with ManiSkill's decomposed URDFs is read from those:
// mobility_cvx.urdf (ManiSkill2, whose folders hold only it) before
// mobility_fixed.urdf (v1) before mobility.urdf.
TEST(PartNet, PrefersTheDecomposedUrdfs) {
  BrokenCopy copy;
  const std::string urdf = readFile(copy.file("100001/mobility.urdf"));
  std::ofstream(copy.file("100001/mobility_fixed.urdf")) << std::regex_replace(urdf, std::regex("joint_0"), "fixed_0");
  EXPECT_NE(partnet::loadObject(copy.folder(), "100001").findJoint("fixed_0"), nullptr);
  std::ofstream(copy.file("100001/mobility_cvx.urdf")) << std::regex_replace(urdf, std::regex("joint_0"), "cvx_0");
  const partnet::Object o = partnet::loadObject(copy.folder(), "100001");
  EXPECT_NE(o.findJoint("cvx_0"), nullptr);
  EXPECT_EQ(o.urdf_file, copy.file("100001/mobility_cvx.urdf"));
  std::filesystem::remove(copy.file("100002/mobility.urdf"));
  EXPECT_EQ(partnet::listObjectIds(copy.folder()), std::vector<std::string>{"100001"});
  std::ofstream(copy.file("100002/mobility_cvx.urdf")) << readFile(copy.file("100001/mobility.urdf"));
  EXPECT_EQ(partnet::listObjectIds(copy.folder()), (std::vector<std::string>{"100001", "100002"}));
}

TEST(PartNet, BadInputNamesTheFileAndTheElement) {
  EXPECT_NE(errorOf([] { partnet::loadObject(kMini, "999"); }).find("no object '999'"), std::string::npos);
  struct Case {
    std::string file, from, to, expected;
  };
  const std::vector<Case> cases = {
      {"100001/mobility.urdf", "upper=\"1.57\"", "upper=\"wide\"", "joint 'joint_0' <limit upper>: 'wide' is not a number"},
      {"100001/mobility.urdf", "type=\"prismatic\"", "type=\"screw\"", "joint 'joint_1' has type 'screw'"},
      {"100001/mobility.urdf", "<axis xyz=\"0 0 1\"/>", "<axis xyz=\"0 0\"/>", "joint 'joint_1' <axis xyz>: expected 3 numbers"},
      {"100001/mobility.urdf", "<parent link=\"link_2\"/>\n    <limit lower=\"0\" upper=\"1.57\"/>",
       "<parent link=\"link_9\"/>\n    <limit lower=\"0\" upper=\"1.57\"/>", "names link 'link_9', which is not there"},
      {"100001/mobility.urdf", "</robot>", "", "mobility.urdf:"},
      {"100001/semantics.txt", "link_1 slider drawer", "link_1 drawer", "semantics.txt:2: expected"},
      {"100001/semantics.txt", "link_2 heavy", "link_7 heavy", "link 'link_7' is not in"},
  };
  for (const Case& c : cases) {
    BrokenCopy copy;
    copy.replace(c.file, c.from, c.to);
    const std::string error = errorOf([&] { partnet::loadObject(copy.folder(), "100001"); });
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.to << " -> " << error;
    EXPECT_NE(error.find(copy.folder()), std::string::npos) << "names the file: " << error;
  }
  BrokenCopy copy;
  std::ofstream(copy.file("100001/textured_objs/original-door_handle.obj")) << "v 1 2\n";
  const partnet::Object o = partnet::loadObject(copy.folder(), "100001");
  const std::string error = errorOf([&] { o.calcVisualBounds(); });
  EXPECT_NE(error.find("original-door_handle.obj:1: bad vertex line"), std::string::npos) << error;
}

}  // namespace
