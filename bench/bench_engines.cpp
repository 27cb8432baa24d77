#include "bench_engines.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "bench_mujoco.hpp"

namespace manibench::bench {
namespace {

// --- manibench::Scene ---------------------------------------------------------

class ManibenchEngine final : public Engine {
 public:
  ManibenchEngine(const Model& model, const PhysicsSettings& settings) : scene_(settings) {
    if (model.ground) scene_.addGround(0);
    for (const Articulation& art : model.articulations) {
      Pose root;
      root.position = art.root_position;
      scene_.addUrdfString(toUrdf(art), "", art.name, root, art.fixed_base);
    }
    scene_.finalize();

    std::vector<Eigen::VectorXd> q(model.articulations.size());
    for (std::size_t a = 0; a < q.size(); ++a) q[a] = scene_.getJointPositions(static_cast<int>(a));
    for (const Model::InitialJoint& init : model.initial_joints)
      q.at(init.articulation)[findJoint(init.articulation, init.joint)] = init.position;
    for (std::size_t a = 0; a < q.size(); ++a)
      if (q[a].size() > 0) scene_.setJointPositions(static_cast<int>(a), q[a]);

    // Drives grouped by articulation, one setDriveCommands call each.
    groups_.resize(model.articulations.size());
    for (std::size_t d = 0; d < model.drives.size(); ++d) {
      const Drive& drive = model.drives[d];
      Group& group = groups_.at(drive.articulation);
      const int joint = findJoint(drive.articulation, drive.joint);
      DriveCommand command;
      command.stiffness = drive.stiffness;
      command.damping = drive.damping;
      command.position_target = q[drive.articulation][joint];
      group.joints.push_back(joint);
      group.commands.push_back(command);
      group.drive_index.push_back(static_cast<int>(d));
      if (drive.balanced) group.balanced.push_back(joint);
    }
    for (std::size_t a = 0; a < groups_.size(); ++a) {
      const Group& group = groups_[a];
      if (!group.joints.empty()) scene_.setDriveCommands(static_cast<int>(a), group.joints, group.commands);
      if (!group.balanced.empty())
        scene_.setPassiveForceBalancing(static_cast<int>(a), group.balanced, true);
    }
    initial_ = scene_.saveState();
  }

  void setTargets(const std::vector<DriveTarget>& targets) override {
    for (std::size_t a = 0; a < groups_.size(); ++a) {
      Group& group = groups_[a];
      if (group.joints.empty()) continue;
      for (std::size_t i = 0; i < group.joints.size(); ++i) {
        const DriveTarget& target = targets.at(group.drive_index[i]);
        group.commands[i].position_target = target.position;
        group.commands[i].velocity_target = target.velocity;
      }
      scene_.setDriveCommands(static_cast<int>(a), group.joints, group.commands);
    }
  }

  void tick() override { scene_.advance(kControlDt); }
  void reset() override { scene_.restoreState(initial_); }
  double getTime() const override { return scene_.getTime(); }

  double getJointPosition(int articulation, const std::string& joint) const override {
    return scene_.getJointPositions(articulation)[findJoint(articulation, joint)];
  }
  double getJointVelocity(int articulation, const std::string& joint) const override {
    return scene_.getJointVelocities(articulation)[findJoint(articulation, joint)];
  }
  IntegratorStatistics getIntegratorStatistics() const override {
    return scene_.getIntegratorStatistics();
  }
  Eigen::Vector3d getRootPosition(int articulation) const override {
    return scene_.getRootPose(articulation).position;
  }

 private:
  struct Group {
    std::vector<int> joints;
    std::vector<DriveCommand> commands;
    std::vector<int> drive_index;  // into Model::drives
    std::vector<int> balanced;
  };

  int findJoint(int articulation, const std::string& name) const {
    const int j = scene_.findJoint(articulation, name);
    if (j < 0) throw std::invalid_argument("bench: no joint '" + name + "' in the manibench scene");
    return j;
  }

  Scene scene_;
  std::vector<Group> groups_;
  SceneState initial_;
};

// --- MuJoCo -------------------------------------------------------------------

class MujocoEngine final : public Engine {
 public:
  MujocoEngine(const Model& model, const MujocoSettings& settings)
      : model_(model), sim_(toMjcf(model, settings.mjcf)), m_(sim_.m), d_(sim_.d) {
    for (const Model::InitialJoint& init : model.initial_joints)
      d_->qpos[m_->jnt_qposadr[findJoint(init.articulation, init.joint)]] = init.position;
    mj_forward(m_, d_);
    initial_qpos_.assign(d_->qpos, d_->qpos + m_->nq);

    substeps_ = static_cast<int>(std::lround(kControlDt / m_->opt.timestep));
    if (substeps_ < 1 || std::abs(substeps_ * m_->opt.timestep - kControlDt) > 1e-12)
      throw std::invalid_argument("MuJoCo: the timestep must divide the 10 ms control tick");
    for (std::size_t i = 0; i < model.drives.size(); ++i) {
      const Drive& drive = model.drives[i];
      const int joint = findJoint(drive.articulation, drive.joint);
      if (drive.balanced) balanced_dofs_.push_back(m_->jnt_dofadr[joint]);
      const double q0 = d_->qpos[m_->jnt_qposadr[joint]];
      d_->ctrl[i] = drive.stiffness * q0;  // hold the initial position
    }
    initial_ctrl_.assign(d_->ctrl, d_->ctrl + m_->nu);
  }

  void setTargets(const std::vector<DriveTarget>& targets) override {
    for (std::size_t i = 0; i < model_.drives.size(); ++i) {
      const Drive& drive = model_.drives[i];
      d_->ctrl[i] = drive.stiffness * targets.at(i).position + drive.damping * targets.at(i).velocity;
    }
  }

  void tick() override {
    for (int i = 0; i < substeps_; ++i) sim_.step(balanced_dofs_);
    sim_.checkFinite();
  }

  void reset() override {
    sim_.resetData();
    std::copy(initial_qpos_.begin(), initial_qpos_.end(), d_->qpos);
    std::copy(initial_ctrl_.begin(), initial_ctrl_.end(), d_->ctrl);
    mj_forward(m_, d_);
  }

  double getTime() const override { return d_->time; }

  double getJointPosition(int articulation, const std::string& joint) const override {
    return d_->qpos[m_->jnt_qposadr[findJoint(articulation, joint)]];
  }
  double getJointVelocity(int articulation, const std::string& joint) const override {
    return d_->qvel[m_->jnt_dofadr[findJoint(articulation, joint)]];
  }
  Eigen::Vector3d getRootPosition(int articulation) const override {
    const Articulation& art = model_.articulations.at(articulation);
    if (art.fixed_base) return art.root_position;
    const int joint = sim_.findId(mjOBJ_JOINT, mjcfName(art, "root"));
    const mjtNum* q = d_->qpos + m_->jnt_qposadr[joint];
    return Eigen::Vector3d(q[0], q[1], q[2]);
  }

  std::string getProblems() const override { return sim_.getProblems(); }

 private:
  int findJoint(int articulation, const std::string& joint) const {
    return sim_.findId(mjOBJ_JOINT, mjcfName(model_.articulations.at(articulation), joint));
  }

  const Model& model_;
  MujocoSim sim_;
  mjModel* m_;
  mjData* d_;
  int substeps_ = 1;
  std::vector<int> balanced_dofs_;
  std::vector<mjtNum> initial_qpos_;
  std::vector<mjtNum> initial_ctrl_;
};

}  // namespace

std::unique_ptr<Engine> makeManibenchEngine(const Model& model, const PhysicsSettings& settings) {
  return std::make_unique<ManibenchEngine>(model, settings);
}

std::unique_ptr<Engine> makeMujocoEngine(const Model& model, const MujocoSettings& settings) {
  return std::make_unique<MujocoEngine>(model, settings);
}

}  // namespace manibench::bench
