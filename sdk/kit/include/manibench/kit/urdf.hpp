// The joint vector the host will build from a URDF, known before the scene
// exists: a task whose observation layout depends on the model (one value
// per joint of an object named in its configuration) declares that layout
// in describe(), before buildScene loads the URDF.
//
// The host's rules (core/scene/urdf_model.cpp, docs/urdf.md), which
// tests/kit/urdf_joints_test.cpp checks against the host itself: movable
// joints depth first from the root link, each link's child joints in file
// order; fixed joints merged (their child's joints follow in place); a
// planar joint is three joints NAME_x, NAME_y (prismatic) and NAME_yaw
// (continuous); a continuous joint, or lower == upper, has no position
// limit. Only the structure is read: a file this accepts may still be
// refused by the host (a missing mesh, a bad inertia), with its reason.
#pragma once

#include <manibench/kit/common.hpp>

#include <boost/property_tree/ptree.hpp>
#include <boost/property_tree/xml_parser.hpp>

#include <algorithm>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace manibench::kit::urdf {

struct UrdfJoint {
  std::string name;
  std::string type;  // revolute, continuous or prismatic
  std::string parent_link, child_link;
  // Position limits; -inf / +inf where the host applies none.
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
};

struct UrdfJoints {
  std::string root_link;
  std::vector<UrdfJoint> joints;  // the host's joint vector, in its order
  // Index of `name` in the joint vector; throws naming the joints it has.
  std::size_t find(const std::string& name) const {
    std::string names;
    for (std::size_t i = 0; i < joints.size(); ++i) {
      if (joints[i].name == name) return i;
      names += (names.empty() ? "" : ", ") + joints[i].name;
    }
    throw Error("no joint '" + name + "' (joints: " + (names.empty() ? "none" : names) + ")", MB_NOT_FOUND);
  }
};

namespace detail {

inline double parseLimit(const std::string& text, const std::string& source, const std::string& joint,
                         const char* attribute) {
  if (text.empty()) return 0.0;  // urdfdom's default
  std::istringstream in(text);
  double value = 0;
  if (!(in >> value) || !(in >> std::ws).eof())
    throw Error("URDF " + source + ": joint '" + joint + "': <limit " + attribute + "=\"" + text +
                    "\"> is not a number",
                MB_INVALID_ARGUMENT);
  return value;
}

}  // namespace detail

// The joints of URDF text; `source` names it in errors.
inline UrdfJoints inspectUrdf(const std::string& urdf_xml, const std::string& source = "<string>") {
  using boost::property_tree::ptree;
  ptree tree;
  try {
    std::istringstream in(urdf_xml);
    boost::property_tree::read_xml(in, tree, boost::property_tree::xml_parser::no_comments);
  } catch (const boost::property_tree::xml_parser_error& e) {
    throw Error("URDF " + source + ":" + std::to_string(e.line()) + ": not valid XML (" + e.message() + ")",
                MB_INVALID_ARGUMENT);
  }
  const auto robot = tree.get_child_optional("robot");
  if (!robot) throw Error("URDF " + source + ": no <robot> element", MB_INVALID_ARGUMENT);

  struct RawJoint {
    UrdfJoint joint;
    bool fixed = false, planar = false;
  };
  std::vector<std::string> links;
  std::vector<RawJoint> raw;  // file order
  for (const auto& [tag, element] : *robot) {
    const std::string name = element.get<std::string>("<xmlattr>.name", "");
    if (tag == "link") {
      links.push_back(name);
    } else if (tag == "joint") {
      RawJoint r;
      r.joint.name = name;
      const std::string type = element.get<std::string>("<xmlattr>.type", "");
      r.joint.parent_link = element.get<std::string>("parent.<xmlattr>.link", "");
      r.joint.child_link = element.get<std::string>("child.<xmlattr>.link", "");
      if (type == "fixed") {
        r.fixed = true;
      } else if (type == "planar") {
        r.planar = true;
      } else if (type == "revolute" || type == "continuous" || type == "prismatic") {
        r.joint.type = type;
      } else {
        throw Error("URDF " + source + ": joint '" + name + "' has type '" + type +
                        "' (the host takes revolute, continuous, prismatic, planar and fixed inside the tree)",
                    MB_INVALID_ARGUMENT);
      }
      if (const auto limit = element.get_child_optional("limit"); limit && type != "continuous" && !r.planar) {
        const double lower = detail::parseLimit(limit->get<std::string>("<xmlattr>.lower", ""), source, name, "lower");
        const double upper = detail::parseLimit(limit->get<std::string>("<xmlattr>.upper", ""), source, name, "upper");
        if (lower != upper) {
          r.joint.lower = lower;
          r.joint.upper = upper;
        }
      }
      raw.push_back(r);
    }
  }
  std::map<std::string, std::vector<std::size_t>> children;  // parent link -> joints, file order
  std::set<std::string> has_parent;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    children[raw[i].joint.parent_link].push_back(i);
    if (!has_parent.insert(raw[i].joint.child_link).second)
      throw Error("URDF " + source + ": link '" + raw[i].joint.child_link + "' has two parent joints",
                  MB_INVALID_ARGUMENT);
  }
  std::vector<std::string> roots;
  for (const std::string& l : links)
    if (has_parent.count(l) == 0) roots.push_back(l);
  if (roots.size() != 1)
    throw Error("URDF " + source + ": expected one root link, found " + std::to_string(roots.size()),
                MB_INVALID_ARGUMENT);

  UrdfJoints out;
  out.root_link = roots.front();
  std::set<std::string> visited;
  // Recursion by hand: a deep chain must not overflow the stack.
  std::vector<std::pair<std::string, std::size_t>> frames{{out.root_link, 0}};
  visited.insert(out.root_link);
  while (!frames.empty()) {
    auto& [link, next] = frames.back();
    const std::vector<std::size_t>& mine = children[link];
    if (next == mine.size()) {
      frames.pop_back();
      continue;
    }
    const RawJoint& r = raw[mine[next++]];
    if (!visited.insert(r.joint.child_link).second)
      throw Error("URDF " + source + ": joint '" + r.joint.name + "' closes a cycle", MB_INVALID_ARGUMENT);
    if (r.planar) {
      for (const auto& [suffix, type] : {std::pair<const char*, const char*>{"_x", "prismatic"},
                                         {"_y", "prismatic"},
                                         {"_yaw", "continuous"}}) {
        UrdfJoint j = r.joint;
        j.name += suffix;
        j.type = type;
        out.joints.push_back(j);
      }
    } else if (!r.fixed) {
      out.joints.push_back(r.joint);
    }
    const std::string child = r.joint.child_link;  // `link` may dangle after the push
    frames.emplace_back(child, 0);
  }
  return out;
}

// The joints of a URDF file.
inline UrdfJoints inspectUrdfFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("URDF " + path + ": cannot read the file", MB_NOT_FOUND);
  std::stringstream text;
  text << in.rdbuf();
  return inspectUrdf(text.str(), path);
}

}  // namespace manibench::kit::urdf
