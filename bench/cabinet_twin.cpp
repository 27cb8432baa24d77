#include "cabinet_twin.hpp"

#include <manibench/sdk/numbers.hpp>

#include <manibench/abi.h>
#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/plugin_registry.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "cabinet_twin_engines.hpp"
#include "model_run.hpp"

namespace manibench::bench {
namespace {

using namespace cabinet_twin;

constexpr const char* kTask = "OpenCabinetDrawer-v0";
const char* const kPartNames[2] = {"robot", "cabinet"};

// Sanity limits (both engines). Speeds: commands reach 3.14 rad/s and
// 0.5 m/s, but a drive at its effort limit cannot hold its joint against
// the base's yaw jerks (damping 1000, a new random yaw rate each tick):
// manibench whips the shoulder to 8.7 rad/s in one bench episode, with
// CPODES at 1e-4 and implicit Euler at 0.25 ms alike, and a light wrist to
// 18; a blow-up is orders of magnitude beyond. Limits and the floor:
// manibench's stops and contacts are penalty springs, MuJoCo's soft
// constraints. Under random commands manibench stays within 6 mm (mrad);
// MuJoCo sinks a finger 9 mm into the floor and lets the light wrist
// (joint 7, 12 Nm, drive damping 100) pass its limit by up to 0.11 rad:
// its implicit integrator at 2 ms divides the limit's impulse by
// 1 + dt kd / I (docs/performance.md).
constexpr double kMaxSpeed = 30;          // rad/s or m/s, any joint
constexpr double kLimitTolerance = 0.15;  // rad beyond a revolute joint's limit
// MuJoCo's soft finger limits: 11 mm past in one of 57 episodes (a finger
// driven at its 100 N into its closed stop while gripping).
constexpr double kSlideLimitTolerance = 0.02;  // m beyond a prismatic joint's limit
constexpr double kFloorTolerance = 0.02;  // m below the floor, any shape
constexpr double kMaxBaseTravel = 3.0;    // m from where the episode started

// Cross-engine checks before timing.
constexpr int kReplaySteps = 5;        // env steps of random actions
constexpr int kHoldSteps = 20;         // 1 s of zero actions
constexpr double kHoldTolerance = 1e-3;  // rad or m
constexpr int kSagSteps = 10;          // 0.5 s without balancing
constexpr double kSagTolerance = 0.05;  // of the sag
constexpr int kOpenLoopSteps = 10;     // 0.5 s of one fixed action
constexpr double kOpenLoopTolerance = 0.01;  // rad or m

// --- the checks ---------------------------------------------------------------

// The worst the checks have seen, for the table's notes.
struct Extremes {
  double penetration = 0;  // deepest shape below the floor, m
  double speed = 0;        // fastest joint, rad/s or m/s
  double beyond_limit = 0;  // farthest past a joint limit, rad or m
  std::string speed_joint, limit_joint, floor_link;
  long checks = 0;
};

// "" if the snapshot is physically sane (see the limits above).
std::string checkSnapshot(const TwinSnapshot& s, const TwinFacts& f, Extremes& seen) {
  char buffer[256];
  ++seen.checks;
  for (int part : {kRobot, kCabinet}) {
    const TwinPlacement& p = f.placements[part];
    for (std::size_t j = 0; j < p.joints.size(); ++j) {
      const JointDescription& joint = p.joints[j];
      const double q = s.q[part][Eigen::Index(j)], v = s.v[part][Eigen::Index(j)];
      if (!std::isfinite(q) || !std::isfinite(v))
        return kPartNames[part] + std::string(" joint '") + joint.name + "' is not finite";
      if (std::abs(v) > seen.speed) {
        seen.speed = std::abs(v);
        seen.speed_joint = joint.name;
      }
      if (std::max(joint.lower - q, q - joint.upper) > seen.beyond_limit) {
        seen.beyond_limit = std::max(joint.lower - q, q - joint.upper);
        seen.limit_joint = joint.name;
      }
      const double tolerance =
          joint.type == JointType::Prismatic ? kSlideLimitTolerance : kLimitTolerance;
      if (!(q >= joint.lower - tolerance && q <= joint.upper + tolerance)) {
        std::snprintf(buffer, sizeof buffer, "%s joint '%s' at %.4g, beyond its limits [%g, %g]",
                      kPartNames[part], joint.name.c_str(), q, joint.lower, joint.upper);
        return buffer;
      }
      if (!(std::abs(v) <= kMaxSpeed)) {
        std::snprintf(buffer, sizeof buffer, "%s joint '%s' moves at %.4g (limit %g)",
                      kPartNames[part], joint.name.c_str(), v, kMaxSpeed);
        return buffer;
      }
    }
    const TwinArticulation& art = p.articulation;
    for (std::size_t l = 0; l < art.links.size(); ++l)
      for (const TwinGeom& geom : art.links[l].geoms) {
        if (part == kCabinet && l == 0) continue;  // fixed to the floor
        const double z = calcLowestZ(geom, s.links[part][l]);
        if (-z > seen.penetration) {
          seen.penetration = -z;
          seen.floor_link = art.links[l].name;
        }
        if (!(z >= -kFloorTolerance)) {
          std::snprintf(buffer, sizeof buffer, "%s link '%s' is %.4g m below the floor",
                        kPartNames[part], art.links[l].name.c_str(), -z);
          return buffer;
        }
      }
  }
  // The robot: its base on the floor and upright, not far from its start.
  const TwinArticulation& robot = f.placements[kRobot].articulation;
  const int base = robot.findLink("base_link"), body = robot.findLink("body_link");
  const Eigen::Isometry3d& X_base = s.links[kRobot][std::size_t(base)];
  const double tilt = X_base.linear().col(2).dot(Eigen::Vector3d::UnitZ());
  const double travel = (X_base.translation().head<2>() - f.initial_q[kRobot].head<2>()).norm();
  if (!(std::abs(X_base.translation().z()) < 1e-6) || !(tilt > 0.999999) ||
      !(s.links[kRobot][std::size_t(body)].linear().col(2).z() > 0.999999))
    return "the robot's base left the floor or tilted";
  if (!(travel < kMaxBaseTravel)) {
    std::snprintf(buffer, sizeof buffer, "the robot's base travelled %.3g m (limit %g)", travel,
                  kMaxBaseTravel);
    return buffer;
  }
  // The cabinet's body stays where it was placed.
  if (!((s.links[kCabinet][0].translation() - f.cabinet_root.translation()).norm() < 1e-9))
    return "the cabinet moved";
  return {};
}

// --- the timed run --------------------------------------------------------------

// Episodes of the random action sequence, each from the reset state, as a
// learning agent explores: uniform actions in [-1, 1] per env step (the
// `random` policy's distribution), the same sequence in both engines.
class TwinRun final : public SceneRun {
 public:
  TwinRun(std::unique_ptr<TwinEngine> engine, std::shared_ptr<const TwinFacts> facts)
      : engine_(std::move(engine)), facts_(std::move(facts)), action_(MobilePandaLaw::kActionDim) {}

  void settle() override {
    engine_->reset();
    check();
  }

  void finish() override {
    while (ok() && (step_ != 0 || episodes_ == 0)) envStep();
  }

  IntegratorStatistics getIntegratorStatistics() const override {
    return engine_->getIntegratorStatistics();
  }

 protected:
  std::string getEngineProblems() const override { return engine_->getProblems(); }
  void runEnvStep() override {
    for (Eigen::Index i = 0; i < action_.size(); ++i)
      action_[i] = uniformAt(-1, 1, facts_->seed, episodes_, step_, int(i));
    engine_->step(action_);
    check();  // every env step: cheap beside the step (under 1 % in MuJoCo)
    if (++step_ < facts_->episode_steps) return;
    const TwinSnapshot s = engine_->snapshot();
    Eigen::VectorXd end(s.q[kRobot].size() + s.q[kCabinet].size());
    end << s.q[kRobot], s.q[kCabinet];
    recordEpisodeEnd(end);
    engine_->reset();
    step_ = 0;
    ++episodes_;
  }

  void endWindow() override { check(); }

  std::string describeChecks() const override {
    char buffer[320];
    std::snprintf(buffer, sizeof buffer,
                  "%ld checks (every env step): fastest joint %.3g (%s), deepest below the floor "
                  "%.3g m (%s), farthest past a joint limit %.3g (%s)",
                  seen_.checks, seen_.speed, seen_.speed_joint.c_str(), seen_.penetration,
                  seen_.floor_link.empty() ? "-" : seen_.floor_link.c_str(), seen_.beyond_limit,
                  seen_.limit_joint.empty() ? "-" : seen_.limit_joint.c_str());
    return buffer + engine_->describeContacts();
  }

 private:
  void check() {
    if (!ok()) return;
    const std::string problem = checkSnapshot(engine_->snapshot(), *facts_, seen_);
    if (problem.empty() || !problem_.empty()) return;  // keep the first
    problem_ = problem;
    if (!problem_.empty())
      problem_ += " (episode " + std::to_string(episodes_ + 1) + ", step " + std::to_string(step_) + ")";
  }

  std::unique_ptr<TwinEngine> engine_;
  std::shared_ptr<const TwinFacts> facts_;
  Eigen::VectorXd action_;
  int step_ = 0;
  Extremes seen_;
};

// --- building the twin ----------------------------------------------------------

ContactMaterial findMaterial(const EnvironmentOptions& options, const std::string& articulation,
                             const std::string& link) {
  ContactMaterial material = options.physics.default_material;
  for (const BodyContactMaterial& body : options.contact_materials)  // later entries win
    if (body.articulation == articulation && (body.link.empty() || body.link == link))
      material = body.material;
  return material;
}

// MuJoCo has one friction coefficient per contact where manibench has a
// static and a dynamic one; the twin uses the static one (MuJoCo's
// friction cone bounds what a contact holds, as manibench's stiction
// does). manibench combines two surfaces by the geometric mean, MuJoCo by
// the maximum, or by the geom of higher priority. So: the articulation
// whose links share one material (the cabinet) gets priority 0, the other
// one's geoms priority 1 and the combined coefficient with it; the floor
// touches only explicit pairs, each with its own combined coefficient.
void assignFriction(const EnvironmentOptions& options, std::vector<TwinPlacement>& placements) {
  const double ground =
      options.ground_material.value_or(options.physics.default_material).static_friction;
  std::vector<std::vector<double>> mu(placements.size());
  for (std::size_t a = 0; a < placements.size(); ++a)
    for (const TwinLink& link : placements[a].articulation.links)
      mu[a].push_back(findMaterial(options, placements[a].articulation.name, link.name).static_friction);
  auto uniform = [&](std::size_t a) {
    return std::all_of(mu[a].begin(), mu[a].end(), [&](double x) { return x == mu[a][0]; });
  };
  const std::size_t low = uniform(kCabinet) ? kCabinet : kRobot, high = 1 - low;
  if (!uniform(low))
    throw std::invalid_argument(
        "MuJoCo twin: neither articulation has one contact material on all its links; MuJoCo's "
        "friction combination cannot reproduce manibench's geometric mean then");
  for (std::size_t a = 0; a < placements.size(); ++a) {
    TwinPlacement& p = placements[a];
    for (std::size_t l = 0; l < mu[a].size(); ++l) {
      p.link_friction.push_back(a == high ? std::sqrt(mu[a][l] * mu[low][0]) : mu[a][l]);
      p.link_priority.push_back(a == high ? 1 : 0);
      p.floor_friction.push_back(std::sqrt(mu[a][l] * ground));
    }
  }
}

struct TwinBuild {
  std::shared_ptr<PluginRegistry> registry;
  std::unique_ptr<Environment> env;
  std::shared_ptr<TwinFacts> facts;
  std::string mjcf;
};

TwinBuild buildTwin(const RunOptions& options) {
  TwinBuild build;
  build.registry = std::make_shared<PluginRegistry>();
  build.registry->loadSearchPath();
  ConfigSources sources;
  if (!options.integrator.empty()) sources.overrides.push_back("physics.integrator=" + options.integrator);
  auto exact = [](double value) {  // reads back as the same double
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", value);
    return std::string(text);
  };
  if (options.accuracy > 0) sources.overrides.push_back("physics.accuracy=" + exact(options.accuracy));
  if (options.fixed_step > 0)
    sources.overrides.push_back("physics.fixed_step=" + exact(options.fixed_step));
  if (options.implicit_step > 0)
    sources.overrides.push_back("physics.implicit_step=" + exact(options.implicit_step));
  EnvironmentOptions env_options = calcEnvironmentOptions(loadTaskConfig(*build.registry, kTask, sources));
  env_options.stop_on_success = false;
  for (const SelfCollisionSetting& setting : env_options.self_collision)
    if (setting.enabled) throw std::invalid_argument("MuJoCo twin: self-collision is not converted");
  if (env_options.physics.gravity_z != -9.81)
    throw std::invalid_argument("MuJoCo twin: only gravity -9.81 m/s^2 is converted");
  build.env = std::make_unique<Environment>(*build.registry, kTask, env_options);
  Environment& env = *build.env;
  const TaskDescription& task = env.getTaskDescription();
  if (env.getControllerDescription().name != "mobile_panda" ||
      !(env.getControllerDescription().flags & MB_CONTROLLER_BALANCE_PASSIVE_FORCES) ||
      task.actuated_joints != MobilePandaLaw::getJointNames())
    throw std::invalid_argument("MuJoCo twin: it copies the mobile_panda controller on the "
                                "single-arm robot, which " + std::string(kTask) + " no longer uses");

  auto facts = std::make_shared<TwinFacts>();
  facts->object = options.twin_object.empty() ? env.listObjects("train").front() : options.twin_object;
  facts->seed = options.twin_seed;
  facts->episode_steps =
      options.twin_episode_steps > 0 ? options.twin_episode_steps : int(task.max_episode_steps);
  facts->frame_skip = int(task.frame_skip);
  facts->control_dt = 1.0 / task.control_frequency;
  env.reset(facts->object, facts->seed);
  const Scene& scene = env.getScene();
  const int ids[2] = {scene.findArticulation(task.robot_articulation), scene.findArticulation("cabinet")};
  if (ids[kCabinet] < 0) throw std::invalid_argument("MuJoCo twin: the scene has no 'cabinet'");
  for (int part : {kRobot, kCabinet}) {
    const ArticulationSource& source = scene.getArticulationSource(ids[part]);
    TwinPlacement p;
    p.articulation = parseTwinArticulation(source.urdf, kPartNames[part],
                                           std::string(kTask) + " " + kPartNames[part] + " URDF");
    p.root.linear() = source.root.orientation.toRotationMatrix();
    p.root.translation() = source.root.position;
    p.fixed_base = source.fixed_base;
    p.joints = scene.getJoints(ids[part]);
    facts->initial_q[part] = scene.getJointPositions(ids[part]);
    if (part == kCabinet) facts->cabinet_root = p.root;
    facts->placements.push_back(std::move(p));
  }
  facts->cabinet_dynamics = drawCabinetDynamics(facts->seed, facts->placements[kCabinet].joints.size(),
                                                facts->initial_q[kRobot][2]);
  for (std::size_t j = 0; j < facts->placements[kCabinet].joints.size(); ++j) {
    facts->placements[kCabinet].joints[j].damping = facts->cabinet_dynamics.damping[j];
    facts->placements[kCabinet].joints[j].friction = facts->cabinet_dynamics.friction[j];
  }
  assignFriction(env_options, facts->placements);

  const TwinArticulation& robot = facts->placements[kRobot].articulation;
  if (robot.findLink("base_link") < 0 || robot.findLink("body_link") < 0)
    throw std::invalid_argument("MuJoCo twin: the robot has no base_link or body_link to check");

  TwinMjcfOptions mjcf;
  mjcf.timestep = options.mujoco_dt;
  mjcf.integrator = options.mujoco_integrator.empty() ? "implicit" : options.mujoco_integrator;
  mjcf.floor = scene.hasGround();
  for (const std::string& joint : MobilePandaLaw::getJointNames()) mjcf.actuated.emplace_back(kRobot, joint);
  build.mjcf = toTwinMjcf(facts->placements, mjcf);
  build.facts = facts;
  return build;
}

// Largest |a - b| over both articulations' joint positions.
double calcDifference(const TwinSnapshot& a, const TwinSnapshot& b) {
  double worst = 0;
  for (int part : {kRobot, kCabinet})
    worst = std::max(worst, (a.q[part] - b.q[part]).cwiseAbs().maxCoeff());
  return worst;
}

std::string formatNumber(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

SceneRuns makeTwinRuns(const RunOptions& options) {
  TwinBuild build = buildTwin(options);
  const std::shared_ptr<const TwinFacts> facts = build.facts;
  SceneRuns runs;
  runs.integrator = describeIntegrator(build.env->getOptions().physics);
  auto manibench = std::make_unique<ManibenchTwin>(build.registry, std::move(build.env), facts);
  auto mujoco = std::make_unique<MujocoTwin>(facts, build.mjcf);
  std::vector<std::string>& notes = runs.notes;
  notes.push_back(std::string(kTask) + ", object " + facts->object + " (" +
                  std::to_string(facts->placements[kCabinet].joints.size()) + " cabinet joints), seed " +
                  std::to_string(facts->seed) + ", " + std::to_string(facts->episode_steps) +
                  " env steps per episode");
  if (!facts->cabinet_dynamics.matches_task)
    notes.push_back("the task's draw of the cabinet's joint damping and friction could not be "
                    "repeated (its reset changed?): both engines use the bench's values");
  auto fail = [&runs](const std::string& problem) {
    runs.problem += (runs.problem.empty() ? "" : "; ") + problem;
  };

  // 1. The copied drive law reproduces Environment::step.
  MobilePandaLaw law(1.0 / facts->control_dt);
  Eigen::VectorXd action(MobilePandaLaw::kActionDim);
  auto randomAction = [&](int step) {
    for (Eigen::Index i = 0; i < action.size(); ++i)
      action[i] = uniformAt(-1, 1, facts->seed ^ 0xC0FFEEULL, 0, step, int(i));
    return action;
  };
  manibench->reset();
  for (int k = 0; k < kReplaySteps; ++k) manibench->step(randomAction(k));
  const TwinSnapshot by_controller = manibench->snapshot();
  manibench->reset();
  for (int k = 0; k < kReplaySteps; ++k) manibench->stepWithLaw(randomAction(k), law);
  const double replay = calcDifference(by_controller, manibench->snapshot());
  if (replay == 0)
    notes.push_back("drive law: the copy replayed on the manibench scene reproduces "
                    "Environment::step bit for bit (" + std::to_string(kReplaySteps) +
                    " random env steps)");
  else
    fail("the copy of mobile_panda's drive law differs from Environment::step by " +
         formatNumber("%.3g", replay) + " after " + std::to_string(kReplaySteps) +
         " random env steps: controllers/ changed, update bench/mobile_panda_law.cpp");

  // 2. Zero actions: both hold the initial state.
  TwinEngine* engines[2] = {manibench.get(), mujoco.get()};
  auto runBoth = [&](int steps, const Eigen::VectorXd& a, TwinSnapshot out[2]) {
    for (int e = 0; e < 2; ++e) {
      engines[e]->reset();
      for (int k = 0; k < steps; ++k) engines[e]->step(a);
      out[e] = engines[e]->snapshot();
    }
  };
  TwinSnapshot hold[2];
  runBoth(kHoldSteps, Eigen::VectorXd::Zero(MobilePandaLaw::kActionDim), hold);
  TwinSnapshot start;
  for (int part : {kRobot, kCabinet}) start.q[part] = facts->initial_q[part];
  const double moved[2] = {calcDifference(hold[0], start), calcDifference(hold[1], start)};
  const double apart = calcDifference(hold[0], hold[1]);
  notes.push_back("zero actions for " + formatNumber("%g", kHoldSteps * facts->frame_skip * facts->control_dt) +
                  " s: manibench moved " + formatNumber("%.2g", moved[0]) + ", MuJoCo " +
                  formatNumber("%.2g", moved[1]) + ", apart " + formatNumber("%.2g", apart) +
                  " (rad or m; limit " + formatNumber("%g", kHoldTolerance) + ")");
  if (!(std::max({moved[0], moved[1], apart}) <= kHoldTolerance))
    fail("the twin does not hold still under zero actions");
  // 3. Gravity alone: without balancing, zero actions let the arm sag
  // against its damping drives; masses, inertias and frames decide how far.
  for (TwinEngine* engine : engines) engine->setBalancing(false);
  TwinSnapshot sag[2];
  runBoth(kSagSteps, Eigen::VectorXd::Zero(MobilePandaLaw::kActionDim), sag);
  for (TwinEngine* engine : engines) engine->setBalancing(true);
  // Joints pushed onto a limit (the lift, by the column's weight) rest on
  // the engines' different stops: reported apart.
  double sagged[2] = {0, 0}, sag_apart = 0;
  std::string on_stops;
  const TwinPlacement& robot = facts->placements[kRobot];
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const JointDescription& joint = robot.joints[j];
    const double q[2] = {sag[0].q[kRobot][Eigen::Index(j)], sag[1].q[kRobot][Eigen::Index(j)]};
    const double q0 = facts->initial_q[kRobot][Eigen::Index(j)];
    if (std::min(q[0], q[1]) < joint.lower || std::max(q[0], q[1]) > joint.upper) {
      on_stops += "; " + joint.name + " on its stop: manibench " + formatNumber("%.3g", q[0] - q0) +
                  ", MuJoCo " + formatNumber("%.3g", q[1] - q0);
      continue;
    }
    for (int e = 0; e < 2; ++e) sagged[e] = std::max(sagged[e], std::abs(q[e] - q0));
    sag_apart = std::max(sag_apart, std::abs(q[0] - q[1]));
  }
  notes.push_back("gravity without balancing, zero actions for " +
                  formatNumber("%g", kSagSteps * facts->frame_skip * facts->control_dt) +
                  " s: the robot's joints sag by up to " + formatNumber("%.4g", sagged[0]) +
                  " (manibench) and " + formatNumber("%.4g", sagged[1]) + " (MuJoCo), " +
                  formatNumber("%.2g", sag_apart) + " apart (rad or m; limit " +
                  formatNumber("%g", kSagTolerance) + " of the sag)" + on_stops);
  if (!(sag_apart <= kSagTolerance * std::max(sagged[0], sagged[1])) || !(sagged[0] > 0))
    fail("the engines sag differently under gravity: masses, inertias or frames differ");

  // 4. One fixed action in free space: both move alike.
  Eigen::VectorXd pattern(MobilePandaLaw::kActionDim);
  pattern << 0.3, -0.2, 0.2, 0.2, 0.3, -0.3, 0.3, -0.3, 0.3, -0.3, 0.3, -0.5;
  TwinSnapshot open_loop[2];
  runBoth(kOpenLoopSteps, pattern, open_loop);
  const double differs = calcDifference(open_loop[0], open_loop[1]);
  notes.push_back("one fixed action for " +
                  formatNumber("%g", kOpenLoopSteps * facts->frame_skip * facts->control_dt) +
                  " s (free space): the engines end " + formatNumber("%.2g", differs) +
                  " apart (rad or m; limit " + formatNumber("%g", kOpenLoopTolerance) + ")");
  if (!(differs <= kOpenLoopTolerance)) fail("the engines do not follow one fixed action alike");
  for (int e = 0; e < 2; ++e) {
    Extremes ignored;
    const std::string problem = checkSnapshot(open_loop[e], *facts, ignored);
    if (!problem.empty()) fail(std::string(e ? "MuJoCo" : "manibench") + " after the fixed action: " + problem);
  }

  runs.manibench = std::make_unique<TwinRun>(std::move(manibench), facts);
  runs.mujoco = std::make_unique<TwinRun>(std::move(mujoco), facts);
  return runs;
}

}  // namespace

BenchScene makeCabinetTwinScene() {
  BenchScene scene;
  scene.name = "cabinet_random";
  scene.description =
      std::string("twin of ") + kTask +
      ": the mobile Panda and one generated cabinet, manibench's real Environment::step against "
      "the same scene in MuJoCo, uniform random actions in [-1, 1] every env step";
  scene.make_runs = makeTwinRuns;
  scene.make_documents = [](const RunOptions& options) {
    const TwinBuild build = buildTwin(options);
    const Scene& scene = build.env->getScene();
    std::vector<std::pair<std::string, std::string>> documents = {{".xml", build.mjcf}};
    for (int part : {kRobot, kCabinet})
      documents.emplace_back(std::string(".") + kPartNames[part] + ".urdf",
                             scene.getArticulationSource(scene.findArticulation(
                                 part == kRobot ? build.env->getTaskDescription().robot_articulation
                                                : "cabinet")).urdf);
    return documents;
  };
  return scene;
}

}  // namespace manibench::bench
