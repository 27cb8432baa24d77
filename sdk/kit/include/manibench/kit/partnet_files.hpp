// The files of a PartNet-Mobility object besides mobility.urdf (which
// partnet.hpp reads): its OBJ meshes (vertices, triangles), semantics.txt
// (what each link is) and result.json (which mesh is which part). Errors
// name the file and line.
#pragma once

#include <manibench/kit/common.hpp>

// (Boost 1.74's JSON reader includes boost/bind.hpp, which warns unless
// told that its global placeholders are wanted; nothing here uses them.)
#ifndef BOOST_BIND_GLOBAL_PLACEHOLDERS
#define BOOST_BIND_GLOBAL_PLACEHOLDERS
#endif
#include <boost/property_tree/json_parser.hpp>
#include <boost/property_tree/ptree.hpp>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace manibench::kit::partnet {

// One line of semantics.txt: 'link_N <kind> <label>', the kinds being
// PartNet-Mobility's joint types: hinge (revolute or continuous), slider
// (prismatic), slider+ (a slider with a hinge on it: the URDF puts a
// massless link_N_helper between the two joints, as an office chair's seat
// that rises and turns), free (a part that moves with no joint of its own,
// e.g. a chair's base), heavy (the body), static (a fixed part).
struct Semantic {
  std::string link;
  std::string kind;   // hinge, slider, slider+, free, heavy, static
  std::string label;  // e.g. door, drawer, seat, wheel, caster
};

// The vertices of an OBJ file ('v x y z' lines), multiplied by `scale`.
inline std::vector<Eigen::Vector3d> readObjVertices(const std::string& path,
                                                    const Eigen::Vector3d& scale = Eigen::Vector3d::Ones()) {
  std::ifstream in(path);
  if (!in) throw Error("PartNet: cannot read mesh " + path, MB_NOT_FOUND);
  std::vector<Eigen::Vector3d> out;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.size() < 2 || line[0] != 'v' || (line[1] != ' ' && line[1] != '\t')) continue;
    std::istringstream s(line.substr(2));
    Eigen::Vector3d v;
    if (!(s >> v.x() >> v.y() >> v.z()) || !v.allFinite())
      throw Error("PartNet: " + path + ":" + std::to_string(number) + ": bad vertex line '" + line + "'",
                  MB_INVALID_ARGUMENT);
    out.push_back(v.cwiseProduct(scale));
  }
  return out;
}

// An OBJ file's vertices (multiplied by `scale`) and triangles.
struct ObjMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
};

// The vertices and the triangles of an OBJ file's 'f' lines (polygons
// fanned; 'a/b/c' indices, negative ones counting back from the last
// vertex so far). Errors name the file and line.
inline ObjMesh readObjMesh(const std::string& path, const Eigen::Vector3d& scale = Eigen::Vector3d::Ones()) {
  ObjMesh mesh;
  mesh.vertices = readObjVertices(path, scale);
  std::ifstream in(path);
  long seen = 0;  // vertices so far
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    const bool blank = line.size() > 1 && (line[1] == ' ' || line[1] == '\t');
    if (blank && line[0] == 'v') ++seen;
    if (!blank || line[0] != 'f') continue;
    std::istringstream tokens(line.substr(2));
    std::vector<uint32_t> face;
    for (std::string token; tokens >> token;) {
      long i = std::strtol(token.c_str(), nullptr, 10);
      if (i < 0) i += seen + 1;
      if (i < 1 || i > long(mesh.vertices.size()))
        throw Error("PartNet: " + path + ":" + std::to_string(number) + ": bad face index '" + token + "'",
                    MB_INVALID_ARGUMENT);
      face.push_back(uint32_t(i - 1));
    }
    for (std::size_t k = 1; k + 1 < face.size(); ++k) mesh.triangles.push_back({face[0], face[k], face[k + 1]});
  }
  return mesh;
}

// semantics.txt; an absent file gives no entries (the URDF is enough to
// load an object), a malformed line is an error naming it.
inline std::vector<Semantic> readSemantics(const std::string& path) {
  std::vector<Semantic> out;
  std::ifstream in(path);
  if (!in) return out;
  static const std::set<std::string> kinds = {"hinge", "slider", "slider+", "free", "heavy", "static"};
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream s(line);
    Semantic e;
    if (!(s >> e.link)) continue;  // blank line
    if (!(s >> e.kind) || kinds.count(e.kind) == 0 || !(s >> e.label))
      throw Error("PartNet: " + path + ":" + std::to_string(number) + ": expected 'link_N <hinge|slider|slider+|free|" +
                      "heavy|static> <label>', got '" + line + "'",
                  MB_INVALID_ARGUMENT);
    out.push_back(e);
  }
  return out;
}

namespace detail {

// Adds to `out` each mesh (an "objs" entry: "original-12") of a part tree
// node of result.json and its children, with the name of the innermost
// named part holding it ("handle", "drawer_front", ...).
inline void collectMeshParts(const boost::property_tree::ptree& node, const std::string& name, std::map<std::string, std::string>& out) {
  const std::string own = node.get<std::string>("name", name);
  if (const auto objs = node.get_child_optional("objs"))
    for (const auto& [key, mesh] : *objs) out[mesh.get_value<std::string>()] = own;
  if (const auto children = node.get_child_optional("children"))
    for (const auto& [key, child] : *children) collectMeshParts(child, own, out);
}


}  // namespace detail

// result.json (PartNet's part hierarchy): the part name of each mesh file
// by its stem ("original-12" -> "handle"). An absent file gives none; one
// that is not JSON is an error naming it.
inline std::map<std::string, std::string> readMeshParts(const std::string& path) {
  std::map<std::string, std::string> out;
  std::ifstream in(path);
  if (!in) return out;
  boost::property_tree::ptree tree;
  try {
    boost::property_tree::read_json(in, tree);
  } catch (const boost::property_tree::json_parser_error& e) {
    throw Error("PartNet: " + path + ":" + std::to_string(e.line()) + ": " + e.message(), MB_INVALID_ARGUMENT);
  }
  for (const auto& [key, node] : tree) detail::collectMeshParts(node, "", out);
  return out;
}

}  // namespace manibench::kit::partnet
