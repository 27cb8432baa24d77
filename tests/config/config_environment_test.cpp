// A configuration really changes a real Environment (Reach-v0 from the
// build tree's plugins): the task's layer, the integrator, gravity, timing,
// the plugins' sections and the errors about their keys, body materials.
#include <manibench/config.hpp>
#include <manibench/environment.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "config_files.hpp"
#include "test_registry.hpp"

namespace manibench {
namespace {

using config_test::TempFile;
using testing::contains;
using testing::getBuildTreeRegistry;

bool startsWith(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}

std::unique_ptr<Environment> makeEnvironment(const ConfigSources& sources, bool stop_on_success = true) {
  const ConfigNode config = loadTaskConfig(getBuildTreeRegistry(), "Reach-v0", sources);
  EnvironmentOptions options = calcEnvironmentOptions(config);
  options.stop_on_success = stop_on_success;
  return std::make_unique<Environment>(getBuildTreeRegistry(), "Reach-v0", options);
}

std::vector<Eigen::VectorXd> recordZeroActionEpisode(Environment& env, int steps) {
  env.reset("2", 11);
  std::vector<Eigen::VectorXd> observations{env.getObservation()};
  // A constant push makes the integrator work (zero action just holds still).
  Eigen::VectorXd action(2);
  action << 0.6, -0.4;
  for (int i = 0; i < steps; ++i) {
    env.step(action);
    observations.push_back(env.getObservation());
  }
  return observations;
}

TEST(ConfigEnvironment, ReachTaskLayerIsPartOfTheMerge) {
  const ConfigNode config = loadTaskConfig(getBuildTreeRegistry(), "Reach-v0", {});
  EXPECT_EQ(config.findPath("physics.integrator")->origin.describe(), "task Reach-v0 defaults:2");
  EXPECT_EQ(config.find("cameras")->items.at(0).find("name")->scalar, "side");
  EXPECT_EQ(config.findPath("episode.max_steps")->scalar, "100");
  EXPECT_EQ(config.findPath("control.controller")->scalar, "joint_velocity");
}

TEST(ConfigEnvironment, IntegratorSettingsChangeTheTrajectory) {
  // Reach's integrator: implicit_euler at 2 ms.
  const auto reference = recordZeroActionEpisode(*makeEnvironment({}), 20);
  const auto same = recordZeroActionEpisode(*makeEnvironment({{}, {"physics.implicit_step=2.0e-3"}}), 20);
  const auto precise = recordZeroActionEpisode(
      *makeEnvironment({{}, {"physics.integrator=cpodes", "physics.accuracy=1e-6"}}), 20);
  const auto merson = recordZeroActionEpisode(*makeEnvironment({{}, {"physics.integrator=rk_merson"}}), 20);
  // Semi-explicit Euler needs a step well below the velocity drives' time
  // constant (inertia / damping, ~1.6e-4 s for Reach's forearm).
  const auto euler = recordZeroActionEpisode(
      *makeEnvironment({{}, {"physics.integrator=semi_explicit_euler", "physics.fixed_step=5e-5"}}), 20);
  ASSERT_EQ(reference.size(), same.size());
  double precise_difference = 0, merson_difference = 0, euler_difference = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    EXPECT_EQ(0, std::memcmp(reference[i].data(), same[i].data(), sizeof(double) * reference[i].size()));
    precise_difference = std::max(precise_difference, (reference[i] - precise[i]).cwiseAbs().maxCoeff());
    merson_difference = std::max(merson_difference, (reference[i] - merson[i]).cwiseAbs().maxCoeff());
    euler_difference = std::max(euler_difference, (reference[i] - euler[i]).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(precise_difference, 0.0);
  EXPECT_GT(merson_difference, 0.0);
  // Different solvers, same physics: the trajectories stay close.
  EXPECT_LT(precise_difference, 0.05);
  EXPECT_LT(merson_difference, 0.05);
  EXPECT_GT(euler_difference, 0.0);
  EXPECT_LT(euler_difference, 0.05);
}

TEST(ConfigEnvironment, GravityComesFromTheConfiguration) {
  // joint_velocity balances gravity by inverse dynamics, so with gravity on
  // or off the arm tracks the same velocities: the difference lies in the
  // drive torques. What must hold: the scene gets the configured gravity,
  // and the balancing cancels it (to rounding: implicit_euler's fixed steps
  // see exactly the same forces; error-controlled integrators differed by
  // their step choices).
  auto earth_env = makeEnvironment({});
  auto moon_env = makeEnvironment({{}, {"physics.gravity=[0, 0, -1.62]"}});
  EXPECT_EQ(earth_env->getScene().getPhysicsSettings().gravity_z, -9.81);
  EXPECT_EQ(moon_env->getScene().getPhysicsSettings().gravity_z, -1.62);
  const auto earth = recordZeroActionEpisode(*earth_env, 10);
  const auto moon = recordZeroActionEpisode(*moon_env, 10);
  double difference = 0;
  for (std::size_t i = 0; i < earth.size(); ++i)
    difference = std::max(difference, (earth[i] - moon[i]).cwiseAbs().maxCoeff());
  EXPECT_LT(difference, 1e-9);
}

TEST(ConfigEnvironment, TimingOverridesChangeTheEnvironmentForReal) {
  // 50 Hz x 2 ticks: one environment step is 0.04 s of physics.
  auto env = makeEnvironment({{}, {"control.frequency=50", "control.frame_skip=2", "episode.max_steps=3"}},
                             /*stop_on_success=*/false);
  EXPECT_EQ(env->getTaskDescription().control_frequency, 50.0);
  EXPECT_EQ(env->getTaskDescription().frame_skip, 2u);
  EXPECT_EQ(env->getTaskDescription().max_episode_steps, 3u);
  env->reset("0", 0);
  const double t0 = env->getScene().getTime();
  StepResult step = env->step(Eigen::VectorXd::Zero(2));
  EXPECT_NEAR(env->getScene().getTime() - t0, 0.04, 1e-12);
  EXPECT_FALSE(step.isDone());
  env->step(Eigen::VectorXd::Zero(2));
  step = env->step(Eigen::VectorXd::Zero(2));
  EXPECT_TRUE(step.isDone());  // the time limit, 3 steps
  EXPECT_EQ(env->getElapsedSteps(), 3u);
}

TEST(ConfigEnvironment, ControllerAndTaskSectionsReachThePlugins) {
  const TempFile file("control:\n  controller: joint_position\ntask:\n  reach_tolerance: 10\n");
  auto env = makeEnvironment({{file.path()}, {}}, false);
  EXPECT_EQ(env->getControllerDescription().name, "joint_position");
  env->reset("0", 0);
  // A 10 m tolerance: every target counts as reached at once.
  EXPECT_EQ(env->step(Eigen::VectorXd::Zero(2)).flags.at(0), 1);
}

TEST(ConfigEnvironment, PluginErrorsAboutTheirKeysNameWhereTheyWereSet) {
  const TempFile file("task:\n  hold_steps: 2\n  reach_tolerance: wide\n");
  const ConfigNode config = loadTaskConfig(getBuildTreeRegistry(), "Reach-v0", {{file.path()}, {}});
  try {
    Environment env(getBuildTreeRegistry(), "Reach-v0", calcEnvironmentOptions(config));
    FAIL() << "Reach accepted reach_tolerance: wide";
  } catch (const PluginCallError& e) {
    const std::string message = annotatePluginError(config, e.what());
    EXPECT_TRUE(contains(message, "reach_tolerance")) << message;
    EXPECT_TRUE(contains(message, "task.reach_tolerance is set at " + file.path() + ":3")) << message;
    EXPECT_FALSE(contains(message, "hold_steps")) << message;  // not named by the plugin
  }
  // Controller keys too.
  const ConfigNode bad_controller =
      loadTaskConfig(getBuildTreeRegistry(), "Reach-v0", {{}, {"control.controller_config={damping: -1}"}});
  try {
    Environment env(getBuildTreeRegistry(), "Reach-v0", calcEnvironmentOptions(bad_controller));
    FAIL() << "the controller accepted damping: -1";
  } catch (const PluginCallError& e) {
    const std::string message = annotatePluginError(bad_controller, e.what());
    EXPECT_TRUE(contains(message, "control.controller_config.damping is set at --set "
                                  "control.controller_config={damping: -1}"))
        << message;
  }
}

TEST(ConfigEnvironment, BodyMaterialsReachTheSceneAndBadNamesAreErrors) {
  // Reach's arm has no collision geometry, so materials change nothing
  // there; what counts is that the scene accepts them before finalize().
  const TempFile good(
      "physics:\n  contact:\n    ground: {static_friction: 1.2, dynamic_friction: 1.0}\n"
      "    bodies:\n      - {articulation: arm, link: forearm, static_friction: 2}\n"
      "  self_collision: {arm: true}\n");
  auto env = makeEnvironment({{good.path()}, {}});
  env->reset("0", 0);
  EXPECT_NO_THROW(env->step(Eigen::VectorXd::Zero(2)));

  // A pattern names every link it starts (PushChair's wheel_*, however
  // many wheels a chair has); one that matches none is no error.
  const TempFile pattern(
      "physics:\n  contact:\n    bodies:\n      - {articulation: arm, link: \"fore*\", static_friction: 2}\n"
      "      - {articulation: arm, link: \"wheel_*\", static_friction: 2}\n");
  auto patterned = makeEnvironment({{pattern.path()}, {}});
  patterned->reset("0", 0);
  EXPECT_NO_THROW(patterned->step(Eigen::VectorXd::Zero(2)));

  const TempFile no_link("physics:\n  contact:\n    bodies:\n      - {articulation: arm, link: hand}\n");
  try {
    makeEnvironment({{no_link.path()}, {}});
    FAIL() << "a material for a missing link was accepted";
  } catch (const SceneError& e) {
    EXPECT_TRUE(startsWith(e.what(), no_link.path() + ":4: physics.contact.bodies: articulation 'arm' of "
                                                      "task 'Reach-v0', object '0' has no link 'hand'"))
        << e.what();
  }
  try {
    makeEnvironment({{}, {"physics.self_collision={robot: true}"}});
    FAIL() << "self-collision of a missing articulation was accepted";
  } catch (const SceneError& e) {
    EXPECT_TRUE(contains(e.what(), "--set physics.self_collision={robot: true}: "
                                   "physics.self_collision.robot: the scene of task 'Reach-v0', "
                                   "object '0' has no articulation 'robot' (it has 'arm')"))
        << e.what();
  }
}

TEST(ConfigEnvironment, EnvironmentRefusesImpossibleTimingOverrides) {
  EnvironmentOptions options;
  options.control_frequency = 0;
  EXPECT_THROW(Environment(getBuildTreeRegistry(), "Reach-v0", options), manibench::InvalidArgument);
  options = {};
  options.frame_skip = 0u;
  EXPECT_THROW(Environment(getBuildTreeRegistry(), "Reach-v0", options), manibench::InvalidArgument);
}

}  // namespace
}  // namespace manibench
