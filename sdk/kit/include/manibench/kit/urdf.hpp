// One reader of a URDF's tree for the kit: readTree (the XML, links,
// joints with an enum type, checked to be one tree) serves both the joint
// vector below and PartNet's objects (partnet.hpp), so the two cannot
// disagree about what a URDF tree is.
//
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
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace manibench::kit::urdf {

// URDF's joint types. The movable single-axis ones carry abi.h's numbers
// (MB_JOINT_*), which the host's JointDescription uses too.
enum class JointType {
  kRevolute = MB_JOINT_REVOLUTE,
  kContinuous = MB_JOINT_CONTINUOUS,
  kPrismatic = MB_JOINT_PRISMATIC,
  kFixed,
  kFloating,
  kPlanar,
};

namespace detail {
// URDF's words, in JointType's order from kRevolute.
inline constexpr const char* kJointTypeWords[] = {"revolute", "continuous", "prismatic",
                                                  "fixed",    "floating",   "planar"};
}  // namespace detail

// URDF's word for a joint type ("revolute", ...).
inline const char* toString(JointType type) {
  return detail::kJointTypeWords[static_cast<int>(type) - static_cast<int>(JointType::kRevolute)];
}

// The joint type a URDF word names; false for a word URDF does not define.
inline bool parseJointType(const std::string& word, JointType& type) {
  for (int i = 0; i < 6; ++i)
    if (word == detail::kJointTypeWords[i]) {
      type = static_cast<JointType>(i + static_cast<int>(JointType::kRevolute));
      return true;
    }
  return false;
}

// A URDF document and its tree, in file order. The elements point into
// `document`, which a caller may rewrite in place (PartNet scales lengths
// and completes limits); a Tree moves but does not copy.
struct Tree {
  struct Link {
    std::string name;
    boost::property_tree::ptree* element = nullptr;
    int parent_joint = -1;                  // index into joints; -1 for the root
    std::vector<std::size_t> child_joints;  // file order
  };
  struct Joint {
    std::string name;
    JointType type = JointType::kFixed;
    std::string parent, child;  // link names
    std::size_t child_link = 0;  // index into links
    boost::property_tree::ptree* element = nullptr;
  };
  std::unique_ptr<boost::property_tree::ptree> document;
  std::vector<Link> links;    // file order
  std::vector<Joint> joints;  // file order
  std::size_t root = 0;       // index into links: the one link that is nobody's child

  // Links from the root, parents before children, breadth first, each
  // link's children in file order.
  std::vector<std::size_t> listBreadthFirst() const {
    std::vector<std::size_t> order{root};
    for (std::size_t i = 0; i < order.size(); ++i)
      for (const std::size_t j : links[order[i]].child_joints) order.push_back(joints[j].child_link);
    return order;
  }
};

// Reads URDF text as a tree. Refused, each naming `where` (e.g. "URDF
// arm.urdf") and the element: XML that does not parse (with its line), no
// <robot>, a link without a name or twice, a joint without a name, with a
// type URDF does not define, without <parent link> or <child link>, naming
// a link that is not there; a link with two parent joints; not exactly one
// root link; joints that form a loop.
inline Tree readTree(std::istream& in, const std::string& where) {
  using boost::property_tree::ptree;
  Tree tree;
  tree.document = std::make_unique<ptree>();
  try {
    boost::property_tree::read_xml(in, *tree.document, boost::property_tree::xml_parser::no_comments);
  } catch (const boost::property_tree::xml_parser_error& e) {
    throw Error(where + ":" + std::to_string(e.line()) + ": not valid XML (" + e.message() + ")",
                MB_INVALID_ARGUMENT);
  }
  const auto robot = tree.document->get_child_optional("robot");
  if (!robot) throw Error(where + ": no <robot> element", MB_INVALID_ARGUMENT);

  std::map<std::string, std::size_t> link_index;
  for (auto& [tag, element] : *robot) {
    const std::string name = element.get<std::string>("<xmlattr>.name", "");
    if (tag == "link") {
      if (name.empty()) throw Error(where + ": a <link> has no name", MB_INVALID_ARGUMENT);
      if (!link_index.emplace(name, tree.links.size()).second)
        throw Error(where + ": link '" + name + "' appears twice", MB_INVALID_ARGUMENT);
      tree.links.push_back({name, &element, -1, {}});
    } else if (tag == "joint") {
      Tree::Joint joint;
      joint.name = name;
      joint.element = &element;
      const std::string what = where + ": joint '" + name + "'";
      const std::string type = element.get<std::string>("<xmlattr>.type", "");
      if (name.empty() || !parseJointType(type, joint.type))
        throw Error(what + " has type '" + type +
                        "' (expected revolute, continuous, prismatic, fixed, floating or planar)",
                    MB_INVALID_ARGUMENT);
      joint.parent = element.get<std::string>("parent.<xmlattr>.link", "");
      joint.child = element.get<std::string>("child.<xmlattr>.link", "");
      if (joint.parent.empty() || joint.child.empty())
        throw Error(what + " lacks <parent link> or <child link>", MB_INVALID_ARGUMENT);
      tree.joints.push_back(std::move(joint));
    }
  }
  if (tree.links.empty()) throw Error(where + " has no <link>", MB_INVALID_ARGUMENT);

  for (std::size_t j = 0; j < tree.joints.size(); ++j) {
    Tree::Joint& joint = tree.joints[j];
    for (const std::string& name : {joint.parent, joint.child})
      if (link_index.count(name) == 0)
        throw Error(where + ": joint '" + joint.name + "' names link '" + name + "', which is not there",
                    MB_INVALID_ARGUMENT);
    joint.child_link = link_index.at(joint.child);
    Tree::Link& child = tree.links[joint.child_link];
    if (child.parent_joint >= 0)
      throw Error(where + ": link '" + joint.child + "' has two parent joints", MB_INVALID_ARGUMENT);
    child.parent_joint = static_cast<int>(j);
    tree.links[link_index.at(joint.parent)].child_joints.push_back(j);
  }
  std::vector<std::size_t> roots;
  for (std::size_t l = 0; l < tree.links.size(); ++l)
    if (tree.links[l].parent_joint < 0) roots.push_back(l);
  if (roots.size() != 1)
    throw Error(where + ": expected one root link, found " + std::to_string(roots.size()), MB_INVALID_ARGUMENT);
  tree.root = roots.front();
  if (tree.listBreadthFirst().size() != tree.links.size())
    throw Error(where + ": the joints form a loop", MB_INVALID_ARGUMENT);
  return tree;
}

struct UrdfJoint {
  std::string name;
  JointType type = JointType::kRevolute;  // revolute, continuous or prismatic
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

// The host's joint (or joints) for one URDF joint: none for a fixed one,
// three for a planar one.
inline void appendHostJoints(const Tree::Joint& joint, const std::string& source, std::vector<UrdfJoint>& out) {
  if (joint.type == JointType::kFixed) return;
  if (joint.type == JointType::kFloating)
    throw Error("URDF " + source + ": joint '" + joint.name +
                    "' has type 'floating' (the host takes revolute, continuous, prismatic, planar and fixed "
                    "inside the tree)",
                MB_INVALID_ARGUMENT);
  UrdfJoint j;
  j.name = joint.name;
  j.type = joint.type;
  j.parent_link = joint.parent;
  j.child_link = joint.child;
  if (joint.type == JointType::kPlanar) {
    for (const auto& [suffix, type] : {std::pair<const char*, JointType>{"_x", JointType::kPrismatic},
                                       {"_y", JointType::kPrismatic},
                                       {"_yaw", JointType::kContinuous}}) {
      out.push_back(j);
      out.back().name += suffix;
      out.back().type = type;
    }
    return;
  }
  if (const auto limit = joint.element->get_child_optional("limit"); limit && joint.type != JointType::kContinuous) {
    const double lower = parseLimit(limit->get<std::string>("<xmlattr>.lower", ""), source, joint.name, "lower");
    const double upper = parseLimit(limit->get<std::string>("<xmlattr>.upper", ""), source, joint.name, "upper");
    if (lower != upper) {
      j.lower = lower;
      j.upper = upper;
    }
  }
  out.push_back(j);
}

}  // namespace detail

// The joints of URDF text; `source` names it in errors.
inline UrdfJoints inspectUrdf(const std::string& urdf_xml, const std::string& source = "<string>") {
  std::istringstream in(urdf_xml);
  const Tree tree = readTree(in, "URDF " + source);
  UrdfJoints out;
  out.root_link = tree.links[tree.root].name;
  // Depth first, by hand: a deep chain must not overflow the stack.
  std::vector<std::pair<std::size_t, std::size_t>> frames{{tree.root, 0}};  // link, next child joint
  while (!frames.empty()) {
    auto& [link, next] = frames.back();
    const std::vector<std::size_t>& mine = tree.links[link].child_joints;
    if (next == mine.size()) {
      frames.pop_back();
      continue;
    }
    const Tree::Joint& joint = tree.joints[mine[next++]];
    detail::appendHostJoints(joint, source, out.joints);
    frames.emplace_back(joint.child_link, 0);  // `link` and `next` may dangle after this
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
