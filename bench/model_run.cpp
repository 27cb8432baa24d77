#include "model_run.hpp"

#include <sstream>

namespace manibench::bench {
namespace {

// One engine running one model scene: the scripted episodes, the checks.
class ModelRun final : public SceneRun {
 public:
  ModelRun(const BenchScene& scene, std::unique_ptr<Engine> engine)
      : scene_(scene), engine_(std::move(engine)), targets_(scene.model.drives.size()) {}

  void settle() override {
    while (ok() && ticks_ * kControlDt < scene_.settle_time - 1e-9) envStep();
    if (scene_.episode_ticks == 0) check();
  }

  void finish() override {
    if (scene_.episode_ticks == 0) return;
    const long target = episodes_ + 1;
    while (ok() && episodes_ < target) envStep();
  }

  IntegratorStatistics getIntegratorStatistics() const override {
    return engine_->getIntegratorStatistics();
  }

 protected:
  std::string getEngineProblems() const override { return engine_->getProblems(); }
  void runEnvStep() override {
    for (int i = 0; i < kTicksPerEnvStep && ok(); ++i) tick();
  }

  void endWindow() override {
    if (scene_.episode_ticks == 0) check();
  }

 private:
  void tick() {
    if (scene_.policy) {
      scene_.policy(episodes_, episode_tick_, targets_);
      engine_->setTargets(targets_);
    }
    engine_->tick();
    ++ticks_;
    if (scene_.episode_ticks > 0 && ++episode_tick_ == scene_.episode_ticks) {
      check();
      Eigen::VectorXd compared(static_cast<Eigen::Index>(scene_.compared_joints.size()));
      for (std::size_t j = 0; j < scene_.compared_joints.size(); ++j)
        compared[static_cast<Eigen::Index>(j)] = engine_->getJointPosition(
            scene_.compared_joints[j].first, scene_.compared_joints[j].second);
      recordEpisodeEnd(compared);
      engine_->reset();
      episode_tick_ = 0;
      ++episodes_;
    }
  }

  void check() {
    if (!scene_.check || !problem_.empty()) return;
    problem_ = scene_.check(*engine_);
    if (!problem_.empty()) {
      std::ostringstream where;
      where << " (at t=" << engine_->getTime() << " s";
      if (scene_.episode_ticks > 0) where << ", episode " << episodes_ + 1;
      where << ")";
      problem_ += where.str();
    }
  }

  const BenchScene& scene_;
  std::unique_ptr<Engine> engine_;
  std::vector<DriveTarget> targets_;
  long ticks_ = 0;
  long episode_tick_ = 0;
};

}  // namespace

PhysicsSettings makeModelSettings(const BenchScene& scene, const RunOptions& options) {
  PhysicsSettings settings;
  settings.integrator =
      parseIntegrator(options.integrator.empty() ? scene.integrator : options.integrator);
  if (options.accuracy > 0) settings.accuracy = options.accuracy;
  if (options.fixed_step > 0) settings.fixed_step = options.fixed_step;
  if (options.implicit_step > 0) settings.implicit_step = options.implicit_step;
  // MuJoCo has one friction coefficient: use it for both of Simbody's.
  settings.default_material.static_friction = scene.model.friction;
  settings.default_material.dynamic_friction = scene.model.friction;
  return settings;
}

std::string describeIntegrator(const PhysicsSettings& settings) {
  std::ostringstream s;
  s << getIntegratorName(settings.integrator);
  switch (settings.integrator) {
    case Integrator::ImplicitEuler:
      s << " h=" << settings.implicit_step;
      break;
    case Integrator::SemiExplicitEuler:
      s << " h=" << settings.fixed_step;
      break;
    case Integrator::CPodes:
    case Integrator::RkMerson:
      s << " acc=" << settings.accuracy;
      break;
  }
  return s.str();
}

SceneRuns makeModelRuns(const BenchScene& scene, const RunOptions& options) {
  SceneRuns runs;
  const PhysicsSettings settings = makeModelSettings(scene, options);
  runs.integrator = describeIntegrator(settings);
  runs.manibench = std::make_unique<ModelRun>(scene, makeManibenchEngine(scene.model, settings));
  MujocoSettings mujoco;
  mujoco.mjcf.timestep = options.mujoco_dt;
  mujoco.mjcf.integrator =
      options.mujoco_integrator.empty() ? scene.mujoco_integrator : options.mujoco_integrator;
  runs.mujoco = std::make_unique<ModelRun>(scene, makeMujocoEngine(scene.model, mujoco));
  return runs;
}

}  // namespace manibench::bench
