// HelloSlider's model: a 0.5 kg block on a 1 m horizontal rail, one
// prismatic joint. Also the model of the evaluation tests' FailingSlider-v0
// (tests/fixtures/fixture_failing_task.cpp), so the two cannot drift apart.
#pragma once

namespace hello_task {

inline const char* const kRailUrdf = R"(<?xml version="1.0"?>
<robot name="rail">
  <link name="rail"/>
  <link name="block">
    <inertial><mass value="0.5"/>
      <inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="rail"/><child link="block"/><axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.5" velocity="0.5" effort="20"/>
  </joint>
</robot>)";

}  // namespace hello_task
