// The Slider catalog: rails of three lengths times blocks of three masses,
// nine objects; the heaviest block on each rail is held out for the test
// split (generalization to unseen masses).
#include "slider.hpp"

#include <cstdio>

namespace slider {

namespace {

const double kHalfLengths[] = {0.4, 0.5, 0.6};
const double kMasses[] = {0.3, 0.6, 1.2};

std::string makeId(int length, int mass) { return "rail" + std::to_string(length) + "_mass" + std::to_string(mass); }

}  // namespace

std::vector<std::string> listRails(const std::string& split) {
  if (split != "train" && split != "test")
    throw sdk::Error("Slider-v0: no split '" + split + "' (train or test)", MB_INVALID_ARGUMENT);
  std::vector<std::string> ids;
  for (int l = 0; l < 3; ++l)
    for (int m = 0; m < 3; ++m)
      if ((m == 2) == (split == "test")) ids.push_back(makeId(l, m));
  return ids;
}

Rail getRail(const std::string& id) {
  for (int l = 0; l < 3; ++l)
    for (int m = 0; m < 3; ++m)
      if (id == makeId(l, m)) return {id, kHalfLengths[l], kMasses[m]};
  throw sdk::Error("Slider-v0: no object '" + id + "'", MB_NOT_FOUND);
}

std::string makeRailUrdf(const Rail& rail) {
  char text[1024];
  std::snprintf(text, sizeof text, R"(<?xml version="1.0"?>
<robot name="rail">
  <link name="rail"/>
  <link name="block">
    <inertial><mass value="%.17g"/>
      <inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="rail"/><child link="block"/><axis xyz="1 0 0"/>
    <limit lower="%.17g" upper="%.17g" velocity="0.5" effort="20"/>
  </joint>
</robot>)",
                rail.block_mass, -rail.half_length, rail.half_length);
  return text;
}

}  // namespace slider
