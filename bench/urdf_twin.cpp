#include "urdf_twin.hpp"

#include <urdf_parser/urdf_parser.h>

#include <cmath>
#include <functional>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace manibench::bench {
namespace {

Eigen::Isometry3d toIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y,
                                  pose.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  X.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  return X;
}

[[noreturn]] void fail(const std::string& what, const std::string& message) {
  throw std::invalid_argument("MuJoCo twin: " + what + ": " + message);
}

// A cylinder with a sphere of its radius centred on each end cap is a
// capsule: the same solid. Merges such triples (URDF has no capsule, so
// the robot generator writes them this way); other shapes stay as they are.
void mergeCapsules(std::vector<TwinGeom>& geoms) {
  constexpr double kTolerance = 1e-9;
  auto isEndSphere = [&](const TwinGeom& sphere, const TwinGeom& cylinder, double side) {
    if (sphere.kind != TwinGeom::Kind::Sphere) return false;
    const Eigen::Vector3d end =
        cylinder.pose * Eigen::Vector3d(0, 0, side * cylinder.size.y());
    return std::abs(sphere.size.x() - cylinder.size.x()) < kTolerance &&
           (sphere.pose.translation() - end).norm() < kTolerance;
  };
  std::vector<bool> used(geoms.size(), false);
  std::vector<TwinGeom> merged;
  for (std::size_t c = 0; c < geoms.size(); ++c) {
    if (geoms[c].kind != TwinGeom::Kind::Cylinder) continue;
    int ends[2] = {-1, -1};
    for (int side = 0; side < 2; ++side)
      for (std::size_t s = 0; s < geoms.size() && ends[side] < 0; ++s)
        if (!used[s] && s != c && isEndSphere(geoms[s], geoms[c], side ? 1.0 : -1.0) &&
            int(s) != ends[0])
          ends[side] = int(s);
    if (ends[0] < 0 || ends[1] < 0) continue;
    used[c] = used[ends[0]] = used[ends[1]] = true;
    TwinGeom capsule = geoms[c];
    capsule.kind = TwinGeom::Kind::Capsule;
    merged.push_back(capsule);
  }
  for (std::size_t i = 0; i < geoms.size(); ++i)
    if (!used[i]) merged.push_back(geoms[i]);
  geoms = std::move(merged);
}

TwinGeom readGeom(const urdf::Collision& collision, const std::string& where) {
  TwinGeom geom;
  geom.pose = toIsometry(collision.origin);
  const urdf::Geometry& g = *collision.geometry;
  switch (g.type) {
    case urdf::Geometry::BOX: {
      const auto& box = static_cast<const urdf::Box&>(g);
      geom.kind = TwinGeom::Kind::Box;
      geom.size = 0.5 * Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z);
      break;
    }
    case urdf::Geometry::SPHERE:
      geom.kind = TwinGeom::Kind::Sphere;
      geom.size.x() = static_cast<const urdf::Sphere&>(g).radius;
      break;
    case urdf::Geometry::CYLINDER: {
      const auto& cylinder = static_cast<const urdf::Cylinder&>(g);
      geom.kind = TwinGeom::Kind::Cylinder;
      geom.size = Eigen::Vector3d(cylinder.radius, cylinder.length / 2, 0);
      break;
    }
    default:
      fail(where, "collision '" + collision.name +
                      "' is a mesh, which the twin does not convert (boxes, spheres and "
                      "cylinders only)");
  }
  if (!(geom.size.minCoeff() >= 0) || !(geom.size.x() > 0))
    fail(where, "collision '" + collision.name + "' has an empty or invalid size");
  return geom;
}

}  // namespace

double calcLowestZ(const TwinGeom& geom, const Eigen::Isometry3d& X_GL) {
  const Eigen::Isometry3d X_GS = X_GL * geom.pose;
  const double z = X_GS.translation().z();
  const Eigen::Vector3d up = X_GS.linear().row(2).transpose();  // world z in the shape frame
  switch (geom.kind) {
    case TwinGeom::Kind::Box:
      return z - up.cwiseAbs().dot(geom.size);
    case TwinGeom::Kind::Sphere:
      return z - geom.size.x();
    case TwinGeom::Kind::Capsule:
      return z - std::abs(up.z()) * geom.size.y() - geom.size.x();
    case TwinGeom::Kind::Cylinder:
      return z - std::abs(up.z()) * geom.size.y() -
             geom.size.x() * std::sqrt(std::max(0.0, 1 - up.z() * up.z()));
  }
  return z;
}

int TwinArticulation::findLink(const std::string& link) const {
  for (std::size_t i = 0; i < links.size(); ++i)
    if (links[i].name == link) return static_cast<int>(i);
  return -1;
}

TwinArticulation parseTwinArticulation(const std::string& urdf_xml, const std::string& name,
                                       const std::string& what) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(urdf_xml);
  if (!model || !model->getRoot()) fail(what, "urdfdom cannot parse the URDF");
  TwinArticulation art;
  art.name = name;
  // Depth first from the root, children in file order: parents come first.
  std::function<void(const urdf::Link&, int)> add = [&](const urdf::Link& link, int parent) {
    TwinLink out;
    out.name = link.name;
    out.parent = parent;
    const std::string where = what + ", link '" + link.name + "'";
    if (const urdf::JointConstSharedPtr& joint = link.parent_joint) {
      out.joint_name = joint->name;
      out.origin = toIsometry(joint->parent_to_joint_origin_transform);
      const Eigen::Vector3d axis(joint->axis.x, joint->axis.y, joint->axis.z);
      switch (joint->type) {
        case urdf::Joint::FIXED: out.joint = TwinLink::Joint::Fixed; break;
        case urdf::Joint::REVOLUTE:
        case urdf::Joint::CONTINUOUS: out.joint = TwinLink::Joint::Revolute; break;
        case urdf::Joint::PRISMATIC: out.joint = TwinLink::Joint::Prismatic; break;
        default:
          fail(where, "joint '" + joint->name +
                          "' is planar or floating, which the twin does not convert");
      }
      if (joint->mimic) fail(where, "joint '" + joint->name + "' is a mimic joint (not converted)");
      if (out.joint != TwinLink::Joint::Fixed) {
        if (!(axis.norm() > 1e-12)) fail(where, "joint '" + joint->name + "' has a zero axis");
        out.axis = axis.normalized();
      }
    }
    if (const urdf::InertialSharedPtr& inertial = link.inertial) {
      // The inertia is given about the centre of mass in the <inertial>
      // frame; MuJoCo's fullinertia is in the body (link) frame.
      const Eigen::Isometry3d X = toIsometry(inertial->origin);
      Eigen::Matrix3d I;
      I << inertial->ixx, inertial->ixy, inertial->ixz, inertial->ixy, inertial->iyy,
          inertial->iyz, inertial->ixz, inertial->iyz, inertial->izz;
      out.mass = inertial->mass;
      out.com = X.translation();
      out.inertia = X.linear() * I * X.linear().transpose();
    }
    for (const urdf::CollisionSharedPtr& collision : link.collision_array)
      if (collision && collision->geometry) out.geoms.push_back(readGeom(*collision, where));
    mergeCapsules(out.geoms);
    art.links.push_back(out);
    const int index = static_cast<int>(art.links.size()) - 1;
    for (const urdf::LinkSharedPtr& child : link.child_links) add(*child, index);
  };
  add(*model->getRoot(), -1);
  return art;
}

namespace {

std::string num(double x) {
  std::ostringstream s;
  s << std::setprecision(17) << x;
  return s.str();
}
std::string vec(const Eigen::Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }
std::string quat(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return num(q.w()) + " " + num(q.x()) + " " + num(q.y()) + " " + num(q.z());
}
std::string frame(const Eigen::Isometry3d& X) {
  return "pos=\"" + vec(X.translation()) + "\" quat=\"" + quat(X.linear()) + "\"";
}
// condim 3: the first coefficient is the sliding friction; the torsional
// and rolling ones (MuJoCo's defaults) are unused.
std::string friction(double mu) { return num(mu) + " 0.005 0.0001"; }

const JointDescription& findJoint(const TwinPlacement& p, const std::string& joint) {
  for (const JointDescription& j : p.joints)
    if (j.name == joint) return j;
  fail(p.articulation.name, "joint '" + joint + "' is not in the manibench scene");
}

std::string geomName(const TwinArticulation& art, const TwinLink& link, std::size_t k) {
  return art.name + "/" + link.name + "/" + std::to_string(k);
}

}  // namespace

std::string toTwinMjcf(const std::vector<TwinPlacement>& placements,
                       const TwinMjcfOptions& options) {
  // Contacts and joint limits as stiff as MuJoCo allows (time constant two
  // steps; its default, 20 ms, lets the 12 Nm wrist pass its limit by 0.25
  // rad and a finger sink 3 cm into the floor under random commands, where
  // manibench's stops and contacts give way by millimetres).
  const std::string stiff = num(2 * options.timestep);
  std::ostringstream x;
  // Buffers sized for the worst case seen (an arm pressed into a cabinet
  // and the floor at once) with a wide margin; MuJoCo warns if exceeded,
  // and the twin fails on any warning.
  x << "<mujoco model=\"twin\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
    << "  <option timestep=\"" << num(options.timestep) << "\" integrator=\"" << options.integrator
    << "\" gravity=\"0 0 -9.81\"/>\n"
    << "  <size nconmax=\"1000\" njmax=\"5000\"/>\n"
    << "  <default>\n"
    << "    <geom contype=\"1\" conaffinity=\"1\" condim=\"3\" solref=\"" << stiff << " 1\"/>\n"
    << "    <pair solref=\"" << stiff << " 1\"/>\n"
    << "    <joint solreflimit=\"" << stiff << " 1\"/>\n"
    << "  </default>\n"
    << "  <worldbody>\n";
  // The floor touches only what the explicit pairs below name, each with
  // its own friction.
  if (options.floor)
    x << "    <geom name=\"floor\" type=\"plane\" size=\"0 0 1\" contype=\"0\" conaffinity=\"0\"/>\n";
  std::ostringstream pairs, excludes;
  for (const TwinPlacement& p : placements) {
    const TwinArticulation& art = p.articulation;
    if (!p.fixed_base) fail(art.name, "floating roots are not converted");
    std::vector<std::vector<int>> children(art.links.size());
    std::vector<bool> moving(art.links.size(), false);  // below a movable joint
    for (std::size_t i = 0; i < art.links.size(); ++i) {
      const TwinLink& link = art.links[i];
      if (link.parent >= 0) {
        children[link.parent].push_back(static_cast<int>(i));
        moving[i] = moving[link.parent] || link.joint != TwinLink::Joint::Fixed;
      }
    }
    std::function<void(int, int)> emit = [&](int index, int depth) {
      const TwinLink& link = art.links[index];
      const std::string pad(2 * depth + 4, ' ');
      x << pad << "<body name=\"" << art.name << "/" << link.name << "\" "
        << frame(index == 0 ? p.root : link.origin) << ">\n";
      if (link.joint == TwinLink::Joint::Revolute || link.joint == TwinLink::Joint::Prismatic) {
        const JointDescription& j = findJoint(p, link.joint_name);
        x << pad << "  <joint name=\"" << art.name << "/" << link.joint_name << "\" type=\""
          << (link.joint == TwinLink::Joint::Revolute ? "hinge" : "slide") << "\" axis=\""
          << vec(link.axis) << "\" damping=\"" << num(j.damping) << "\" frictionloss=\""
          << num(j.friction) << "\"";
        if (std::isfinite(j.lower) || std::isfinite(j.upper))
          x << " limited=\"true\" range=\""
            << num(std::isfinite(j.lower) ? j.lower : -1e10) << " "
            << num(std::isfinite(j.upper) ? j.upper : 1e10) << "\"";
        else
          x << " limited=\"false\"";
        x << "/>\n";
      }
      if (link.mass > 0) {
        const Eigen::Matrix3d& I = link.inertia;
        x << pad << "  <inertial pos=\"" << vec(link.com) << "\" mass=\"" << num(link.mass)
          << "\" fullinertia=\"" << num(I(0, 0)) << " " << num(I(1, 1)) << " " << num(I(2, 2))
          << " " << num(I(0, 1)) << " " << num(I(0, 2)) << " " << num(I(1, 2)) << "\"/>\n";
      }
      for (std::size_t k = 0; k < link.geoms.size(); ++k) {
        const TwinGeom& g = link.geoms[k];
        static const char* kTypes[] = {"box", "sphere", "cylinder", "capsule"};
        const std::string size = g.kind == TwinGeom::Kind::Box      ? vec(g.size)
                                 : g.kind == TwinGeom::Kind::Sphere ? num(g.size.x())
                                                                    : num(g.size.x()) + " " + num(g.size.y());
        const std::string name = geomName(art, link, k);
        x << pad << "  <geom name=\"" << name << "\" type=\"" << kTypes[int(g.kind)] << "\" size=\""
          << size << "\" " << frame(g.pose) << " friction=\"" << friction(p.link_friction[index])
          << "\" priority=\"" << p.link_priority[index] << "\"/>\n";
        // Geoms welded to the world never meet the floor (nor in manibench,
        // where a fixed root is part of Ground).
        if (options.floor && moving[index])
          pairs << "    <pair geom1=\"floor\" geom2=\"" << name << "\" friction=\""
                << num(p.floor_friction[index]) << " " << friction(p.floor_friction[index])
                << " 0.0001\"/>\n";
      }
      for (int child : children[index]) emit(child, depth + 1);
      x << pad << "</body>\n";
    };
    emit(0, 0);
    // Links of one articulation never touch (manibench's default).
    for (std::size_t i = 0; i < art.links.size(); ++i)
      for (std::size_t j = i + 1; j < art.links.size(); ++j)
        if (!art.links[i].geoms.empty() && !art.links[j].geoms.empty())
          excludes << "    <exclude body1=\"" << art.name << "/" << art.links[i].name
                   << "\" body2=\"" << art.name << "/" << art.links[j].name << "\"/>\n";
  }
  x << "  </worldbody>\n  <contact>\n" << pairs.str() << excludes.str() << "  </contact>\n";
  if (!options.actuated.empty()) {
    x << "  <actuator>\n";
    for (const auto& [placement, joint] : options.actuated) {
      const TwinPlacement& p = placements.at(placement);
      const JointDescription& j = findJoint(p, joint);
      const std::string name = p.articulation.name + "/" + joint;
      x << "    <general name=\"" << name << "\" joint=\"" << name
        << "\" gaintype=\"fixed\" gainprm=\"1\" biastype=\"affine\" biasprm=\"0 0 0\""
        << " ctrllimited=\"false\"";
      if (j.effort_limit > 0)
        x << " forcelimited=\"true\" forcerange=\"" << num(-j.effort_limit) << " "
          << num(j.effort_limit) << "\"";
      x << "/>\n";
    }
    x << "  </actuator>\n";
  }
  x << "</mujoco>\n";
  return x.str();
}

void setDrive(mjModel* m, mjData* d, int actuator, const DriveCommand& c) {
  mjtNum* bias = m->actuator_biasprm + actuator * mjNBIAS;
  bias[1] = -c.stiffness;
  bias[2] = -c.damping;
  d->ctrl[actuator] = c.stiffness * c.position_target + c.damping * c.velocity_target + c.force;
}

}  // namespace manibench::bench
