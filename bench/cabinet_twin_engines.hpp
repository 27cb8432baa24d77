// The cabinet twin's two engines (cabinet_twin.cpp runs and checks them):
// manibench's real Environment and MuJoCo's converted scene, each behind
// TwinEngine, and what both read: the episode's facts and a snapshot of the
// state. A concern of its own beside the checks and the timed run.
#pragma once

#include <manibench/environment.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/sdk/numbers.hpp>
#include <manibench/sdk/random.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_mujoco.hpp"
#include "mobile_panda_law.hpp"
#include "urdf_twin.hpp"

namespace manibench::bench::cabinet_twin {

enum Part { kRobot = 0, kCabinet = 1 };

// The cabinet's per-episode joint damping and friction. The task draws
// them at each reset (open_cabinet_task.cpp: splitmix64 seeded with
// seed ^ "open_cab", three draws for the robot's placement, then per
// cabinet joint friction U(0.05, 0.15) and damping U(5, 20)), and the
// scene keeps them where no public call reads them. The bench repeats
// that draw and sets the values in both engines: the manibench scene is
// then unchanged if the copy is right, and both engines agree even if it
// is not (the heading check below says which).
struct CabinetDynamics {
  std::vector<double> damping, friction;
  bool matches_task = false;
};

inline CabinetDynamics drawCabinetDynamics(std::uint64_t seed, std::size_t joints, double robot_yaw) {
  sdk::Random rng(seed ^ 0x6f70656e5f636162ULL);  // the task's own generator
  auto uniform = [&rng](double lo, double hi) { return rng.uniform(lo, hi); };
  using sdk::kPi;
  uniform(1.6, 1.8);  // distance
  const double around = uniform(0.9 * kPi, 1.1 * kPi);
  const double heading = around + kPi + uniform(-0.05 * kPi, 0.05 * kPi);
  CabinetDynamics out;
  out.matches_task = std::abs(std::remainder(heading, 2 * kPi) - robot_yaw) < 1e-12;
  for (std::size_t j = 0; j < joints; ++j) {
    out.friction.push_back(uniform(0.05, 0.15));
    out.damping.push_back(uniform(5.0, 20.0));
  }
  return out;
}

struct TwinFacts {
  std::string object;
  std::uint64_t seed = 0;
  int episode_steps = 200;
  int frame_skip = 5;
  double control_dt = 0.01;
  std::vector<TwinPlacement> placements;  // [kRobot], [kCabinet]
  Eigen::VectorXd initial_q[2];           // manibench's joint order
  Eigen::Isometry3d cabinet_root = Eigen::Isometry3d::Identity();
  CabinetDynamics cabinet_dynamics;
};

// One engine's state as the checks read it.
struct TwinSnapshot {
  Eigen::VectorXd q[2], v[2];               // manibench's joint order
  std::vector<Eigen::Isometry3d> links[2];  // per TwinArticulation link
};

class TwinEngine {
 public:
  virtual ~TwinEngine() = default;
  // Back to the episode's initial state (the task's reset).
  virtual void reset() = 0;
  // One env step (frame_skip control ticks); throws if the simulation broke.
  virtual void step(const Eigen::VectorXd& action) = 0;
  virtual TwinSnapshot snapshot() const = 0;
  // Passive-force balancing on the robot's actuated joints (on by default,
  // as mobile_panda asks; reset() does not change it).
  virtual void setBalancing(bool on) = 0;
  virtual std::string getProblems() const { return {}; }
  virtual IntegratorStatistics getIntegratorStatistics() const { return {}; }
  // What the engine counted of its contacts, or "".
  virtual std::string describeContacts() const { return {}; }
};

// manibench: the real environment.
class ManibenchTwin final : public TwinEngine {
 public:
  ManibenchTwin(std::shared_ptr<PluginRegistry> registry, std::unique_ptr<Environment> env,
                std::shared_ptr<const TwinFacts> facts)
      : registry_(std::move(registry)), env_(std::move(env)), facts_(std::move(facts)) {
    const Scene& scene = env_->getScene();
    const TaskDescription& task = env_->getTaskDescription();
    robot_ = scene.findArticulation(task.robot_articulation);
    cabinet_ = scene.findArticulation("cabinet");
    for (const std::string& name : task.actuated_joints) actuated_.push_back(scene.findJoint(robot_, name));
    const int ids[2] = {robot_, cabinet_};
    for (int part : {kRobot, kCabinet})
      for (const TwinLink& link : facts_->placements[part].articulation.links)
        link_ids_[part].push_back(scene.findLink(ids[part], link.name));
  }

  void reset() override {
    env_->reset(facts_->object, facts_->seed);
    const CabinetDynamics& d = facts_->cabinet_dynamics;
    for (std::size_t j = 0; j < d.damping.size(); ++j)
      env_->updScene().setJointDynamics(cabinet_, int(j), d.damping[j], d.friction[j]);
    // The reset restored the environment's balancing.
    if (!balancing_) env_->updScene().setPassiveForceBalancing(robot_, actuated_, false);
  }

  void step(const Eigen::VectorXd& action) override { env_->step(action); }

  void setBalancing(bool on) override {
    balancing_ = on;
    env_->updScene().setPassiveForceBalancing(robot_, actuated_, on);
  }

  // One env step as Environment::step takes it, but with the bench's copy
  // of the drive law in place of the controller plugin.
  void stepWithLaw(const Eigen::VectorXd& action, MobilePandaLaw& law) {
    const Eigen::VectorXd clipped = action.cwiseMax(-1.0).cwiseMin(1.0);
    Scene& scene = env_->updScene();
    std::vector<DriveCommand> commands;
    for (int k = 0; k < facts_->frame_skip; ++k) {
      law.compute(clipped, scene.getJointPositions(robot_)[2], commands);
      scene.setDriveCommands(robot_, actuated_, commands);
      scene.advance(facts_->control_dt);
    }
  }

  TwinSnapshot snapshot() const override {
    const Scene& scene = env_->getScene();
    TwinSnapshot s;
    const int ids[2] = {robot_, cabinet_};
    for (int part : {kRobot, kCabinet}) {
      s.q[part] = scene.getJointPositions(ids[part]);
      s.v[part] = scene.getJointVelocities(ids[part]);
      for (int link : link_ids_[part]) {
        const Pose pose = scene.getLinkPose(link);
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.linear() = pose.orientation.toRotationMatrix();
        X.translation() = pose.position;
        s.links[part].push_back(X);
      }
    }
    return s;
  }

  IntegratorStatistics getIntegratorStatistics() const override {
    return env_->getScene().getIntegratorStatistics();
  }

 private:
  std::shared_ptr<PluginRegistry> registry_;  // the environment's plugins
  std::unique_ptr<Environment> env_;
  std::shared_ptr<const TwinFacts> facts_;
  int robot_ = -1, cabinet_ = -1;
  std::vector<int> actuated_;
  bool balancing_ = true;
  std::vector<int> link_ids_[2];
};

// MuJoCo: the converted scene, driven by the copied drive law.
class MujocoTwin final : public TwinEngine {
 public:
  MujocoTwin(std::shared_ptr<const TwinFacts> facts, const std::string& mjcf)
      : facts_(std::move(facts)), sim_(mjcf), law_(1.0 / facts_->control_dt) {
    const mjModel* m = sim_.m;
    substeps_ = static_cast<int>(std::lround(facts_->control_dt / m->opt.timestep));
    if (substeps_ < 1 || std::abs(substeps_ * m->opt.timestep - facts_->control_dt) > 1e-12)
      throw std::invalid_argument("MuJoCo: the timestep must divide the control tick");
    for (int part : {kRobot, kCabinet}) {
      const TwinPlacement& p = facts_->placements[part];
      for (const JointDescription& joint : p.joints) {
        const int id = sim_.findId(mjOBJ_JOINT, p.articulation.name + "/" + joint.name);
        qpos_[part].push_back(m->jnt_qposadr[id]);
        dof_[part].push_back(m->jnt_dofadr[id]);
      }
      for (const TwinLink& link : p.articulation.links)
        bodies_[part].push_back(sim_.findId(mjOBJ_BODY, p.articulation.name + "/" + link.name));
    }
    // Actuators are the law's joints in its order; all are balanced, as
    // mobile_panda asks of the host.
    for (const std::string& name : MobilePandaLaw::getJointNames()) {
      const int id = sim_.findId(mjOBJ_JOINT, "robot/" + name);
      balanced_dofs_.push_back(m->jnt_dofadr[id]);
      if (name == "root_yaw") yaw_qpos_ = m->jnt_qposadr[id];
    }
  }

  void reset() override {
    sim_.resetData();
    for (int part : {kRobot, kCabinet})
      for (std::size_t j = 0; j < qpos_[part].size(); ++j)
        sim_.d->qpos[qpos_[part][j]] = facts_->initial_q[part][Eigen::Index(j)];
    law_.reset();
    for (int i = 0; i < sim_.m->nu; ++i) setDrive(sim_.m, sim_.d, i, DriveCommand{});
    mj_forward(sim_.m, sim_.d);
  }

  void step(const Eigen::VectorXd& action) override {
    const Eigen::VectorXd clipped = action.cwiseMax(-1.0).cwiseMin(1.0);
    for (int k = 0; k < facts_->frame_skip; ++k) {
      law_.compute(clipped, sim_.d->qpos[yaw_qpos_], commands_);
      for (std::size_t i = 0; i < commands_.size(); ++i) setDrive(sim_.m, sim_.d, int(i), commands_[i]);
      for (int s = 0; s < substeps_; ++s) {
        sim_.step(balancing_ ? balanced_dofs_ : no_dofs_);
        contacts_ += sim_.d->ncon;
        most_contacts_ = std::max(most_contacts_, sim_.d->ncon);
        ++steps_;
      }
    }
    sim_.checkFinite();
  }

  void setBalancing(bool on) override { balancing_ = on; }

  std::string describeContacts() const override {
    char buffer[120];
    std::snprintf(buffer, sizeof buffer, "; %.2f contacts per mj_step on average, at most %d",
                  steps_ > 0 ? double(contacts_) / double(steps_) : 0.0, most_contacts_);
    return buffer;
  }

  TwinSnapshot snapshot() const override {
    mj_kinematics(sim_.m, sim_.d);  // link poses of the current positions
    TwinSnapshot s;
    for (int part : {kRobot, kCabinet}) {
      const std::size_t n = qpos_[part].size();
      s.q[part].resize(Eigen::Index(n));
      s.v[part].resize(Eigen::Index(n));
      for (std::size_t j = 0; j < n; ++j) {
        s.q[part][Eigen::Index(j)] = sim_.d->qpos[qpos_[part][j]];
        s.v[part][Eigen::Index(j)] = sim_.d->qvel[dof_[part][j]];
      }
      for (int body : bodies_[part]) {
        const mjtNum* p = sim_.d->xpos + 3 * body;
        const mjtNum* q = sim_.d->xquat + 4 * body;
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
        X.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
        s.links[part].push_back(X);
      }
    }
    return s;
  }

  std::string getProblems() const override { return sim_.getProblems(); }

 private:
  std::shared_ptr<const TwinFacts> facts_;
  MujocoSim sim_;
  MobilePandaLaw law_;
  int substeps_ = 1;
  int yaw_qpos_ = 0;
  std::vector<int> qpos_[2], dof_[2], bodies_[2];
  std::vector<int> balanced_dofs_, no_dofs_;
  bool balancing_ = true;
  std::vector<DriveCommand> commands_;
  long contacts_ = 0, steps_ = 0;
  int most_contacts_ = 0;
};

}  // namespace manibench::bench::cabinet_twin
