// Scene::Impl's stepping half: the integrator (stepper.hpp) behind each
// advance(), and divergence found and named (see scene_impl.hpp).
#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

#include "scene_impl.hpp"

namespace manibench {

using scene_detail::isValidPose;
using scene_detail::kConstraintTolerance;
using scene_detail::toTransform;

namespace {

// Divergence by step size: an advance() whose integrator steps average
// below kMinMeanStepSize (after kMinStepBudget steps) is a blow-up, not a
// stiff but healthy system (those take ~10-30 us steps even explicitly).
// stepTo() returns every kStepsPerCall internal steps so that this is
// checked; without it a runaway CPodes creeps forward in 1e-14 s steps.
constexpr double kMinMeanStepSize = 1e-6;  // s
constexpr int kMinStepBudget = 10000;
constexpr int kStepsPerCall = 1000;
// How far below the ground a body's origin may go before the scene says it
// fell through (a divergence naming the link).
constexpr double kFallThroughDepth = 10;  // m

std::unique_ptr<scene_detail::Stepper> makeStepper(const SimTK::MultibodySystem& system,
                                                   const SimTK::State& initial,
                                                   const PhysicsSettings& settings,
                                                   const scene_detail::JointForces* joint_forces,
                                                   const scene_detail::ContactForce* contact_force) {
  // Scenes without constraints keep the integrators' defaults (CPodes: a
  // tenth of the accuracy).
  const bool constrained = system.getMatterSubsystem().getNumConstraints() > 0;
  switch (settings.integrator) {
    case Integrator::ImplicitEuler: {
      scene_detail::ImplicitEulerOptions options;
      options.step = settings.implicit_step;
      options.constraint_tolerance = constrained ? kConstraintTolerance : 0;
      return scene_detail::makeImplicitEulerStepper(system, initial, {joint_forces, contact_force},
                                                    options);
    }
    case Integrator::CPodes: {
      scene_detail::CPodesOptions options;
      options.accuracy = settings.accuracy;
      options.constraint_tolerance =
          constrained ? kConstraintTolerance : settings.accuracy / 10;
      return scene_detail::makeCPodesStepper(system, initial, options);
    }
    case Integrator::RkMerson:
    case Integrator::SemiExplicitEuler:
      break;
  }
  return scene_detail::makeSimbodyStepper(system, initial, settings,
                                          constrained ? kConstraintTolerance : 0);
}

std::string formatTime(double t) {
  std::ostringstream s;
  s << t;
  return s.str();
}

}  // namespace

// --- Integrator ---------------------------------------------------------

namespace {
constexpr std::pair<Integrator, const char*> kIntegratorNames[] = {
    {Integrator::ImplicitEuler, "implicit_euler"},
    {Integrator::CPodes, "cpodes"},
    {Integrator::RkMerson, "rk_merson"},
    {Integrator::SemiExplicitEuler, "semi_explicit_euler"},
};
}  // namespace

const char* getIntegratorName(Integrator integrator) {
  for (const auto& [value, name] : kIntegratorNames)
    if (value == integrator) return name;
  assert(false && "every Integrator has a name");
  return "?";
}

Integrator parseIntegrator(const std::string& name) {
  std::string choices;
  for (const auto& [value, known] : kIntegratorNames) {
    if (name == known) return value;
    choices += std::string(choices.empty() ? "'" : ", '") + known + "'";
  }
  throw SceneError("PhysicsSettings: unknown integrator '" + name + "' (expected " + choices + ")");
}

const std::string& Scene::Impl::getMobodLinkName(SimTK::MobilizedBodyIndex mobod) const {
  static const std::string ground = "ground";
  const int link = mobod.isValid() ? mobod_link[mobod] : -1;
  if (link < 0) return ground;
  const auto& [a, l] = links[link];
  return articulations[a].model.links[l].name;
}

std::string Scene::Impl::describeMobod(SimTK::MobilizedBodyIndex mobod) const {
  const int link = mobod.isValid() ? mobod_link[mobod] : -1;
  if (link < 0) return "ground";
  return "link '" + getMobodLinkName(mobod) + "' of articulation '" +
         articulations[links[link].first].name + "'";
}

bool Scene::Impl::findDivergence(const SimTK::State& s,
                                 SimTK::MobilizedBodyIndex& mobod,
                                 std::string& what) const {
  const SimTK::Vector& q = s.getQ();
  for (int i = 0; i < q.size(); ++i)
    if (!std::isfinite(q[i])) {
      mobod = q_mobod[i];
      what = "non-finite position";
      return true;
    }
  const SimTK::Vector& u = s.getU();
  const double limit = settings.divergence_speed_limit;
  for (int i = 0; i < u.size(); ++i)
    if (!(std::abs(u[i]) <= limit)) {
      mobod = u_mobod[i];
      if (!std::isfinite(u[i])) {
        what = "non-finite velocity";
      } else {
        std::ostringstream m;
        m << "speed " << std::abs(u[i]) << " above divergence_speed_limit " << limit;
        what = m.str();
      }
      return true;
    }
  // A body far below the ground fell through it (a shape that lost its
  // collision, a contact that gave way): nothing a task wants, and nothing
  // the speed check sees, since a fall stays slow for a long time.
  if (has_ground) {
    system.realize(s, SimTK::Stage::Position);
    const SimTK::SimbodyMatterSubsystem& matter = system.getMatterSubsystem();
    for (SimTK::MobilizedBodyIndex b(1); b < matter.getNumBodies(); ++b) {
      const double z = matter.getMobilizedBody(b).getBodyOriginLocation(s)[2];
      if (z < ground_height - kFallThroughDepth) {
        mobod = b;
        std::ostringstream m;
        m << "fell through the ground (" << ground_height - z << " m below it)";
        what = m.str();
        return true;
      }
    }
  }
  return false;
}

void Scene::Impl::throwDiverged(const std::string& cause) {
  // Whatever the integrator holds becomes the current state; the next
  // advance() restarts from it (and will fail again unless a restore or a
  // setter repaired it).
  // (If initialize() itself failed, `state` already is that state.)
  if (!needs_init) state = stepper->getState();
  needs_init = true;
  SimTK::MobilizedBodyIndex mobod;
  std::string what;
  if (!findDivergence(state, mobod, what)) {
    // The state itself is finite (the integrator gave up before accepting a
    // bad step): blame the first body with a non-finite acceleration.
    try {
      system.realize(state, SimTK::Stage::Acceleration);
      const SimTK::Vector& udot = state.getUDot();
      for (int i = 0; i < udot.size(); ++i)
        if (!std::isfinite(udot[i])) {
          mobod = u_mobod[i];
          what = "non-finite acceleration";
          break;
        }
      // All finite: the integrator gave up on something stiff. The body
      // with the largest acceleration is where to look (a light link on a
      // stiff drive, a limit stop, a contact).
      if (!mobod.isValid()) {
        int fastest = -1;
        for (int i = 0; i < udot.size(); ++i)
          if (fastest < 0 || std::abs(udot[i]) > std::abs(udot[fastest])) fastest = i;
        if (fastest >= 0) {
          mobod = u_mobod[fastest];
          std::ostringstream m;
          m << "the largest acceleration, " << std::abs(udot[fastest]) << " (speed " << state.getU()[fastest]
            << ")";
          what = m.str();
        }
      }
    } catch (const std::exception&) {
    }
  }
  const double t = state.getTime();
  std::string message = "simulation diverged at t=" + formatTime(t) + " s";
  if (mobod.isValid()) message += ": " + describeMobod(mobod) + ": " + what;
  if (!cause.empty()) message += " (" + cause + ")";
  throw SimulationDiverged(message, mobod.isValid() ? getMobodLinkName(mobod) : "", t);
}

IntegratorStatistics Scene::Impl::calcIntegratorStatistics() const {
  IntegratorStatistics total = retired_statistics;
  if (stepper) total += stepper->getStatistics();
  return total;
}

void Scene::Impl::advance(double dt) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw SceneError("Scene::advance: dt must be positive and finite, got " + formatTime(dt));
  if (state.getNY() == 0) {
    // Nothing moves (only ground and fixed bodies): just the clock runs.
    state.updTime() += dt;
    return;
  }
  try {
    if (needs_init) {
      // A fresh integrator rather than initialize() again: CPodes leaks ~2
      // kB per re-initialization (Simbody 3.7), too much at one per episode.
      retired_statistics = calcIntegratorStatistics();
      ++retired_statistics.initializations;
      stepper = makeStepper(system, state, settings, joint_forces, contact_force);
      needs_init = false;
    }
    const double t_end = stepper->getState().getTime() + dt;
    const std::int64_t first_step = stepper->getStatistics().steps;
    const double budget = std::max<double>(kMinStepBudget, std::ceil(dt / kMinMeanStepSize));
    while (!stepper->stepTo(t_end, kStepsPerCall)) {
      SimTK::MobilizedBodyIndex mobod;
      std::string what;
      if (findDivergence(stepper->getState(), mobod, what)) throwDiverged("");
      const std::int64_t steps = stepper->getStatistics().steps - first_step;
      if (steps > budget) {
        std::ostringstream cause;
        cause << "the integrator took " << steps << " steps and reached only t="
              << stepper->getState().getTime() << " s";
        throw std::runtime_error(cause.str());
      }
    }
  } catch (const SimulationDiverged&) {
    throw;
  } catch (const std::exception& e) {
    std::string cause = e.what();
    // Simbody's messages span lines; keep the first few for the report.
    std::replace(cause.begin(), cause.end(), '\n', ' ');
    if (cause.size() > 400) cause = cause.substr(0, 400) + "...";
    throwDiverged("integrator failed: " + cause);
  }
  SimTK::MobilizedBodyIndex mobod;
  std::string what;
  if (findDivergence(stepper->getState(), mobod, what)) throwDiverged("");
}

}  // namespace manibench
