// Expert episodes of PushChair-v0 with the mobile_panda_ee controller
// (plugins/push_chair), on train and test chairs and a PartNet-format one,
// and determinism. The
// full success-rate sweep is docs/tasks/push_chair.md's table.
#include <gtest/gtest.h>

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>

#include <cstdlib>
#include <iostream>

#include "push_chair.hpp"
#include "test_env.hpp"

namespace {

namespace mb = manibench;
using L = push_chair::ObservationLayout;

using mb::testing::ExpertSetup;

ExpertSetup makeExpertSetup(const std::vector<std::string>& overrides = {}) {
  return mb::testing::makeExpertSetup("PushChair-v0", "push_chair_expert", overrides);
}

void expectExpertSucceeds(ExpertSetup& s, const std::string& object, uint64_t seed) {
  const mb::EpisodeResult r = mb::runEpisode(*s.env, *s.expert, object, seed);
  EXPECT_TRUE(r.success) << object << " seed " << seed << ": " << r.steps << " steps, chair "
                         << r.final_values[0] << " m from the target, speed " << r.final_values[1] << ", tilt "
                         << r.final_values[2];
  EXPECT_LT(r.steps, 200u) << object;
}

TEST(PushChairScenario, ExpertPushesChairsOfBothSplitsToTheTarget) {
  ExpertSetup s = makeExpertSetup();
  expectExpertSucceeds(s, "3000", 0);
  expectExpertSucceeds(s, "3105", 1);
}

// The PartNet-format fixture (plugins/push_chair/tests/partnet_chairs): its
// seat link carries the backrest, the hands go to the cushion's top. The
// expert succeeds on 3 of levels 0-5 of `manibench eval` with this folder.
TEST(PushChairScenario, ExpertPushesAPartNetChair) {
  ExpertSetup s = makeExpertSetup(
      {"task.partnet_dir=" + std::string(MANIBENCH_TEST_SOURCE_DIR) + "/plugins/push_chair/tests/partnet_chairs"});
  expectExpertSucceeds(s, "200001", 1273471130);
}

TEST(PushChairScenario, SameSeedSameTrajectory) {
  ExpertSetup a = makeExpertSetup({"episode.max_steps=60"});
  ExpertSetup b = makeExpertSetup({"episode.max_steps=60"});
  const mb::EpisodeResult ra = mb::runEpisode(*a.env, *a.expert, "3101", 4);
  const mb::EpisodeResult rb = mb::runEpisode(*b.env, *b.expert, "3101", 4);
  EXPECT_EQ(ra.steps, rb.steps);
  EXPECT_EQ(ra.total_reward, rb.total_reward);
  EXPECT_EQ(a.env->getObservation(), b.env->getObservation());
}

}  // namespace
