// kit::urdf::inspectUrdf: the joint vector a plugin can know before its scene
// exists must be the one the host builds. Checked against the host's own
// Scene on the robots, the PartNet fixture and a file written to exercise
// the ordering rules (out-of-order children, fixed joints, planar, limits).
#include <manibench/scene.hpp>
#include <manibench/kit/urdf.hpp>

#include <gtest/gtest.h>

#include <string>

#include "test_support.hpp"

namespace manibench {
namespace {

using testing::catchMessage;
using testing::expectMentions;

// The SDK's reading of `path` equals the host's joint vector of it.
void expectSameAsTheHost(const kit::urdf::UrdfJoints& inspected, Scene& scene, int articulation) {
  const std::vector<JointDescription>& host = scene.getJoints(articulation);
  ASSERT_EQ(inspected.joints.size(), host.size());
  for (std::size_t i = 0; i < host.size(); ++i) {
    SCOPED_TRACE("joint " + std::to_string(i) + " " + host[i].name);
    EXPECT_EQ(inspected.joints[i].name, host[i].name);
    // Both number joint types as abi.h's MB_JOINT_*.
    EXPECT_EQ(static_cast<int>(inspected.joints[i].type), static_cast<int>(host[i].type))
        << kit::urdf::toString(inspected.joints[i].type);
    EXPECT_EQ(inspected.joints[i].lower, host[i].lower);
    EXPECT_EQ(inspected.joints[i].upper, host[i].upper);
  }
  EXPECT_EQ(inspected.root_link, scene.getLinkName(scene.getRootLink(articulation)));
}

TEST(UrdfJoints, TheRobotsAndAPartNetObjectGiveTheHostsJointVector) {
  const std::string source = MANIBENCH_TEST_SOURCE_DIR;
  for (const std::string& path : {source + "/assets/robots/mobile_panda_single.urdf",
                                 source + "/assets/robots/mobile_panda_dual.urdf",
                                 source + "/tests/fixtures/partnet_mini/100001/mobility.urdf"}) {
    SCOPED_TRACE(path);
    Scene scene;
    const int a = scene.addUrdfFile(path, "a", Pose(), true);
    scene.finalize();
    const kit::urdf::UrdfJoints inspected = kit::urdf::inspectUrdfFile(path);
    EXPECT_GT(inspected.joints.size(), 1u);
    expectSameAsTheHost(inspected, scene, a);
  }
}

TEST(UrdfJoints, OrderFixedJointsPlanarAndLimitsFollowTheHostsRules) {
  const std::string box = "<collision><geometry><box size=\"0.1 0.1 0.1\"/></geometry></collision>";
  auto link = [&](const std::string& name) { return "<link name=\"" + name + "\">" + box + "</link>\n"; };
  auto joint = [](const std::string& name, const std::string& type, const std::string& parent,
                  const std::string& child, const std::string& limit) {
    return "<joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent + "\"/><child link=\"" +
           child + "\"/><axis xyz=\"0 0 1\"/>" + limit + "</joint>\n";
  };
  const std::string limited = "<limit lower=\"-1\" upper=\"2\" effort=\"1\" velocity=\"1\"/>";
  const std::string equal = "<limit lower=\"0\" upper=\"0\" effort=\"1\" velocity=\"1\"/>";
  // Links listed out of order; base's children in file order z, a, m; a
  // fixed joint whose child has a joint; a planar base.
  const std::string urdf = "<robot name=\"r\">" + link("c") + link("world") + link("base") + link("z") + link("a") +
                           link("m") + link("m2") + joint("zj", "prismatic", "base", "z", limited) +
                           joint("planar", "planar", "world", "base", "") +
                           joint("aj", "continuous", "base", "a", limited) +
                           joint("mj", "fixed", "base", "m", "") + joint("m2j", "revolute", "m", "m2", equal) +
                           joint("cj", "revolute", "a", "c", limited) + "</robot>";
  Scene scene;
  const int r = scene.addUrdfString(urdf, "", "r", Pose(), true);
  scene.finalize();
  const kit::urdf::UrdfJoints inspected = kit::urdf::inspectUrdf(urdf, "ordering.urdf");
  expectSameAsTheHost(inspected, scene, r);
  ASSERT_EQ(inspected.joints.size(), 7u);
  EXPECT_EQ(inspected.joints[0].name, "planar_x");
  EXPECT_EQ(inspected.find("cj"), 5u);
  expectMentions(catchMessage<sdk::Error>([&] { inspected.find("nope"); }), {"no joint 'nope'", "planar_yaw"});
}

TEST(UrdfJoints, BadFilesAreRefusedNamingThem) {
  expectMentions(catchMessage<sdk::Error>([] { kit::urdf::inspectUrdf("<robot name=\"r\">", "cut.urdf"); }),
                 {"cut.urdf:1", "not valid XML"});
  expectMentions(catchMessage<sdk::Error>([] { kit::urdf::inspectUrdfFile("/no/such.urdf"); }),
                 {"/no/such.urdf", "cannot read"});
  expectMentions(catchMessage<sdk::Error>([] {
                   kit::urdf::inspectUrdf("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/></robot>", "two.urdf");
                 }),
                 {"two.urdf", "expected one root link, found 2"});
  expectMentions(catchMessage<sdk::Error>([] {
                   kit::urdf::inspectUrdf("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" "
                                          "type=\"floating\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>",
                                          "float.urdf");
                 }),
                 {"float.urdf", "joint 'j'", "'floating'"});
  expectMentions(
      catchMessage<sdk::Error>([] {
        kit::urdf::inspectUrdf("<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/><joint name=\"j\" type=\"revolute\">"
                         "<parent link=\"a\"/><child link=\"b\"/><limit lower=\"x\" upper=\"1\"/></joint></robot>",
                         "nan.urdf");
      }),
      {"nan.urdf", "joint 'j'", "lower=\"x\"", "not a number"});
}

}  // namespace
}  // namespace manibench
