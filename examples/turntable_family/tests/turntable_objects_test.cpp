// The Turntable catalog: the splits are disjoint and cover the nine
// objects, every id resolves, and its URDF carries the object's mass.
#include "turntable.hpp"

#include <gtest/gtest.h>

#include <set>
#include <sstream>

namespace turntable {
namespace {

TEST(TurntableObjects, SplitsAreDisjointAndComplete) {
  const std::vector<std::string> train = listArms("train"), test = listArms("test");
  EXPECT_EQ(train.size(), 6u);
  EXPECT_EQ(test.size(), 3u);
  std::set<std::string> all(train.begin(), train.end());
  all.insert(test.begin(), test.end());
  EXPECT_EQ(all.size(), 9u);
  EXPECT_THROW(listArms("validation"), sdk::Error);
}

TEST(TurntableObjects, EveryIdResolvesToItsUrdf) {
  for (const char* split : {"train", "test"})
    for (const std::string& id : listArms(split)) {
      const Arm arm = getArm(id);
      EXPECT_EQ(arm.id, id);
      std::ostringstream mass;
      mass.precision(17);
      mass << "<mass value='" << arm.mass << "'/>";
      EXPECT_NE(makeArmUrdf(arm).find(mass.str()), std::string::npos) << makeArmUrdf(arm);
    }
  EXPECT_THROW(getArm("arm9_mass9"), sdk::Error);
}

}  // namespace
}  // namespace turntable
