// What both MuJoCo sides of the benchmark share (the bench::Model scenes and
// the cabinet twin): loading MJCF from memory, the substep with passive-
// force balancing, and MuJoCo's warnings.
#pragma once

#include <mujoco/mujoco.h>

#include <string>
#include <vector>

namespace manibench::bench {

// An mjModel and its mjData, loaded from an MJCF document held in memory
// (a virtual file: no temporary files, no clashes between runs).
class MujocoSim {
 public:
  // Throws std::runtime_error with MuJoCo's message if the model is refused.
  explicit MujocoSim(const std::string& mjcf);
  ~MujocoSim();
  MujocoSim(const MujocoSim&) = delete;
  MujocoSim& operator=(const MujocoSim&) = delete;

  mjModel* m = nullptr;
  mjData* d = nullptr;

  // One mj_step. Passive-force balancing (supplement B.7): qfrc_bias,
  // gravity plus Coriolis at this state, applied on the balanced dofs
  // before the forces are summed (MuJoCo 2.2.2 has no gravcomp).
  void step(const std::vector<int>& balanced_dofs);
  // mj_resetData, keeping the warning counts it clears.
  void resetData();
  // Throws std::runtime_error if a position or velocity is not finite.
  void checkFinite() const;
  // MuJoCo's warnings so far (full buffers, bad accelerations and the
  // resets they cause); "" if none.
  std::string getProblems() const;
  // Finds a named object; throws std::invalid_argument naming it if absent.
  int findId(mjtObj type, const std::string& name) const;

 private:
  long warnings_[mjNWARNING] = {};  // counted before the last reset
};

}  // namespace manibench::bench
