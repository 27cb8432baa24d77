// manibench::Error (manibench/error.hpp): every class the host throws
// derives from it, so one handler catches them all (the CLI's main,
// Python's manibench.Error), and bad values are InvalidArgument.
#include <manibench/demos.hpp>

#include <gtest/gtest.h>

#include <type_traits>

#include "test_registry.hpp"

namespace manibench {
namespace {

template <class... E>
constexpr bool allAreErrors() {
  return (std::is_base_of_v<Error, E> && ...);
}
static_assert(allAreErrors<InvalidArgument, PluginError, PluginCallError, SceneError, SimulationDiverged, RenderError,
                           InvalidAction, EpisodeFailure, ConfigError, DemoError, EvaluationError>());
static_assert(std::is_base_of_v<std::runtime_error, Error>);

TEST(Errors, ABadValueIsAnInvalidArgumentAndAManibenchError) {
  EXPECT_THROW(parseLevels("3-1"), InvalidArgument);
  Environment env(testing::getBuildTreeRegistry(), "Reach_3-v0");
  try {
    env.reset("4", 0);
    FAIL() << "an object the fixed-object environment does not have";
  } catch (const Error& e) {
    EXPECT_NE(dynamic_cast<const InvalidArgument*>(&e), nullptr) << e.what();
    testing::expectMentions(e.what(), {"'4'"});
  }
}

}  // namespace
}  // namespace manibench
