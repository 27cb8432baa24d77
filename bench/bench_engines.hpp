// The two engines behind one small interface: manibench::Scene (Simbody) and
// MuJoCo 2.2.2, each built from the same bench::Model and advanced one
// control tick at a time with the same drive targets.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "bench_model.hpp"
#include "bench_run.hpp"
#include "manibench/scene.hpp"

namespace manibench::bench {

class Engine {
 public:
  virtual ~Engine() = default;
  // One drive target per Model::drives entry; they hold until replaced.
  virtual void setTargets(const std::vector<DriveTarget>& targets) = 0;
  // Advances one control tick. Throws std::runtime_error (for manibench a
  // SimulationDiverged) if the simulation broke.
  virtual void tick() = 0;
  // Back to the state right after construction (initial joints, targets).
  virtual void reset() = 0;

  virtual double getTime() const = 0;
  virtual double getJointPosition(int articulation, const std::string& joint) const = 0;
  virtual double getJointVelocity(int articulation, const std::string& joint) const = 0;
  virtual Eigen::Vector3d getRootPosition(int articulation) const = 0;
  // Empty if the engine reports nothing wrong so far (MuJoCo's warnings:
  // full contact buffers, bad accelerations and the resets they cause).
  virtual std::string getProblems() const { return {}; }
  // manibench's integrator work so far; all zero for MuJoCo.
  virtual IntegratorStatistics getIntegratorStatistics() const { return {}; }
};

std::unique_ptr<Engine> makeManibenchEngine(const Model& model, const PhysicsSettings& settings);

struct MujocoSettings {
  MjcfOptions mjcf;
};
std::unique_ptr<Engine> makeMujocoEngine(const Model& model, const MujocoSettings& settings);

}  // namespace manibench::bench
