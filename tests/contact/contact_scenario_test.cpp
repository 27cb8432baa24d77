// Long contact scenarios (ctest label `scenario`): the contact-rich pile
// with CPodes, whose dense Jacobian makes it slow with a dozen free bodies.
#include <gtest/gtest.h>

#include "contact_scenes.hpp"

namespace manibench {
namespace {

using namespace contact_scenes;

// 300 ticks (3 s: the twelve bodies have fallen, piled up and are stirred
// by half an arm sweep) rather than the explicit steppers' 1000: CPodes'
// error control makes a settled pile's ticks costly, and 1000 took 246 s,
// the whole suite's critical path on two cores (300: 40 s).
TEST(ContactScenarioTest, APileIsBitIdenticalInTwoScenesWithCPodes) {
  expectPileIsBitIdentical("cpodes", 300);
}

TEST(ContactScenarioTest, RestoringAStateReplaysThePileWithCPodes) { expectPileReplays("cpodes"); }

}  // namespace
}  // namespace manibench
