#include "scene/urdf_model.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
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

constexpr double kPi = 3.14159265358979323846;

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

[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw SceneError("URDF " + source + ": " + what);
}

Transform toTransform(const urdf::Pose& pose) {
  double x, y, z, w;
  pose.rotation.getQuaternion(x, y, z, w);
  return Transform(Rotation(SimTK::Quaternion(w, x, y, z)),
                   Vec3(pose.position.x, pose.position.y, pose.position.z));
}

SymMat33 toSymmetric(const Mat33& m) {
  return SymMat33().setFromLower(0.5 * (m + ~m));
}

const char* describeGeometry(int type) {
  switch (type) {
    case urdf::Geometry::SPHERE: return "sphere";
    case urdf::Geometry::BOX: return "box";
    case urdf::Geometry::CYLINDER: return "cylinder";
    case urdf::Geometry::MESH: return "mesh";
  }
  return "unknown geometry";
}

// Adds a rigid part of mass m, centre of mass com_B and central inertia
// Ic_B (both in the body frame) to the body's mass properties.
void addMass(BodyModel& body, double m, const Vec3& com_B, const Mat33& Ic_B) {
  if (m <= 0) return;
  body.mass += m;
  body.first_moment += m * com_B;
  body.inertia += Inertia(toSymmetric(Ic_B)).shiftFromMassCenter(com_B, m);
}

struct Builder {
  const urdf::ModelInterface& urdf;
  const std::string& source;
  double density;
  std::map<std::string, int> joint_file_order;
  ArticulationModel model;

  int getFileOrder(const std::string& joint_name) const {
    const auto found = joint_file_order.find(joint_name);
    return found == joint_file_order.end() ? std::numeric_limits<int>::max()
                                           : found->second;
  }

  // The link's own mass properties, from <inertial> or else from its
  // collision volume at the default density.
  void addLinkMass(const urdf::Link& link, const Transform& X_BL,
                   BodyModel& body) {
    if (link.inertial) {
      const urdf::Inertial& in = *link.inertial;
      if (!std::isfinite(in.mass) || in.mass < 0)
        fail(source, "link '" + link.name + "' has invalid mass " +
                         std::to_string(in.mass));
      if (in.mass == 0) return;
      const Mat33 Ic_I(in.ixx, in.ixy, in.ixz,  //
                       in.ixy, in.iyy, in.iyz,  //
                       in.ixz, in.iyz, in.izz);
      if (!Inertia::isValidInertiaMatrix(SymMat33().setFromLower(Ic_I))) {
        std::ostringstream s;
        s << "link '" << link.name << "' has an invalid inertia (ixx " << in.ixx
          << " iyy " << in.iyy << " izz " << in.izz << " ixy " << in.ixy
          << " ixz " << in.ixz << " iyz " << in.iyz
          << "): moments must be non-negative and obey the triangle inequality";
        fail(source, s.str());
      }
      const Transform X_BI = X_BL * toTransform(in.origin);
      const Mat33 R = X_BI.R().asMat33();
      addMass(body, in.mass, X_BI.p(), R * Ic_I * ~R);
      return;
    }
    for (const urdf::CollisionSharedPtr& collision : link.collision_array) {
      if (!collision || !collision->geometry) continue;
      const Transform X_BS = X_BL * toTransform(collision->origin);
      const Mat33 R = X_BS.R().asMat33();
      const urdf::Geometry& g = *collision->geometry;
      double m = 0;
      Vec3 moments(0);  // central, in the shape frame
      if (g.type == urdf::Geometry::SPHERE) {
        const double r = static_cast<const urdf::Sphere&>(g).radius;
        m = density * 4.0 / 3.0 * kPi * r * r * r;
        moments = Vec3(0.4 * m * r * r);
      } else if (g.type == urdf::Geometry::BOX) {
        const urdf::Vector3& d = static_cast<const urdf::Box&>(g).dim;
        m = density * d.x * d.y * d.z;
        moments = m / 12 * Vec3(d.y * d.y + d.z * d.z, d.x * d.x + d.z * d.z,
                                d.x * d.x + d.y * d.y);
      } else if (g.type == urdf::Geometry::CYLINDER) {
        const auto& c = static_cast<const urdf::Cylinder&>(g);
        const double r = c.radius, l = c.length;
        m = density * kPi * r * r * l;
        const double side = m * (3 * r * r + l * l) / 12;
        moments = Vec3(side, side, 0.5 * m * r * r);
      }
      // A mesh's volume needs the mesh loader (not there yet): no mass.
      const Mat33 Ic_S(moments[0], 0, 0, 0, moments[1], 0, 0, 0, moments[2]);
      addMass(body, m, X_BS.p(), R * Ic_S * ~R);
    }
  }

  void addLinkShapes(const urdf::Link& link, int link_index,
                     const Transform& X_BL, BodyModel& body) {
    int ordinal = 0;
    for (const urdf::CollisionSharedPtr& collision : link.collision_array) {
      ++ordinal;
      if (!collision || !collision->geometry) continue;
      const urdf::Geometry& g = *collision->geometry;
      CollisionShape shape;
      shape.link = link_index;
      shape.X_BS = X_BL * toTransform(collision->origin);
      if (g.type == urdf::Geometry::SPHERE) {
        const double r = static_cast<const urdf::Sphere&>(g).radius;
        if (!(r > 0) || !std::isfinite(r))
          fail(source, "link '" + link.name + "' has a sphere of radius " +
                           std::to_string(r));
        shape.kind = CollisionShape::Kind::Sphere;
        shape.size = Vec3(r, 0, 0);
      } else if (g.type == urdf::Geometry::BOX) {
        const urdf::Vector3& d = static_cast<const urdf::Box&>(g).dim;
        if (!(d.x > 0 && d.y > 0 && d.z > 0) ||
            !std::isfinite(d.x + d.y + d.z))
          fail(source, "link '" + link.name + "' has a box of size " +
                           std::to_string(d.x) + " " + std::to_string(d.y) +
                           " " + std::to_string(d.z));
        shape.kind = CollisionShape::Kind::Box;
        shape.size = Vec3(d.x / 2, d.y / 2, d.z / 2);
      } else {
        std::string what = "link '" + link.name + "': " +
                           describeGeometry(g.type) + " '" +
                           (collision->name.empty()
                                ? "#" + std::to_string(ordinal)
                                : collision->name) + "'";
        model.unsimulated.push_back(std::move(what));
        continue;
      }
      body.shapes.push_back(shape);
    }
  }

  // Adds `link` (reached with the link frame at X_BL in body `body_index`)
  // and, depth first, everything below it.
  void addLink(const urdf::Link& link, int body_index, const Transform& X_BL) {
    const int link_index = static_cast<int>(model.links.size());
    model.links.push_back({link.name, body_index, X_BL});
    addLinkMass(link, X_BL, model.bodies[body_index]);
    addLinkShapes(link, link_index, X_BL, model.bodies[body_index]);

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

  void addJoint(const urdf::Joint& joint, int parent_body,
                const Transform& X_PL) {
    const urdf::LinkConstSharedPtr child = urdf.getLink(joint.child_link_name);
    if (!child)
      fail(source, "joint '" + joint.name + "' has unknown child link '" +
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
        fail(source, "joint '" + joint.name +
                         "' is floating; only the root may float (fixed_base = "
                         "false), not a link inside the tree");
      case urdf::Joint::PLANAR:
        fail(source, "joint '" + joint.name +
                         "' is planar, which is not supported (revolute, "
                         "continuous, prismatic and fixed are)");
      default:
        fail(source, "joint '" + joint.name + "' has an unsupported type");
    }
    const Vec3 axis(joint.axis.x, joint.axis.y, joint.axis.z);
    if (!(axis.norm() > 1e-12) || !axis.isFinite())
      fail(source, "joint '" + joint.name + "' has a zero or invalid axis");
    if (joint.limits) {
      const urdf::JointLimits& limits = *joint.limits;
      if (limits.effort < 0 || limits.velocity < 0)
        fail(source, "joint '" + joint.name + "' has a negative effort or velocity limit");
      description.effort_limit = limits.effort;
      description.velocity_limit = limits.velocity;
      // lower == upper (both default to 0 in urdfdom) is read as "no
      // position limit": real files use it for unlimited joints.
      if (description.type != JointType::Continuous &&
          limits.lower != limits.upper) {
        if (!(limits.lower < limits.upper))
          fail(source, "joint '" + joint.name + "' has lower limit " +
                           std::to_string(limits.lower) + " above upper limit " +
                           std::to_string(limits.upper));
        description.lower = limits.lower;
        description.upper = limits.upper;
      }
    }
    if (joint.dynamics) {
      if (!(joint.dynamics->damping >= 0) || !(joint.dynamics->friction >= 0))
        fail(source, "joint '" + joint.name + "' has negative damping or friction");
      description.damping = joint.dynamics->damping;
      description.friction = joint.dynamics->friction;
    }
    if (joint.mimic)
      std::fprintf(stderr,
                   "manibench: URDF %s: mimic of joint '%s' is ignored (not "
                   "supported yet); it moves independently\n",
                   source.c_str(), joint.name.c_str());

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

ArticulationModel buildArticulationModel(const std::string& urdf_xml,
                                         const std::string& source,
                                         double default_density) {
  // TinyXML first: it says where malformed XML breaks, and it gives the
  // joints' file order, which urdfdom does not keep.
  TiXmlDocument doc;
  doc.Parse(urdf_xml.c_str());
  if (doc.Error()) {
    std::ostringstream s;
    s << "malformed XML";
    if (doc.ErrorRow() > 0) s << " at line " << doc.ErrorRow() << ", column " << doc.ErrorCol();
    s << ": " << doc.ErrorDesc();
    fail(source, s.str());
  }
  std::map<std::string, int> joint_file_order;
  if (const TiXmlElement* robot = doc.FirstChildElement("robot")) {
    for (const TiXmlElement* j = robot->FirstChildElement("joint"); j != nullptr;
         j = j->NextSiblingElement("joint")) {
      if (const char* name = j->Attribute("name"))
        joint_file_order.emplace(name, static_cast<int>(joint_file_order.size()));
    }
  }

  urdf::ModelInterfaceSharedPtr urdf;
  std::string errors;
  {
    UrdfErrorCapture capture;
    urdf = urdf::parseURDF(urdf_xml);
    errors = capture.getErrors();
  }
  if (!urdf)
    fail(source, "invalid URDF: " + (errors.empty() ? std::string("rejected by urdfdom") : errors));
  const urdf::LinkConstSharedPtr root = urdf->getRoot();
  if (!root) fail(source, "the model has no root link");

  Builder builder{*urdf, source, default_density, std::move(joint_file_order), {}};
  builder.model.source = source;
  builder.model.bodies.emplace_back();  // the root body
  builder.model.bodies[0].link = 0;
  builder.addLink(*root, 0, Transform());
  return std::move(builder.model);
}

}  // namespace scene_detail
}  // namespace manibench
