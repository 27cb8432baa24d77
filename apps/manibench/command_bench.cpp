// manibench bench: environment steps per second of a task, and the
// integrator's work per step (which does not depend on the machine's load).
#include <chrono>
#include <iomanip>
#include <iostream>
#include <manibench/episode.hpp>
#include <memory>

#include "cli.hpp"

namespace manibench::cli {

namespace {

const std::string kBenchUsageText = R"(usage: manibench bench TASK [options]

Measures environment steps per second: episodes of TASK on the split's
objects (in turn, seeds 0, 1, ...) until --steps environment steps have run.
Each env step is frame_skip control steps of physics plus the task's reward,
success and observation. Resets are timed separately: the first on its
own (its scene was built with the environment; in the visual modes it
starts the renderer), then the mean of the rest (a new object each, scene
rebuilt, while the split has several).
Then the time of an env step by stage, in ms: physics (controller and
integrator), task (reward, success, state vector), render (drawing the
cameras and reading their pixels back), assembly (the point cloud or
images made from those pixels), policy, and the rest.
The last line gives the integrator's work per env step (steps; for
implicit_euler its island solves, for cpodes its failed steps, Newton
iterations and Jacobians; evaluations of the equations of motion), which
does not depend on the load of the machine.

Options:
)" + std::string(kPolicyUsage) + R"(                          without --policy: random; a trained network:
                          --policy torch_policy --policy-config FILE
                          (docs/learning.md)
  --obs MODE              observation mode: state (default), pointcloud or rgbd
                          (the visual modes render every camera at every step)
  --steps N               environment steps to time (default 2000)
  --split train|test      objects to cycle through (default train)
  --controller NAME       override the task's default controller (default: the
                          one the policy names, e.g. an expert's mobile_panda_ee)
  --config FILE, --set KEY=VALUE   configuration layers, as for run
)";
const char* const kBenchUsage = kBenchUsageText.c_str();

}  // namespace

int commandBench(int argc, char** argv) {
  const Arguments args = parseArguments(argc, argv, 2,
                                        {"policy", "policy-config", "obs", "steps", "split", "controller", "config", "set"}, {},
                                        kBenchUsage);
  if (args.help) {
    std::cout << kBenchUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("bench needs exactly one TASK", kBenchUsage);
  mb::ConfigSources sources = getConfigSources(args, parseObservationMode(args, kBenchUsage));
  const std::string split = parseSplit(args, "train", kBenchUsage);
  const uint64_t target_steps = parseSeed(valueOr(args, "steps", "2000"), kBenchUsage, "--steps");
  if (target_steps == 0) throw UsageError("--steps must be positive", kBenchUsage);

  mb::PluginRegistry registry;
  loadPlugins(registry);
  const PolicyChoice choice = choosePolicy(registry, args, kBenchUsage, "random");
  const std::string& policy_name = choice.name;
  applyPolicyController(registry, policy_name, args, sources, kBenchUsage);
  const std::unique_ptr<mb::Environment> env =
      makeEnvironment(registry, args.positional[0], sources, true);
  const std::vector<std::string> objects = env->listObjects(split);
  if (objects.empty()) throw std::runtime_error("the " + split + " split has no objects");
  mb::PolicyInstance policy(registry, policy_name, choice.config, env->calcPolicyLayout());

  using Clock = std::chrono::steady_clock;
  std::chrono::duration<double> step_time{0}, reset_time{0}, first_reset_time{0};
  uint64_t steps = 0, episodes = 0, successes = 0;
  // Integrator work during env steps only (resets rebuild scenes).
  mb::IntegratorStatistics physics, before;
  Clock::time_point start, act_start;
  // Stage seconds over the timed env steps, and the counters at the step's
  // start (the observer belongs to the scene, which only resets replace).
  struct Stages {
    double physics = 0, task = 0, render = 0, assembly = 0, policy = 0;
  } stages;
  mb::Environment::StageTimes env_before;
  mb::VisualObserver::Times observer_before;
  // Resets (environment and policy) from entering the first to the first
  // act; env steps from each act to the end of its step.
  mb::EpisodeHooks hooks;
  hooks.on_phase = [&](mb::EpisodePhase phase, uint32_t step) {
    if (phase == mb::EpisodePhase::EnvReset) start = Clock::now();
    if (phase == mb::EpisodePhase::EnvStep)
      stages.policy += std::chrono::duration<double>(Clock::now() - act_start).count();
    if (phase != mb::EpisodePhase::PolicyAct) return;
    if (step == 0) (episodes == 0 ? first_reset_time : reset_time) += Clock::now() - start;
    before = env->getScene().getIntegratorStatistics();
    env_before = env->getStageTimes();
    observer_before = env->getObserver().getTimes();
    start = act_start = Clock::now();
  };
  hooks.on_step = [&](const mb::StepResult& result, const mb::EpisodeResult&) {
    step_time += Clock::now() - start;
    physics += env->getScene().getIntegratorStatistics();
    physics -= before;
    const mb::Environment::StageTimes& env_now = env->getStageTimes();
    const mb::VisualObserver::Times& observer_now = env->getObserver().getTimes();
    stages.physics += env_now.physics - env_before.physics;
    stages.task += env_now.task - env_before.task;
    stages.render += observer_now.render - observer_before.render;
    stages.assembly += observer_now.assembly - observer_before.assembly;
    ++steps;
    if (result.isDone() && result.success) ++successes;
    return steps < target_steps;
  };
  while (steps < target_steps) {
    mb::runEpisode(*env, policy, objects[episodes % objects.size()], episodes, hooks);
    ++episodes;
  }
  const mb::PhysicsSettings& settings = env->getScene().getPhysicsSettings();
  std::cout << "task " << args.positional[0] << ", obs " << mb::toString(env->getObservationMode())
            << ", policy " << policy_name << ", controller " << env->getControllerDescription().name
            << ", integrator " << mb::getIntegratorName(settings.integrator) << "\n"
            << steps << " env steps in " << episodes << " episodes (" << successes
            << " successful), " << std::fixed << std::setprecision(1)
            << steps / step_time.count() << " env steps/s (policy + physics + task)\n"
            << "resets: the first " << std::setprecision(2) << 1e3 * first_reset_time.count()
            << " ms (on the scene built with the environment"
            << (mb::isVisualMode(env->getObservationMode()) ? "; it starts the renderer" : "")
            << ")";
  if (episodes > 1)
    std::cout << ", then " << 1e3 * reset_time.count() / double(episodes - 1) << " ms per reset ("
              << episodes - 1 << (objects.size() > 1 ? ", a new object each" : ", the same object")
              << ")";
  const double ms = 1e3 / double(steps);
  const double other = step_time.count() - stages.physics - stages.task - stages.render -
                       stages.assembly - stages.policy;
  std::cout << "\nper env step (ms): " << std::setprecision(3) << "physics "
            << ms * stages.physics << ", task " << ms * stages.task << ", render "
            << ms * stages.render << ", assembly " << ms * stages.assembly << ", policy "
            << ms * stages.policy << ", other " << ms * other << "; total "
            << ms * step_time.count();
  std::cout << "\nphysics per env step: " << std::setprecision(1)
            << double(physics.steps) / double(steps) << " integrator steps";
  if (settings.integrator == mb::Integrator::ImplicitEuler) {
    // Its steps never fail; one solve per contact island, more where a
    // drive's effort limit is reached during the step.
    std::cout << ", " << double(physics.iterations) / double(steps) << " island solves, ";
  } else {
    std::cout << " (" << double(physics.error_test_failures) / double(steps) << " error-test and "
              << double(physics.convergence_test_failures) / double(steps)
              << " convergence failures), " << double(physics.iterations) / double(steps)
              << " Newton iterations, " << double(physics.jacobians) / double(steps)
              << " Jacobians, ";
  }
  std::cout << double(physics.realizations) / double(steps) << " evaluations of the dynamics\n";
  std::cout.unsetf(std::ios::fixed);
  return 0;
}

}  // namespace manibench::cli
