#include "urdf_model.hpp"

#include "mass_properties.hpp"
#include "urdf_xml_checks.hpp"

#include <manibench/sdk/numbers.hpp>

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

namespace manibench {
namespace scene_detail {
namespace {

using SimTK::Inertia;
using SimTK::Mat33;
using SimTK::Rotation;
using SimTK::SymMat33;
using SimTK::Transform;
using SimTK::Vec3;

using sdk::kPi;

// urdfdom reports why it rejected a model only through console_bridge. This
// routes its error messages into a string for the SceneError while parsing;
// warnings still reach the previous handler. console_bridge's handler is
// process-wide, hence the lock (other threads' messages are forwarded).
class UrdfErrorCapture : public console_bridge::OutputHandler {
 public:
  UrdfErrorCapture()
      : lock_(mutex()), previous_(console_bridge::getOutputHandler()) {
    console_bridge::useOutputHandler(this);
  }
  ~UrdfErrorCapture() override { console_bridge::useOutputHandler(previous_); }
  UrdfErrorCapture(const UrdfErrorCapture&) = delete;
  UrdfErrorCapture& operator=(const UrdfErrorCapture&) = delete;

  void log(const std::string& text, console_bridge::LogLevel level,
           const char* filename, int line) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR &&
        std::this_thread::get_id() == thread_) {
      if (!errors_.empty()) errors_ += "; ";
      errors_ += text;
    } else if (previous_ != nullptr) {
      previous_->log(text, level, filename, line);
    }
  }
  const std::string& getErrors() const { return errors_; }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  console_bridge::OutputHandler* previous_;
  std::thread::id thread_ = std::this_thread::get_id();
  std::string errors_;
};

Transform toTransform(const urdf::Pose& pose) {
  double x, y, z, w;
  pose.rotation.getQuaternion(x, y, z, w);
  return Transform(Rotation(SimTK::Quaternion(w, x, y, z)),
                   Vec3(pose.position.x, pose.position.y, pose.position.z));
}

bool isFile(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

struct Builder {
  const urdf::ModelInterface& urdf;
  const std::string& source;
  const std::string& base_dir;
  double density;
  double default_damping;  // of joints without <dynamics>
  std::map<std::string, int> joint_file_order;
  // (link name, collision ordinal) of each <capsule>, which urdfdom saw as
  // a cylinder of the same radius and length.
  std::set<std::pair<std::string, int>> capsules;
  std::set<std::pair<std::string, int>> visual_capsules;  // same, for <visual>
  ArticulationModel model;
  std::vector<std::pair<int, std::string>> mimics;  // (follower, leader name)

  int getFileOrder(const std::string& joint_name) const {
    const auto found = joint_file_order.find(joint_name);
    return found == joint_file_order.end() ? std::numeric_limits<int>::max()
                                           : found->second;
  }

  // The link's own mass properties, from <inertial> or else from the
  // volume of its collision shapes (overlaps counted twice).
  void addLinkMass(const urdf::Link& link, const Transform& X_BL,
                   const std::vector<CollisionShape>& shapes, BodyModel& body) {
    if (link.inertial) {
      const urdf::Inertial& in = *link.inertial;
      if (!std::isfinite(in.mass) || in.mass < 0)
        failUrdf(source, "link '" + link.name + "' has invalid mass " +
                         std::to_string(in.mass));
      if (in.mass == 0) return;
      const Mat33 Ic_I(in.ixx, in.ixy, in.ixz,  //
                       in.ixy, in.iyy, in.iyz,  //
                       in.ixz, in.iyz, in.izz);
      // Invalid alone is fine if its body's sum is valid (checkBodyMasses).
      if (!Inertia::isValidInertiaMatrix(SymMat33().setFromLower(Ic_I)) &&
          body.invalid_part.empty()) {
        std::ostringstream s;
        s << "link '" << link.name << "' has an invalid inertia (ixx " << in.ixx
          << " iyy " << in.iyy << " izz " << in.izz << " ixy " << in.ixy
          << " ixz " << in.ixz << " iyz " << in.iyz << ")";
        body.invalid_part = s.str();
      }
      const Transform X_BI = X_BL * toTransform(in.origin);
      const Mat33 R = X_BI.R().asMat33();
      addMass(body, in.mass, X_BI.p(), R * Ic_I * ~R);
      return;
    }
    for (const CollisionShape& shape : shapes) {
      double m = 0;
      Vec3 com_S(0);
      Mat33 Ic_S(0, 0, 0, 0, 0, 0, 0, 0, 0);
      calcShapeMass(shape.geometry, density, m, com_S, Ic_S);
      const Mat33 R = shape.X_BS.R().asMat33();
      addMass(body, m, shape.X_BS * com_S, R * Ic_S * ~R);
    }
  }

  void noteMeshFile(const std::string& path) {
    if (std::find(model.mesh_files.begin(), model.mesh_files.end(), path) == model.mesh_files.end())
      model.mesh_files.push_back(path);
  }

  // The convex hull of a <mesh>; a flat or thin one is a 1 cm solid
  // (loadConvexHull pads it), so every mesh found has one.
  std::shared_ptr<const ConvexHull> loadMeshHull(const urdf::Link& link, const urdf::Mesh& mesh) {
    const Vec3 scale(mesh.scale.x, mesh.scale.y, mesh.scale.z);
    if (!scale.isFinite() || scale[0] == 0 || scale[1] == 0 || scale[2] == 0)
      failUrdf(source, "link '" + link.name + "': mesh '" + mesh.filename + "' has scale " +
                       std::to_string(scale[0]) + " " + std::to_string(scale[1]) + " " +
                       std::to_string(scale[2]) + "; every factor must be finite and non-zero");
    const std::string path = findMeshFile(mesh.filename, base_dir);
    if (path.empty())
      failUrdf(source, "link '" + link.name + "': collision mesh " + describeMissingMesh(mesh.filename, base_dir));
    noteMeshFile(path);
    try {
      return loadConvexHull(path, scale);
    } catch (const std::exception& e) {
      failUrdf(source, "link '" + link.name + "': collision mesh '" + path + "': " + e.what());
    }
  }

  // visit(element, geometry, capsule, what) for each <collision> or <visual>
  // (`kind`) with a geometry, its sizes checked. `capsule`: in `capsule_set`;
  // `what`, for errors: "link 'L': collision 'name'" ('#N' from 1 unnamed).
  template <class Element, class Visit>
  void forEachShape(const urdf::Link& link, const std::vector<std::shared_ptr<Element>>& elements, const char* kind,
                    const std::set<std::pair<std::string, int>>& capsule_set, Visit&& visit) const {
    for (std::size_t i = 0; i < elements.size(); ++i) {
      const Element* element = elements[i].get();
      if (!element || !element->geometry) continue;
      const std::string what = "link '" + link.name + "': " + kind + " '" +
                               (element->name.empty() ? "#" + std::to_string(i + 1) : element->name) + "'";
      const bool capsule = capsule_set.count({link.name, static_cast<int>(i)}) > 0;
      checkPrimitiveSize(*element->geometry, capsule, what);
      visit(*element, *element->geometry, capsule, what);
    }
  }

  // A primitive's sizes must be positive and finite (a capsule's length may
  // be 0): one rule for collisions and visuals.
  void checkPrimitiveSize(const urdf::Geometry& g, bool capsule, const std::string& what) const {
    if (g.type == urdf::Geometry::SPHERE) {
      const double r = static_cast<const urdf::Sphere&>(g).radius;
      if (!(r > 0) || !std::isfinite(r)) failUrdf(source, what + " is a sphere of radius " + std::to_string(r));
    } else if (g.type == urdf::Geometry::BOX) {
      const urdf::Vector3& d = static_cast<const urdf::Box&>(g).dim;
      if (!(d.x > 0 && d.y > 0 && d.z > 0) || !std::isfinite(d.x + d.y + d.z))
        failUrdf(source, what + " is a box of size " + std::to_string(d.x) + " " + std::to_string(d.y) + " " +
                             std::to_string(d.z));
    } else if (g.type == urdf::Geometry::CYLINDER) {
      const auto& c = static_cast<const urdf::Cylinder&>(g);
      if (!(c.radius > 0) || !std::isfinite(c.radius) || !std::isfinite(c.length) ||
          (capsule ? !(c.length >= 0) : !(c.length > 0)))
        failUrdf(source, what + " is a " + (capsule ? "capsule" : "cylinder") + " of radius " +
                             std::to_string(c.radius) + " and length " + std::to_string(c.length));
    }
  }

  std::vector<CollisionShape> makeLinkShapes(const urdf::Link& link, int link_index, const Transform& X_BL) {
    std::vector<CollisionShape> shapes;
    forEachShape(link, link.collision_array, "collision", capsules,
                 [&](const urdf::Collision& collision, const urdf::Geometry& g, bool capsule, const std::string& what) {
                   CollisionShape shape;
                   shape.link = link_index;
                   shape.X_BS = X_BL * toTransform(collision.origin);
                   if (g.type == urdf::Geometry::SPHERE) {
                     shape.geometry = ShapeGeometry::makeSphere(static_cast<const urdf::Sphere&>(g).radius);
                   } else if (g.type == urdf::Geometry::BOX) {
                     const urdf::Vector3& d = static_cast<const urdf::Box&>(g).dim;
                     shape.geometry = ShapeGeometry::makeBox(Vec3(d.x / 2, d.y / 2, d.z / 2));
                   } else if (g.type == urdf::Geometry::CYLINDER) {
                     const auto& c = static_cast<const urdf::Cylinder&>(g);
                     shape.geometry = capsule ? ShapeGeometry::makeCapsule(c.radius, c.length / 2)
                                              : ShapeGeometry::makeCylinder(c.radius, c.length / 2);
                   } else if (g.type == urdf::Geometry::MESH) {
                     shape.geometry = ShapeGeometry::makeConvex(loadMeshHull(link, static_cast<const urdf::Mesh&>(g)));
                   } else {
                     model.unsimulated.push_back(what + " (unknown geometry type)");
                     return;
                   }
                   shapes.push_back(std::move(shape));
                 });
    return shapes;
  }

  std::shared_ptr<const std::vector<VisualMesh>> loadVisualMesh(const urdf::Mesh& mesh,
                                                                const std::string& what,
                                                                std::string& path) {
    const Vec3 scale(mesh.scale.x, mesh.scale.y, mesh.scale.z);
    if (!scale.isFinite() || scale[0] == 0 || scale[1] == 0 || scale[2] == 0)
      failUrdf(source, what + ": mesh '" + mesh.filename + "' has scale " +
                       std::to_string(scale[0]) + " " + std::to_string(scale[1]) + " " +
                       std::to_string(scale[2]) + "; every factor must be finite and non-zero");
    path = findMeshFile(mesh.filename, base_dir);
    if (path.empty())
      failUrdf(source, what + ": visual mesh " + describeMissingMesh(mesh.filename, base_dir));
    noteMeshFile(path);
    try {
      return loadVisualMeshes(path, scale);
    } catch (const std::exception& e) {
      failUrdf(source, what + ": visual mesh '" + path + "': " + e.what());
    }
  }

  // The visual's URDF material: its own, or a robot-level one it names.
  // urdfdom leaves a name-only reference with a default (black) color, so
  // the robot-level definition wins whenever one exists.
  void setVisualMaterial(const urdf::Visual& visual, VisualShape& shape) {
    urdf::MaterialSharedPtr material = visual.material;
    const std::string name = !visual.material_name.empty() ? visual.material_name
                             : material                   ? material->name
                                                          : std::string();
    if (!name.empty())
      if (urdf::MaterialSharedPtr named = urdf.getMaterial(name)) material = named;
    if (!material) return;
    shape.has_material = true;
    shape.material_name = material->name;
    shape.texture = material->texture_filename;
    const urdf::Color& c = material->color;
    shape.color = Eigen::Vector4f(c.r, c.g, c.b, c.a);
    // A texture-only material has urdfdom's default color (0, 0, 0, 1): the
    // texture is meant to show unmodulated.
    if (!shape.texture.empty() && c.r == 0 && c.g == 0 && c.b == 0)
      shape.color = Eigen::Vector4f::Ones();
  }

  void addLinkVisuals(const urdf::Link& link, int link_index) {
    forEachShape(link, link.visual_array, "visual", visual_capsules,
                 [&](const urdf::Visual& visual, const urdf::Geometry& g, bool capsule, const std::string& what) {
                   VisualShape shape;
                   shape.link = link_index;
                   shape.name = visual.name;
                   const urdf::Pose& origin = visual.origin;
                   double qx, qy, qz, qw;
                   origin.rotation.getQuaternion(qx, qy, qz, qw);
                   shape.pose_in_link.position =
                       Eigen::Vector3d(origin.position.x, origin.position.y, origin.position.z);
                   shape.pose_in_link.orientation = Eigen::Quaterniond(qw, qx, qy, qz).normalized();
                   if (g.type == urdf::Geometry::SPHERE) {
                     shape.kind = VisualShape::Kind::Sphere;
                     shape.size = Eigen::Vector3d(static_cast<const urdf::Sphere&>(g).radius, 0, 0);
                   } else if (g.type == urdf::Geometry::BOX) {
                     const urdf::Vector3& d = static_cast<const urdf::Box&>(g).dim;
                     shape.kind = VisualShape::Kind::Box;
                     shape.size = Eigen::Vector3d(d.x, d.y, d.z);
                   } else if (g.type == urdf::Geometry::CYLINDER) {
                     const auto& c = static_cast<const urdf::Cylinder&>(g);
                     shape.kind = capsule ? VisualShape::Kind::Capsule : VisualShape::Kind::Cylinder;
                     shape.size = Eigen::Vector3d(c.radius, c.length, 0);
                   } else if (g.type == urdf::Geometry::MESH) {
                     const auto& mesh = static_cast<const urdf::Mesh&>(g);
                     shape.kind = VisualShape::Kind::Mesh;
                     shape.mesh_scale = Eigen::Vector3d(mesh.scale.x, mesh.scale.y, mesh.scale.z);
                     shape.meshes = loadVisualMesh(mesh, what, shape.mesh_file);
                   } else {
                     return;  // nothing a renderer could draw
                   }
                   setVisualMaterial(visual, shape);
                   model.visuals.push_back(std::move(shape));
                 });
  }

  // Adds `link` (reached with the link frame at X_BL in body `body_index`)
  // and, depth first, everything below it.
  void addLink(const urdf::Link& link, int body_index, const Transform& X_BL) {
    const int link_index = static_cast<int>(model.links.size());
    model.links.push_back({link.name, body_index, X_BL});
    std::vector<CollisionShape> shapes = makeLinkShapes(link, link_index, X_BL);
    addLinkVisuals(link, link_index);
    BodyModel& body = model.bodies[body_index];
    addLinkMass(link, X_BL, shapes, body);
    for (CollisionShape& shape : shapes) body.shapes.push_back(std::move(shape));

    // Children in the order their joints appear in the file (urdfdom keeps
    // them sorted by name), so joint indices follow the author's order.
    std::vector<urdf::JointSharedPtr> children = link.child_joints;
    std::stable_sort(children.begin(), children.end(),
                     [this](const urdf::JointSharedPtr& a,
                            const urdf::JointSharedPtr& b) {
                       return getFileOrder(a->name) < getFileOrder(b->name);
                     });
    for (const urdf::JointSharedPtr& joint : children) addJoint(*joint, body_index, X_BL);
  }

  // A planar joint as three one-dof joints on a chain of massless bodies:
  // <name>_x and <name>_y slide along in-plane directions u and v (u x v =
  // axis; x and y for a z axis), <name>_yaw turns about the axis. At zero
  // the child frame is the joint frame. Position limits are not applied
  // (URDF gives one pair for three coordinates); effort and velocity
  // limits, damping and friction apply to each.
  void addPlanarJoint(const urdf::Joint& joint, const urdf::Link& child,
                      const JointDescription& planar, int parent_body, const Transform& X_PJ,
                      const Vec3& axis) {
    const SimTK::UnitVec3 n(axis);
    Vec3 u = Vec3(1, 0, 0) - n[0] * Vec3(n);
    if (u.norm() < 1e-6) u = Vec3(0, 1, 0) - n[1] * Vec3(n);
    const SimTK::UnitVec3 u_hat(u);
    const SimTK::UnitVec3 v_hat(SimTK::cross(Vec3(n), Vec3(u_hat)));
    const struct {
      const char* suffix;
      JointType type;
      SimTK::UnitVec3 axis;
    } parts[] = {{"_x", JointType::Prismatic, u_hat},
                 {"_y", JointType::Prismatic, v_hat},
                 {"_yaw", JointType::Continuous, n}};
    int parent = parent_body;
    Transform X = X_PJ;
    for (const auto& part : parts) {
      JointDescription description = planar;
      description.name = joint.name + part.suffix;
      description.type = part.type;
      description.index = static_cast<int>(model.joints.size());
      description.lower = -std::numeric_limits<double>::infinity();
      description.upper = std::numeric_limits<double>::infinity();
      BodyModel body;
      body.parent = parent;
      body.joint = description.index;
      body.link = static_cast<int>(model.links.size());  // the child, added below
      body.X_PJ = X;
      body.axis = part.axis;
      body.massless = part.type != JointType::Continuous;
      model.joints.push_back(description);
      model.bodies.push_back(body);
      parent = static_cast<int>(model.bodies.size()) - 1;
      X = Transform();
    }
    addLink(child, parent, Transform());
  }

  // Points each mimic joint at its leader (which may come later in the
  // file) once every joint exists.
  void resolveMimics() {
    for (const auto& [follower, leader_name] : mimics) {
      JointDescription& joint = model.joints[follower];
      int leader = -1;
      for (const JointDescription& other : model.joints)
        if (other.name == leader_name) leader = other.index;
      if (leader < 0) {
        const urdf::JointConstSharedPtr urdf_leader = urdf.getJoint(leader_name);
        failUrdf(source, "joint '" + joint.name + "' mimics joint '" + leader_name + "', " +
                         (urdf_leader ? "which is not a movable one-dof joint"
                                      : "which does not exist"));
      }
      if (leader == follower) failUrdf(source, "joint '" + joint.name + "' mimics itself");
      joint.mimic = leader;
    }
  }

  void addJoint(const urdf::Joint& joint, int parent_body,
                const Transform& X_PL) {
    const urdf::LinkConstSharedPtr child = urdf.getLink(joint.child_link_name);
    if (!child)
      failUrdf(source, "joint '" + joint.name + "' has unknown child link '" +
                       joint.child_link_name + "'");
    const Transform X_PJ = X_PL * toTransform(joint.parent_to_joint_origin_transform);
    if (joint.type == urdf::Joint::FIXED) {
      addLink(*child, parent_body, X_PJ);
      return;
    }

    JointDescription description;
    description.name = joint.name;
    description.index = static_cast<int>(model.joints.size());
    switch (joint.type) {
      case urdf::Joint::REVOLUTE: description.type = JointType::Revolute; break;
      case urdf::Joint::CONTINUOUS: description.type = JointType::Continuous; break;
      case urdf::Joint::PRISMATIC: description.type = JointType::Prismatic; break;
      case urdf::Joint::FLOATING:
        failUrdf(source, "joint '" + joint.name +
                         "' is floating; only the root may float (fixed_base = "
                         "false), not a link inside the tree");
      case urdf::Joint::PLANAR: description.type = JointType::Prismatic; break;
      default:
        failUrdf(source, "joint '" + joint.name + "' has an unsupported type");
    }
    const Vec3 axis(joint.axis.x, joint.axis.y, joint.axis.z);
    if (!(axis.norm() > 1e-12) || !axis.isFinite())
      failUrdf(source, "joint '" + joint.name + "' has a zero or invalid axis");
    if (joint.limits) {
      const urdf::JointLimits& limits = *joint.limits;
      if (limits.effort < 0 || limits.velocity < 0)
        failUrdf(source, "joint '" + joint.name + "' has a negative effort or velocity limit");
      description.effort_limit = limits.effort;
      description.velocity_limit = limits.velocity;
      // lower == upper (both default to 0 in urdfdom) is read as "no
      // position limit": real files use it for unlimited joints.
      if (description.type != JointType::Continuous &&
          limits.lower != limits.upper) {
        if (!(limits.lower < limits.upper))
          failUrdf(source, "joint '" + joint.name + "' has lower limit " +
                           std::to_string(limits.lower) + " above upper limit " +
                           std::to_string(limits.upper));
        description.lower = limits.lower;
        description.upper = limits.upper;
      }
    }
    description.damping = default_damping;
    if (joint.dynamics) {
      if (!(joint.dynamics->damping >= 0) || !(joint.dynamics->friction >= 0))
        failUrdf(source, "joint '" + joint.name + "' has negative damping or friction");
      description.damping = joint.dynamics->damping;
      description.friction = joint.dynamics->friction;
    }
    if (joint.mimic) {
      const urdf::JointMimic& mimic = *joint.mimic;
      if (joint.type == urdf::Joint::PLANAR)
        failUrdf(source, "joint '" + joint.name + "' is planar and cannot mimic another joint");
      if (!std::isfinite(mimic.multiplier) || !std::isfinite(mimic.offset))
        failUrdf(source, "joint '" + joint.name + "' has a non-finite mimic multiplier or offset");
      description.mimic_multiplier = mimic.multiplier;
      description.mimic_offset = mimic.offset;
      mimics.emplace_back(description.index, mimic.joint_name);  // resolved at the end
    }

    if (joint.type == urdf::Joint::PLANAR) {
      addPlanarJoint(joint, *child, description, parent_body, X_PJ, axis);
      return;
    }

    BodyModel body;
    body.parent = parent_body;
    body.joint = description.index;
    body.link = static_cast<int>(model.links.size());
    body.X_PJ = X_PJ;
    body.axis = SimTK::UnitVec3(axis);
    model.joints.push_back(description);
    model.bodies.push_back(body);
    addLink(*child, static_cast<int>(model.bodies.size()) - 1, Transform());
  }
};

}  // namespace

std::string findMeshFile(const std::string& filename, const std::string& base_dir,
                         std::vector<std::string>* tried) {
  const std::string dir = base_dir.empty() ? "." : base_dir;
  std::vector<std::string> candidates;
  const std::string file_scheme = "file://", package_scheme = "package://";
  if (filename.compare(0, file_scheme.size(), file_scheme) == 0) {
    candidates.push_back(filename.substr(file_scheme.size()));
  } else if (filename.compare(0, package_scheme.size(), package_scheme) == 0) {
    const std::string rest = filename.substr(package_scheme.size());
    const std::size_t slash = rest.find('/');
    const std::string package = rest.substr(0, slash);
    const std::string inside = slash == std::string::npos ? "" : rest.substr(slash + 1);
    if (const char* paths = std::getenv("ROS_PACKAGE_PATH")) {
      std::stringstream list(paths);
      std::string entry;
      while (std::getline(list, entry, ':'))
        if (!entry.empty()) candidates.push_back(entry + "/" + package + "/" + inside);
    }
    // An ancestor of the URDF's directory named after the package.
    std::string ancestor = dir;
    while (!ancestor.empty()) {
      const std::size_t cut = ancestor.find_last_of('/');
      const std::string last = cut == std::string::npos ? ancestor : ancestor.substr(cut + 1);
      if (last == package) candidates.push_back(ancestor + "/" + inside);
      if (cut == std::string::npos || cut == 0) break;
      ancestor.resize(cut);
    }
    // PyBullet-style folders write package://meshes/x.obj for
    // <urdf dir>/meshes/x.obj.
    candidates.push_back(dir + "/" + rest);
    candidates.push_back(dir + "/" + inside);
  } else if (!filename.empty() && filename[0] == '/') {
    candidates.push_back(filename);
  } else {
    candidates.push_back(dir + "/" + filename);
  }
  if (tried) *tried = candidates;
  for (const std::string& candidate : candidates)
    if (isFile(candidate)) return candidate;
  return "";
}

std::string describeMissingMesh(const std::string& filename, const std::string& base_dir) {
  std::vector<std::string> tried;
  findMeshFile(filename, base_dir, &tried);
  std::string text = "'" + filename + "' not found; tried";
  for (std::size_t i = 0; i < tried.size(); ++i) text += (i ? ", '" : " '") + tried[i] + "'";
  return text;
}

ArticulationModel buildArticulationModel(const std::string& urdf_xml,
                                         const std::string& source,
                                         const std::string& base_dir,
                                         double default_density,
                                         double default_joint_damping) {
  // TinyXML first: it says where malformed XML breaks, and it gives the
  // joints' file order, which urdfdom does not keep.
  TiXmlDocument doc;
  doc.Parse(urdf_xml.c_str());
  if (doc.Error()) {
    // TinyXML says "Error document empty" for anything without an element,
    // random bytes included.
    if (urdf_xml.find('<') == std::string::npos || urdf_xml.find('\0') != std::string::npos)
      failUrdf(source, "not an XML file (no XML elements" +
                       std::string(urdf_xml.find('\0') != std::string::npos ? ", binary data" : "") + ")");
    std::ostringstream s;
    s << "malformed XML";
    if (doc.ErrorRow() > 0) s << " at line " << doc.ErrorRow() << ", column " << doc.ErrorCol();
    s << ": " << doc.ErrorDesc();
    failUrdf(source, s.str());
  }
  std::map<std::string, int> joint_file_order;
  bool limits_completed = false;
  if (TiXmlElement* robot = doc.FirstChildElement("robot")) {
    checkNumbersAreFinite(*robot, source);
    checkJointTree(*robot, source);
    limits_completed = completeLimits(*robot);
    for (const TiXmlElement* j = robot->FirstChildElement("joint"); j != nullptr;
         j = j->NextSiblingElement("joint")) {
      if (const char* name = j->Attribute("name"))
        joint_file_order.emplace(name, static_cast<int>(joint_file_order.size()));
    }
  }
  std::set<std::pair<std::string, int>> capsules, visual_capsules;
  std::string urdf_text;
  if (rewriteCapsules(doc, capsules, visual_capsules) || limits_completed) {
    TiXmlPrinter printer;
    doc.Accept(&printer);
    urdf_text = printer.CStr();
  }

  urdf::ModelInterfaceSharedPtr urdf;
  std::string errors;
  {
    UrdfErrorCapture capture;
    urdf = urdf::parseURDF(urdf_text.empty() ? urdf_xml : urdf_text);
    errors = capture.getErrors();
  }
  if (!urdf)
    failUrdf(source, "invalid URDF: " + (errors.empty() ? std::string("rejected by urdfdom") : errors));
  const urdf::LinkConstSharedPtr root = urdf->getRoot();
  if (!root) failUrdf(source, "the model has no root link");

  Builder builder{*urdf,
                  source,
                  base_dir,
                  default_density,
                  default_joint_damping,
                  std::move(joint_file_order),
                  std::move(capsules),
                  std::move(visual_capsules),
                  {},
                  {}};
  builder.model.source = source;
  builder.model.bodies.emplace_back();  // the root body
  builder.model.bodies[0].link = 0;
  builder.addLink(*root, 0, Transform());
  builder.resolveMimics();
  checkBodyMasses(builder.model, [&source](const std::string& what) { failUrdf(source, what); });
  return std::move(builder.model);
}

}  // namespace scene_detail
}  // namespace manibench
