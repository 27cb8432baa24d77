// The Slider catalog: the splits are disjoint and cover the nine objects,
// every id resolves, and its URDF carries the object's numbers.
#include "slider.hpp"

#include <gtest/gtest.h>

#include <set>

namespace slider {
namespace {

TEST(SliderObjects, SplitsAreDisjointAndComplete) {
  const std::vector<std::string> train = listRails("train"), test = listRails("test");
  EXPECT_EQ(train.size(), 6u);
  EXPECT_EQ(test.size(), 3u);
  std::set<std::string> all(train.begin(), train.end());
  all.insert(test.begin(), test.end());
  EXPECT_EQ(all.size(), 9u);
  EXPECT_THROW(listRails("validation"), sdk::Error);
}

TEST(SliderObjects, EveryIdResolvesToItsUrdf) {
  for (const char* split : {"train", "test"})
    for (const std::string& id : listRails(split)) {
      const Rail rail = getRail(id);
      EXPECT_EQ(rail.id, id);
      const std::string urdf = makeRailUrdf(rail);
      EXPECT_NE(urdf.find("upper=\"" + std::to_string(rail.half_length).substr(0, 3)), std::string::npos) << urdf;
    }
  EXPECT_THROW(getRail("rail9_mass9"), sdk::Error);
}

}  // namespace
}  // namespace slider
