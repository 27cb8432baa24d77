// Long contact scenarios (ctest label `scenario`): the contact-rich pile
// with CPodes, whose dense Jacobian makes it slow with a dozen free bodies.
#include <gtest/gtest.h>

#include "contact_scenes.hpp"

namespace manibench {
namespace {

using namespace contact_scenes;

TEST(ContactScenarioTest, APileIsBitIdenticalInTwoScenesWithCPodes) {
  expectPileIsBitIdentical("cpodes", 1000);
}

TEST(ContactScenarioTest, RestoringAStateReplaysThePileWithCPodes) { expectPileReplays("cpodes"); }

}  // namespace
}  // namespace manibench
