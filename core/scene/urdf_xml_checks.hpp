// What the URDF builder (urdf_model.cpp) checks and repairs in the XML
// before urdfdom reads it: urdfdom accepts non-finite numbers and joint
// graphs that are not trees, and refuses <capsule> and <limit> without
// effort and velocity. Errors are SceneErrors naming the line and element.
#pragma once

#include <manibench/scene.hpp>

#include <tinyxml.h>

#include <set>
#include <string>
#include <utility>

namespace manibench {
namespace scene_detail {

// Throws SceneError "URDF <source>: <what>".
[[noreturn]] inline void failUrdf(const std::string& source, const std::string& what) {
  throw SceneError("URDF " + source + ": " + what);
}

// urdfdom rejects <capsule> (and then drops every collision of the link):
// turn each into a <cylinder> with the same attributes and remember which
// collisions they were (link name, ordinal among the link's collisions or
// visuals). Returns true if anything changed.
bool rewriteCapsules(TiXmlDocument& doc, std::set<std::pair<std::string, int>>& capsules,
                     std::set<std::pair<std::string, int>>& visual_capsules);

// Every numeric attribute of `element` and below must be finite.
void checkNumbersAreFinite(const TiXmlElement& element, const std::string& source);

// The joint graph below <robot> must be a tree.
void checkJointTree(const TiXmlElement& robot, const std::string& source);

// <limit> without effort or velocity completed with 0 ("not limited").
// Returns true if anything changed.
bool completeLimits(TiXmlElement& robot);

}  // namespace scene_detail
}  // namespace manibench
