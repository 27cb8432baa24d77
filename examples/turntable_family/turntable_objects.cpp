// The Turntable catalog: rods of three lengths times three masses, nine
// objects; the heaviest rod of each length is held out for the test split
// (generalization to unseen inertia).
#include "turntable.hpp"

#include <sstream>

namespace turntable {

namespace {

const double kLengths[] = {0.2, 0.3, 0.4};
const double kMasses[] = {0.3, 0.6, 1.2};

std::string makeId(int length, int mass) { return "arm" + std::to_string(length) + "_mass" + std::to_string(mass); }

}  // namespace

std::vector<std::string> listArms(const std::string& split) {
  if (split != "train" && split != "test")
    throw sdk::Error("Turntable-v0: no split '" + split + "' (train or test)", MB_INVALID_ARGUMENT);
  std::vector<std::string> ids;
  for (int l = 0; l < 3; ++l)
    for (int m = 0; m < 3; ++m)
      if ((m == 2) == (split == "test")) ids.push_back(makeId(l, m));
  return ids;
}

Arm getArm(const std::string& id) {
  for (int l = 0; l < 3; ++l)
    for (int m = 0; m < 3; ++m)
      if (id == makeId(l, m)) return {id, kLengths[l], kMasses[m]};
  throw sdk::Error("Turntable-v0: no object '" + id + "'", MB_NOT_FOUND);
}

std::string makeArmUrdf(const Arm& arm) {
  // A rod along x from the hinge: its centre of mass halfway, inertia
  // m L^2 / 12 about its centre (a thin rod), a box for the renderer.
  const double centre = arm.length / 2, across = arm.mass * arm.length * arm.length / 12;
  std::ostringstream urdf;
  urdf.precision(17);
  urdf << "<robot name='turntable'><link name='base'/>"
       << "<link name='rod'><inertial><origin xyz='" << centre << " 0 0'/><mass value='" << arm.mass << "'/>"
       << "<inertia ixx='1e-4' ixy='0' ixz='0' iyy='" << across << "' iyz='0' izz='" << across << "'/></inertial>"
       << "<visual><origin xyz='" << centre << " 0 0'/><geometry><box size='" << arm.length
       << " 0.03 0.03'/></geometry></visual></link>"
       << "<joint name='hinge' type='revolute'><parent link='base'/><child link='rod'/><axis xyz='0 0 1'/>"
       << "<limit lower='-3' upper='3' velocity='2' effort='20'/></joint></robot>";
  return urdf.str();
}

}  // namespace turntable
