#include "bench_mujoco.hpp"

#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <utility>

namespace manibench::bench {

MujocoSim::MujocoSim(const std::string& mjcf) {
  auto vfs = std::make_unique<mjVFS>();  // ~1 MB: not on the stack
  mj_defaultVFS(vfs.get());
  const char* file = "bench_model.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), file, static_cast<int>(mjcf.size())) != 0)
    throw std::runtime_error("MuJoCo: cannot create the virtual model file");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), file)], mjcf.data(), mjcf.size());
  char error[1024] = "";
  m = mj_loadXML(file, vfs.get(), error, sizeof error);
  mj_deleteVFS(vfs.get());
  if (m == nullptr) throw std::runtime_error(std::string("MuJoCo: cannot load the model: ") + error);
  d = mj_makeData(m);
  if (d == nullptr) {
    mj_deleteModel(m);
    throw std::runtime_error("MuJoCo: mj_makeData failed");
  }
}

MujocoSim::~MujocoSim() {
  mj_deleteData(d);
  mj_deleteModel(m);
}

void MujocoSim::step(const std::vector<int>& balanced_dofs) {
  if (balanced_dofs.empty()) {
    mj_step(m, d);
    return;
  }
  mj_step1(m, d);
  for (int dof : balanced_dofs) d->qfrc_applied[dof] = d->qfrc_bias[dof];
  mj_step2(m, d);
}

void MujocoSim::resetData() {
  for (int i = 0; i < mjNWARNING; ++i) warnings_[i] += d->warning[i].number;
  mj_resetData(m, d);
}

void MujocoSim::checkFinite() const {
  for (int i = 0; i < m->nq; ++i)
    if (!std::isfinite(d->qpos[i]))
      throw std::runtime_error("MuJoCo: non-finite position at t=" + std::to_string(d->time));
  for (int i = 0; i < m->nv; ++i)
    if (!std::isfinite(d->qvel[i]))
      throw std::runtime_error("MuJoCo: non-finite velocity at t=" + std::to_string(d->time));
}

std::string MujocoSim::getProblems() const {
  static const std::pair<int, const char*> kWarnings[] = {
      {mjWARN_CONTACTFULL, "contact buffer full"},
      {mjWARN_CNSTRFULL, "constraint buffer full"},
      {mjWARN_BADQACC, "bad acceleration (data reset)"},
      {mjWARN_BADQPOS, "bad position (data reset)"},
      {mjWARN_BADQVEL, "bad velocity (data reset)"},
      {mjWARN_BADCTRL, "bad control"},
  };
  std::string problems;
  for (const auto& [id, text] : kWarnings)
    if (const long n = warnings_[id] + d->warning[id].number; n > 0)
      problems += (problems.empty() ? "" : "; ") + std::string(text) + " x" + std::to_string(n);
  return problems;
}

int MujocoSim::findId(mjtObj type, const std::string& name) const {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0)
    throw std::invalid_argument("bench: no " + std::string(mju_type2Str(type)) + " '" + name +
                                "' in the MuJoCo model");
  return id;
}

}  // namespace manibench::bench
