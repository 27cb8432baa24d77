// The one C++ segment type: a named slice [offset, offset + size) of a flat
// vector (an observation, an action), on both sides of the ABI. A plugin
// describes its layout in order (TaskSpec::observation,
// ControllerSpec::action: name, size, description; the SDK fills the
// offsets); a policy reads the host's layout (Layout::segments); the host
// keeps the plugins' layouts (TaskDescription, ControllerDescription). Only
// the C record mb_segment crosses the boundary (abi.h), so this type may
// grow without touching the ABI: fromC and toC are the two crossings.
#pragma once

#include <manibench/abi.h>

#include <cstdint>
#include <string>

namespace manibench::sdk {

struct Segment {
  std::string name;
  uint32_t size = 0;
  std::string description;
  // Where the slice starts; in a spec written in order, 0 until the SDK
  // fills it from the order (SegmentTable).
  uint32_t offset = 0;

  static Segment fromC(const mb_segment& s) {
    return {s.name ? s.name : "", s.size, s.description ? s.description : "", s.offset};
  }
  // Points into this Segment: valid while it lives unchanged.
  mb_segment toC() const { return {name.c_str(), offset, size, description.c_str()}; }
};

}  // namespace manibench::sdk
