// sdk::Config, what a plugin reads its YAML with: booleans as the host's
// configuration reads them (YAML 1.2), and unknown keys refused with the
// closest known one.
#include <manibench/sdk/common.hpp>

#include <gtest/gtest.h>

#include "test_support.hpp"

namespace manibench {
namespace {

using testing::catchMessage;
using testing::expectMentions;

TEST(SdkConfig, BooleansAreYaml12) {
  const sdk::Config config("a: true\nb: False\nc: yes\nd: on\n");
  EXPECT_TRUE(config.get<bool>("a", false));
  EXPECT_FALSE(config.get<bool>("b", true));
  expectMentions(catchMessage<sdk::Error>([&] { config.get<bool>("c", false); }),
                 {"'c'", "line 3", "must be true or false", "'yes'"});
  expectMentions(catchMessage<sdk::Error>([&] { config.get<bool>("d", false); }), {"'d'", "'on'"});
  EXPECT_TRUE(config.get<bool>("missing", true));
}

TEST(SdkConfig, UnknownKeysAreRefusedWithTheClosestKnownOne) {
  const sdk::Config good("hold_steps: 3\npartnet_dir: /x\n");
  EXPECT_NO_THROW(good.requireKnownKeys({"hold_steps", "partnet_dir", "scale"}, "task MyTask-v0"));
  const sdk::Config typo("hold_steps: 3\npartnet_dri: /x\n");
  expectMentions(catchMessage<sdk::Error>([&] {
                   typo.requireKnownKeys({"hold_steps", "partnet_dir", "scale"}, "task MyTask-v0");
                 }),
                 {"task MyTask-v0", "unknown key 'partnet_dri'", "did you mean 'partnet_dir'?"});
  const sdk::Config far("colour: red\n");
  const std::string message =
      catchMessage<sdk::Error>([&] { far.requireKnownKeys({"hold_steps"}, "task MyTask-v0"); });
  expectMentions(message, {"unknown key 'colour'"});
  EXPECT_EQ(message.find("did you mean"), std::string::npos) << message;
  EXPECT_EQ(sdk::calcEditDistance("kitten", "sitting"), 3u);
}

}  // namespace
}  // namespace manibench
