// PartNet-Mobility objects from the user's disk, for task families that
// load them instead of (or beside) their own generated objects: the folder
// layout, mobility.urdf as a small kinematic model and its edits, bounds
// (the other files an object holds: partnet_files.hpp). Header-only, over Boost.PropertyTree's XML reader
// (the SDK depends on Boost already), so a family needs no extra library.
//
// A PartNet-Mobility folder holds one sub-folder per object:
//   <folder>/<id>/mobility.urdf, semantics.txt, textured_objs/*.obj
//   <folder>/test.txt   (optional) the test split's ids, one a line
// The URDF's root is 'base'; links are link_N, joints joint_N; the base
// joint turns the Y-up object frame Z-up; <limit> tags carry lower/upper
// only (urdfdom, the host's URDF reader, also wants effort and velocity).
// PartNet data is never shipped: families test on hand-made fixtures in
// that layout (tests/fixtures/partnet_*).
//
// What a handle, a seat or a bucket rim is stays with the families: this
// header knows folders, URDF structure and geometry, nothing else.
#pragma once

#include <manibench/kit/common.hpp>
#include <manibench/kit/partnet_files.hpp>
#include <manibench/kit/urdf.hpp>

#include <boost/property_tree/ptree.hpp>
#include <boost/property_tree/xml_parser.hpp>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace manibench::kit::partnet {

// An axis-aligned box grown point by point; empty until the first point.
struct Bounds {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  void add(const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void add(const Bounds& b) {
    if (!b.empty()) {
      add(b.lo);
      add(b.hi);
    }
  }
  bool empty() const { return !(lo.x() <= hi.x()); }
  Eigen::Vector3d center() const { return (lo + hi) / 2; }
  Eigen::Vector3d extent() const { return hi - lo; }
};

// The geometry of a <visual> or <collision>, sizes already scaled.
struct Geometry {
  enum class Kind { kNone, kMesh, kBox, kCylinder, kSphere };
  Kind kind = Kind::kNone;
  std::string filename;                              // mesh, relative to the object folder
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();   // mesh
  Eigen::Vector3d size = Eigen::Vector3d::Zero();    // box, full side lengths
  double radius = 0, length = 0;                     // cylinder (along its z), sphere
};

// A <visual> or <collision> element.
struct Shape {
  std::string name;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  // in the link frame
  Geometry geometry;
};

struct Link {
  std::string name;
  std::vector<Shape> visuals, collisions;
  int parent_joint = -1;  // index into Object::joints; -1 for the root
};

using urdf::JointType;

struct Joint {
  std::string name;
  JointType type = JointType::kFixed;
  std::string parent, child;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  // child frame in the parent's at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();           // URDF's default
  bool limited = false;  // a <limit> element was there
  double lower = 0, upper = 0;
  bool isMovable() const { return type != JointType::kFixed; }
};

namespace detail {

using boost::property_tree::ptree;

inline std::string formatNumber(double x) {
  std::ostringstream s;
  s.precision(17);
  s << x;
  return s.str();
}

// The leading number of `text`. PartNet has limit strings with junk after
// the number: the number is kept (and the attribute rewritten clean);
// text without a leading number is an error naming `what`.
inline double parseNumber(const std::string& text, const std::string& what) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double x = std::strtod(begin, &end);
  if (end == begin || !std::isfinite(x))
    throw Error("PartNet: " + what + ": '" + text + "' is not a number", MB_INVALID_ARGUMENT);
  return x;
}

inline Eigen::Vector3d parseVector(const std::string& text, const std::string& what) {
  std::istringstream s(text);
  Eigen::Vector3d v;
  std::string extra;
  if (!(s >> v.x() >> v.y() >> v.z()) || (s >> extra) || !v.allFinite())
    throw Error("PartNet: " + what + ": expected 3 numbers, got '" + text + "'", MB_INVALID_ARGUMENT);
  return v;
}

inline std::string formatVector(const Eigen::Vector3d& v) {
  return formatNumber(v.x()) + " " + formatNumber(v.y()) + " " + formatNumber(v.z());
}

inline ptree* findAttributes(ptree& element) {
  const auto it = element.find("<xmlattr>");
  return it == element.not_found() ? nullptr : &element.to_iterator(it)->second;
}

inline std::string getAttribute(const ptree& element, const std::string& name, const std::string& fallback = "") {
  return element.get<std::string>("<xmlattr>." + name, fallback);
}

// URDF rpy: R = Rz(yaw) Ry(pitch) Rx(roll).
inline Eigen::Isometry3d parseOrigin(const ptree& parent, const std::string& what) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const auto origin = parent.get_child_optional("origin");
  if (!origin) return t;
  const std::string xyz = getAttribute(*origin, "xyz"), rpy = getAttribute(*origin, "rpy");
  if (!xyz.empty()) t.translation() = parseVector(xyz, what + " <origin xyz>");
  if (!rpy.empty()) {
    const Eigen::Vector3d a = parseVector(rpy, what + " <origin rpy>");
    t.linear() = (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
  }
  return t;
}

// Multiplies an attribute holding numbers by `factor`.
inline void scaleAttribute(ptree& element, const std::string& name, double factor, const std::string& what) {
  ptree* attributes = findAttributes(element);
  if (attributes == nullptr) return;
  const auto value = attributes->get_optional<std::string>(name);
  if (!value) return;
  std::istringstream s(*value);
  std::string out, token;
  while (s >> token) {
    if (!out.empty()) out += " ";
    out += formatNumber(factor * parseNumber(token, what + " " + name));
  }
  attributes->put(name, out);
}

// Scales the lengths of one <visual>/<collision>/<inertial>'s origin and geometry.
inline void scaleGeometry(ptree& element, double factor, const std::string& what) {
  if (auto origin = element.get_child_optional("origin")) scaleAttribute(*origin, "xyz", factor, what);
  auto geometry = element.get_child_optional("geometry");
  if (!geometry) return;
  for (auto& [kind, g] : *geometry) {
    if (kind == "mesh") {
      if (getAttribute(g, "scale").empty())
        g.put("<xmlattr>.scale", formatVector(Eigen::Vector3d::Constant(factor)));
      else
        scaleAttribute(g, "scale", factor, what + " <mesh>");
    } else if (kind == "box") {
      scaleAttribute(g, "size", factor, what + " <box>");
    } else if (kind == "cylinder" || kind == "capsule") {
      scaleAttribute(g, "radius", factor, what + " <" + kind + ">");
      scaleAttribute(g, "length", factor, what + " <" + kind + ">");
    } else if (kind == "sphere") {
      scaleAttribute(g, "radius", factor, what + " <sphere>");
    }
  }
}

inline Geometry parseGeometry(const ptree& element, const std::string& what) {
  Geometry out;
  const auto geometry = element.get_child_optional("geometry");
  if (!geometry) return out;
  for (const auto& [kind, g] : *geometry) {
    if (kind == "mesh") {
      out.kind = Geometry::Kind::kMesh;
      out.filename = getAttribute(g, "filename");
      if (out.filename.empty()) throw Error("PartNet: " + what + ": <mesh> without a filename", MB_INVALID_ARGUMENT);
      const std::string scale = getAttribute(g, "scale");
      if (!scale.empty()) out.scale = parseVector(scale, what + " <mesh scale>");
    } else if (kind == "box") {
      out.kind = Geometry::Kind::kBox;
      out.size = parseVector(getAttribute(g, "size"), what + " <box size>");
    } else if (kind == "cylinder" || kind == "capsule") {
      out.kind = Geometry::Kind::kCylinder;
      out.radius = parseNumber(getAttribute(g, "radius"), what + " <" + kind + " radius>");
      out.length = parseNumber(getAttribute(g, "length"), what + " <" + kind + " length>");
    } else if (kind == "sphere") {
      out.kind = Geometry::Kind::kSphere;
      out.radius = parseNumber(getAttribute(g, "radius"), what + " <sphere radius>");
    }
  }
  return out;
}

}  // namespace detail

// A PartNet-Mobility object: its URDF text, ready for
// SceneView::addUrdfString with base_dir = dir, and the same URDF as a
// kinematic model, with its semantics.
class Object {
 public:
  std::string id;
  std::string dir;   // the object's folder (relative mesh paths start here)
  std::string urdf;  // limits completed, lengths scaled
  std::string urdf_file;  // the file it was read from (findUrdfFile)
  double scale = 1;  // applied to every length of the file
  std::vector<Link> links;    // parents before children: links.front() is the root
  std::vector<Joint> joints;  // in file order
  std::vector<Semantic> semantics;
  const Link& getRoot() const { return links.front(); }
  const Link* findLink(const std::string& name) const {
    for (const Link& l : links)
      if (l.name == name) return &l;
    return nullptr;
  }
  const Joint* findJoint(const std::string& name) const {
    for (const Joint& j : joints)
      if (j.name == name) return &j;
    return nullptr;
  }
  // The joint whose child is `link` (nullptr for the root).
  const Joint* findParentJoint(const std::string& link) const {
    const Link* l = findLink(link);
    return l == nullptr || l->parent_joint < 0 ? nullptr : &joints[std::size_t(l->parent_joint)];
  }
  const Semantic* findSemantic(const std::string& link) const {
    for (const Semantic& s : semantics)
      if (s.link == link) return &s;
    return nullptr;
  }

  // Every link's pose in the object frame (the root's) with each joint at
  // its position in `q` (by joint name; 0 for joints it does not name): a
  // revolute or continuous joint turns its child about its axis, a
  // prismatic one slides it along it (URDF: the axis in the joint frame).
  std::map<std::string, Eigen::Isometry3d> calcLinkPoses(const std::map<std::string, double>& q = {}) const {
    std::map<std::string, Eigen::Isometry3d> pose;
    for (const Link& l : links) {
      if (l.parent_joint < 0) {
        pose[l.name] = Eigen::Isometry3d::Identity();
      } else {
        const Joint& j = joints[std::size_t(l.parent_joint)];
        Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
        const auto at = q.find(j.name);
        const double x = at == q.end() ? 0.0 : at->second;
        if (j.type == JointType::kRevolute || j.type == JointType::kContinuous)
          motion.linear() = Eigen::AngleAxisd(x, j.axis).toRotationMatrix();
        else if (j.type == JointType::kPrismatic)
          motion.translation() = x * j.axis;
        pose[l.name] = pose.at(j.parent) * j.origin * motion;
      }
    }
    return pose;
  }
  // Each limited movable joint at its lower limit (where ManiSkill v1 and
  // the tasks' resets put them), by name.
  std::map<std::string, double> getLowerLimits() const {
    std::map<std::string, double> q;
    for (const Joint& j : joints)
      if (j.isMovable() && j.limited) q[j.name] = j.lower;
    return q;
  }

  // Points of a shape in its link's frame: mesh vertices (read once and
  // kept), box corners, points on a cylinder's rims, on a sphere's
  // meridians. Enough for bounds and distances at a few mm.
  const std::vector<Eigen::Vector3d>& calcShapePoints(const Shape& shape) const {
    const std::string key = shapeKey(shape);
    auto& slot = point_cache_[key];
    if (slot) return *slot;
    std::vector<Eigen::Vector3d> local;
    const Geometry& g = shape.geometry;
    switch (g.kind) {
      case Geometry::Kind::kMesh:
        local = readObjVertices((std::filesystem::path(dir) / g.filename).string(), g.scale);
        break;
      case Geometry::Kind::kBox:
        for (int i = 0; i < 8; ++i)
          local.emplace_back((i & 1 ? 0.5 : -0.5) * g.size.x(), (i & 2 ? 0.5 : -0.5) * g.size.y(),
                             (i & 4 ? 0.5 : -0.5) * g.size.z());
        break;
      case Geometry::Kind::kCylinder:
        for (int i = 0; i < 16; ++i) {
          const double a = 2 * kPi * i / 16;
          for (const double z : {-0.5 * g.length, 0.5 * g.length})
            local.emplace_back(g.radius * std::cos(a), g.radius * std::sin(a), z);
        }
        break;
      case Geometry::Kind::kSphere:
        for (int i = 0; i < 16; ++i)
          for (int k = 0; k <= 8; ++k) {
            const double a = 2 * kPi * i / 16, b = kPi * k / 8;
            local.emplace_back(g.radius * std::sin(b) * std::cos(a), g.radius * std::sin(b) * std::sin(a),
                               g.radius * std::cos(b));
          }
        break;
      case Geometry::Kind::kNone:
        break;
    }
    for (Eigen::Vector3d& p : local) p = shape.origin * p;
    slot = std::make_shared<std::vector<Eigen::Vector3d>>(std::move(local));
    return *slot;
  }

  // Bounds of the visuals in the object frame, each joint at its position
  // in `q` (calcLinkPoses; every joint at 0 by default).
  Bounds calcVisualBounds(const std::map<std::string, double>& q = {}) const {
    const auto pose = calcLinkPoses(q);
    Bounds all;
    for (const Link& l : links)
      for (const Shape& v : l.visuals)
        for (const Eigen::Vector3d& p : calcShapePoints(v)) all.add(pose.at(l.name) * p);
    return all;
  }

 private:
  static std::string shapeKey(const Shape& s) {
    std::ostringstream k;
    k.precision(17);
    k << int(s.geometry.kind) << '|' << s.geometry.filename << '|' << s.geometry.scale.transpose() << '|'
      << s.geometry.size.transpose() << '|' << s.geometry.radius << '|' << s.geometry.length << '|'
      << s.origin.matrix();
    return k.str();
  }
  mutable std::map<std::string, std::shared_ptr<std::vector<Eigen::Vector3d>>> point_cache_;
};

// The one way the kit rewrites URDF text: `urdf` with `edit(robot)` called
// on its <robot> element (as Boost.PropertyTree's XML: attributes under
// "<xmlattr>"), written back. Errors name `where` (XML that does not parse,
// with its line; no <robot>).
inline std::string editRobot(const std::string& urdf, const std::function<void(boost::property_tree::ptree&)>& edit,
                             const std::string& where = "URDF") {
  using detail::ptree;
  ptree document;
  std::istringstream in(urdf);
  try {
    boost::property_tree::read_xml(in, document, boost::property_tree::xml_parser::trim_whitespace);
  } catch (const boost::property_tree::xml_parser_error& e) {
    throw Error(where + ":" + std::to_string(e.line()) + ": not valid XML (" + e.message() + ")", MB_INVALID_ARGUMENT);
  }
  const auto robot = document.get_child_optional("robot");
  if (!robot) throw Error(where + ": no <robot> element", MB_INVALID_ARGUMENT);
  edit(*robot);
  std::ostringstream out;
  boost::property_tree::write_xml(out, document, boost::property_tree::xml_writer_make_settings<std::string>(' ', 1));
  return out.str();
}

// `urdf` with `edit(name, element)` called on every <link> element.
inline std::string editLinks(const std::string& urdf,
                             const std::function<void(const std::string&, boost::property_tree::ptree&)>& edit) {
  return editRobot(urdf, [&](detail::ptree& robot) {
    for (auto& [tag, link] : robot)
      if (tag == "link") edit(detail::getAttribute(link, "name"), link);
  });
}

// `urdf` with the links named in `names` renamed (old -> new), in their
// <link> elements and in every joint's <parent link> and <child link>.
inline std::string renameLinks(const std::string& urdf, const std::map<std::string, std::string>& names) {
  return editRobot(urdf, [&](detail::ptree& robot) {
    auto rename = [&](detail::ptree& element, const std::string& path) {
      const auto value = element.get_optional<std::string>(path);
      if (!value) return;
      const auto found = names.find(*value);
      if (found != names.end()) element.put(path, found->second);
    };
    for (auto& [tag, element] : robot) {
      if (tag == "link") rename(element, "<xmlattr>.name");
      if (tag == "joint") {
        rename(element, "parent.<xmlattr>.link");
        rename(element, "child.<xmlattr>.link");
      }
    }
  });
}

// `urdf` with the elements of `fragment` (URDF text without its <robot>,
// e.g. a <link> and a <joint>) put first in <robot>, after its attributes.
inline std::string prependElements(const std::string& urdf, const std::string& fragment,
                                   const std::string& where = "URDF") {
  using detail::ptree;
  ptree added;
  std::istringstream in("<robot>" + fragment + "</robot>");
  boost::property_tree::read_xml(in, added, boost::property_tree::xml_parser::trim_whitespace);
  return editRobot(
      urdf,
      [&](ptree& robot) {
        auto at = robot.begin();
        if (at != robot.end() && at->first == "<xmlattr>") ++at;
        for (auto& child : added.get_child("robot")) at = std::next(robot.insert(at, child));
      },
      where);
}

// `urdf` with every <collision> of the links named in `meshes` replaced by
// one <collision> per mesh file given (absolute paths, in the link frame,
// unscaled): a part's convex pieces instead of its concave meshes.
inline std::string replaceCollisionMeshes(const std::string& urdf,
                                          const std::map<std::string, std::vector<std::string>>& meshes) {
  return editLinks(urdf, [&](const std::string& name, detail::ptree& link) {
    const auto found = meshes.find(name);
    if (found == meshes.end()) return;
    for (auto it = link.begin(); it != link.end();) it = it->first == "collision" ? link.erase(it) : std::next(it);
    for (std::size_t k = 0; k < found->second.size(); ++k) {
      detail::ptree collision;
      collision.put("<xmlattr>.name", "convex_piece_" + std::to_string(k));
      collision.put("geometry.mesh.<xmlattr>.filename", found->second[k]);
      link.add_child("collision", collision);
    }
  });
}

// The URDF an object's folder is read from, the decomposed ones first:
// ManiSkill2's mobility_cvx.urdf (its collision meshes made convex with
// CoACD; its asset folders hold only this one), ManiSkill v1's
// mobility_fixed.urdf, then the dataset's mobility.urdf. "" if none.
inline std::string findUrdfFile(const std::string& object_dir) {
  for (const char* name : {"mobility_cvx.urdf", "mobility_fixed.urdf", "mobility.urdf"}) {
    const std::filesystem::path path = std::filesystem::path(object_dir) / name;
    if (std::filesystem::is_regular_file(path)) return path.string();
  }
  return "";
}

// Sub-folders of `folder` holding an object's URDF (findUrdfFile), sorted.
inline std::vector<std::string> listObjectIds(const std::string& folder) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(folder))
    throw Error("PartNet: '" + folder + "' is not a folder", MB_INVALID_ARGUMENT);
  std::vector<std::string> ids;
  for (const fs::directory_entry& e : fs::directory_iterator(folder))
    if (e.is_directory() && !findUrdfFile(e.path().string()).empty()) ids.push_back(e.path().filename().string());
  std::sort(ids.begin(), ids.end());
  return ids;
}

// The ids of a split: <folder>/test.txt lists the test objects, one id a
// line; every other object is in train. A listed id without its folder is
// an error naming the line.
inline std::vector<std::string> listObjectIds(const std::string& folder, const std::string& split) {
  if (split != "train" && split != "test")
    throw Error("unknown split '" + split + "' (use train or test)", MB_INVALID_ARGUMENT);
  const std::vector<std::string> all = listObjectIds(folder);
  std::set<std::string> test;
  const std::string list = folder + "/test.txt";
  if (std::ifstream in(list); in) {
    int number = 0;
    for (std::string line; std::getline(in, line);) {
      ++number;
      line.erase(line.find_last_not_of(" \t\r") + 1);
      line.erase(0, line.find_first_not_of(" \t"));
      if (line.empty()) continue;
      if (!std::binary_search(all.begin(), all.end(), line))
        throw Error("PartNet: " + list + ":" + std::to_string(number) + ": no object folder '" + line +
                        "' with a mobility.urdf in " + folder,
                    MB_INVALID_ARGUMENT);
      test.insert(line);
    }
  }
  std::vector<std::string> ids;
  for (const std::string& id : all)
    if ((test.count(id) > 0) == (split == "test")) ids.push_back(id);
  return ids;
}

// Loads <folder>/<id>/'s URDF (findUrdfFile) and semantics.txt. Every length of the
// URDF (origins, mesh scales, primitive sizes, prismatic limits, inertial
// origins; masses by scale^3 and inertias by scale^5) is multiplied by
// `scale`; <limit> elements without effort or velocity get effort 100 and
// velocity 1 (PartNet writes lower/upper only), and a limit number with
// junk after it is rewritten as the number. Errors name the file and the
// element.
inline Object loadObject(const std::string& folder, const std::string& id, double scale = 1.0) {
  using detail::ptree;
  namespace fs = std::filesystem;
  if (!(scale > 0) || !std::isfinite(scale))
    throw Error("PartNet: scale must be positive, got " + detail::formatNumber(scale), MB_INVALID_ARGUMENT);
  const fs::path dir = fs::path(folder) / id;
  const std::string found = findUrdfFile(dir.string());
  const std::string path = found.empty() ? (dir / "mobility.urdf").string() : found;
  std::ifstream in(path);
  if (!in) throw Error("PartNet: no object '" + id + "' (" + path + " is missing)", MB_NOT_FOUND);
  urdf::Tree tree = urdf::readTree(in, "PartNet: " + path);

  Object object;
  object.id = id;
  object.dir = dir.string();
  object.urdf_file = path;
  object.scale = scale;
  const std::map<std::string, std::string> mesh_parts = readMeshParts((dir / "result.json").string());
  for (const urdf::Tree::Joint& j : tree.joints) {
    Joint joint;
    joint.name = j.name;
    joint.type = j.type;
    joint.parent = j.parent;
    joint.child = j.child;
    ptree& element = *j.element;
    const std::string what = path + ": joint '" + joint.name + "'";
    if (scale != 1)
      if (auto origin = element.get_child_optional("origin")) detail::scaleAttribute(*origin, "xyz", scale, what);
    joint.origin = detail::parseOrigin(element, what);
    if (const auto axis = element.get_child_optional("axis")) {
      const std::string xyz = detail::getAttribute(*axis, "xyz");
      if (!xyz.empty()) joint.axis = detail::parseVector(xyz, what + " <axis xyz>");
      if (!(joint.axis.norm() > 0)) throw Error("PartNet: " + what + " has a zero axis", MB_INVALID_ARGUMENT);
      joint.axis.normalize();
    }
    if (auto limit = element.get_child_optional("limit")) {
      joint.limited = true;
      if (limit->find("<xmlattr>") == limit->not_found()) limit->add_child("<xmlattr>", ptree());
      ptree& a = limit->get_child("<xmlattr>");
      const double length_scale = joint.type == JointType::kPrismatic ? scale : 1.0;
      for (const char* bound : {"lower", "upper"}) {
        const auto text = a.get_optional<std::string>(bound);
        if (!text) continue;
        const double x = length_scale * detail::parseNumber(*text, what + " <limit " + bound + ">");
        a.put(bound, detail::formatNumber(x));
        (std::string(bound) == "lower" ? joint.lower : joint.upper) = x;
      }
      if (!a.get_optional<std::string>("effort")) a.put("effort", "100");
      if (!a.get_optional<std::string>("velocity")) a.put("velocity", "1");
    }
    object.joints.push_back(joint);
  }
  // Parents before children.
  for (const std::size_t l : tree.listBreadthFirst()) {
    Link link;
    link.name = tree.links[l].name;
    link.parent_joint = tree.links[l].parent_joint;
    for (auto& [child_tag, child] : *tree.links[l].element) {
      const bool visual = child_tag == "visual", collision = child_tag == "collision";
      const std::string what = path + ": link '" + link.name + "' <" + child_tag + ">";
      if (child_tag == "inertial" && scale != 1) {
        if (auto origin = child.get_child_optional("origin")) detail::scaleAttribute(*origin, "xyz", scale, what);
        if (auto mass = child.get_child_optional("mass"))
          detail::scaleAttribute(*mass, "value", scale * scale * scale, what + " <mass>");
        if (auto inertia = child.get_child_optional("inertia"))
          for (const char* k : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"})
            detail::scaleAttribute(*inertia, k, std::pow(scale, 5), what + " <inertia>");
      }
      if (!visual && !collision) continue;
      if (scale != 1) detail::scaleGeometry(child, scale, what);
      Shape shape;
      shape.name = detail::getAttribute(child, "name");
      shape.geometry = detail::parseGeometry(child, what);
      // Older files leave visuals unnamed (cabinet 45940): result.json's
      // part name of the mesh names it, in the URDF too, so that the host's
      // masks and the families find a "handle" by name either way.
      if (shape.name.empty() && shape.geometry.kind == Geometry::Kind::kMesh) {
        const auto part = mesh_parts.find(fs::path(shape.geometry.filename).stem().string());
        if (part != mesh_parts.end()) {
          shape.name = part->second;
          child.put("<xmlattr>.name", shape.name);
        }
      }
      shape.origin = detail::parseOrigin(child, what);
      (visual ? link.visuals : link.collisions).push_back(shape);
    }
    object.links.push_back(std::move(link));
  }

  std::ostringstream text;
  boost::property_tree::write_xml(text, *tree.document, boost::property_tree::xml_writer_make_settings<std::string>(' ', 1));
  object.urdf = text.str();
  object.semantics = readSemantics((dir / "semantics.txt").string());
  for (const Semantic& s : object.semantics)
    if (!object.findLink(s.link))
      throw Error("PartNet: " + (dir / "semantics.txt").string() + ": link '" + s.link + "' is not in " + path,
                  MB_INVALID_ARGUMENT);
  return object;
}

}  // namespace manibench::kit::partnet
