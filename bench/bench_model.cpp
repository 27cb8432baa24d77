#include "bench_model.hpp"

#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace manibench::bench {
namespace {

// 15 significant digits: readable documents, far below any tolerance.
std::ostringstream makeStream() {
  std::ostringstream s;
  s << std::setprecision(15);
  return s;
}

std::string vec(const Eigen::Vector3d& v) {
  std::ostringstream s = makeStream();
  s << v.x() << ' ' << v.y() << ' ' << v.z();
  return s.str();
}

const Link& checkedParent(const Articulation& art, const Link& link) {
  if (link.parent < 0 || link.parent >= static_cast<int>(art.links.size()))
    throw std::invalid_argument("bench model: link '" + link.name + "' of '" +
                                art.name + "' has no valid parent");
  return art.links[link.parent];
}

void checkArticulation(const Articulation& art) {
  if (art.links.empty())
    throw std::invalid_argument("bench model: articulation '" + art.name + "' has no links");
  if (art.links[0].joint != Link::Joint::Root)
    throw std::invalid_argument("bench model: the first link of '" + art.name + "' must be the root");
  for (std::size_t i = 1; i < art.links.size(); ++i) {
    if (art.links[i].joint == Link::Joint::Root || art.links[i].parent >= static_cast<int>(i))
      throw std::invalid_argument("bench model: link '" + art.links[i].name + "' of '" +
                                  art.name + "' must follow its parent and have a joint");
    checkedParent(art, art.links[i]);
  }
}

}  // namespace

Shape Shape::box(const Eigen::Vector3d& half, const Eigen::Vector3d& at) {
  Shape s;
  s.kind = Kind::Box;
  s.half_extents = half;
  s.position = at;
  return s;
}

Shape Shape::sphere(double radius, const Eigen::Vector3d& at) {
  Shape s;
  s.kind = Kind::Sphere;
  s.radius = radius;
  s.position = at;
  return s;
}

int Model::countShapes() const {
  int n = 0;
  for (const Articulation& art : articulations)
    for (const Link& link : art.links) n += static_cast<int>(link.shapes.size());
  return n;
}

std::string toUrdf(const Articulation& art) {
  checkArticulation(art);
  std::ostringstream x = makeStream();
  x << "<?xml version=\"1.0\"?>\n<robot name=\"" << art.name << "\">\n";
  for (const Link& link : art.links) {
    x << "  <link name=\"" << link.name << "\">\n"
      << "    <inertial><origin xyz=\"" << vec(link.com) << "\"/><mass value=\"" << link.mass
      << "\"/><inertia ixx=\"" << link.inertia.x() << "\" iyy=\"" << link.inertia.y()
      << "\" izz=\"" << link.inertia.z() << "\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>\n";
    for (const Shape& shape : link.shapes) {
      x << "    <collision><origin xyz=\"" << vec(shape.position) << "\"/><geometry>";
      if (shape.kind == Shape::Kind::Box)
        x << "<box size=\"" << vec(2 * shape.half_extents) << "\"/>";
      else
        x << "<sphere radius=\"" << shape.radius << "\"/>";
      x << "</geometry></collision>\n";
    }
    x << "  </link>\n";
  }
  for (const Link& link : art.links) {
    if (link.joint == Link::Joint::Root) continue;
    const Link& parent = checkedParent(art, link);
    const bool revolute = link.joint == Link::Joint::Revolute;
    // An unlimited revolute joint is "continuous"; an unlimited prismatic
    // one has lower == upper, which manibench reads as "no position limit".
    const char* type = revolute ? (link.limited ? "revolute" : "continuous") : "prismatic";
    x << "  <joint name=\"" << link.joint_name << "\" type=\"" << type << "\">\n"
      << "    <parent link=\"" << parent.name << "\"/><child link=\"" << link.name << "\"/>\n"
      << "    <origin xyz=\"" << vec(link.origin) << "\"/><axis xyz=\"" << vec(link.axis) << "\"/>\n"
      << "    <limit lower=\"" << (link.limited ? link.lower : 0.0) << "\" upper=\""
      << (link.limited ? link.upper : 0.0) << "\" effort=\"" << link.effort
      << "\" velocity=\"0\"/>\n"
      << "    <dynamics damping=\"" << link.damping << "\" friction=\"0\"/>\n"
      << "  </joint>\n";
  }
  x << "</robot>\n";
  return x.str();
}

std::string mjcfName(const Articulation& art, const std::string& name) {
  return art.name + "/" + name;
}

std::string toMjcf(const Model& model, const MjcfOptions& options) {
  for (const Articulation& art : model.articulations) checkArticulation(art);
  // Buffers: a box touches a plane or a box in up to 8 points (MuJoCo's
  // box-box); a pyramidal friction cone of dimension 3 takes 4 rows.
  const int ncon = 8 * model.countShapes() + 64;
  std::ostringstream x = makeStream();
  x << "<mujoco model=\"" << model.name << "\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
    << "  <option timestep=\"" << options.timestep << "\" integrator=\"" << options.integrator
    << "\" gravity=\"0 0 -9.81\"/>\n"
    << "  <size nconmax=\"" << ncon << "\" njmax=\"" << 4 * ncon + 64 << "\"/>\n"
    << "  <default><geom friction=\"" << model.friction << " 0.005 0.0001\"/></default>\n"
    << "  <worldbody>\n";
  if (model.ground) x << "    <geom name=\"floor\" type=\"plane\" size=\"0 0 1\"/>\n";

  for (const Articulation& art : model.articulations) {
    // Children of each link, to nest the bodies depth first.
    std::vector<std::vector<int>> children(art.links.size());
    for (std::size_t i = 1; i < art.links.size(); ++i) children[art.links[i].parent].push_back(static_cast<int>(i));
    auto emit = [&](auto&& self, int index, int depth) -> void {
      const Link& link = art.links[index];
      const std::string pad(2 * depth + 4, ' ');
      const Eigen::Vector3d pos = index == 0 ? art.root_position : link.origin;
      x << pad << "<body name=\"" << mjcfName(art, link.name) << "\" pos=\"" << vec(pos) << "\">\n";
      if (index == 0 && !art.fixed_base) {
        x << pad << "  <freejoint name=\"" << mjcfName(art, "root") << "\"/>\n";
      } else if (index != 0) {
        x << pad << "  <joint name=\"" << mjcfName(art, link.joint_name) << "\" type=\""
          << (link.joint == Link::Joint::Revolute ? "hinge" : "slide") << "\" axis=\""
          << vec(link.axis) << "\" damping=\"" << link.damping << "\"";
        if (link.limited)
          x << " limited=\"true\" range=\"" << link.lower << ' ' << link.upper << "\"";
        else
          x << " limited=\"false\"";
        x << "/>\n";
      }
      x << pad << "  <inertial pos=\"" << vec(link.com) << "\" mass=\"" << link.mass
        << "\" diaginertia=\"" << vec(link.inertia) << "\"/>\n";
      for (const Shape& shape : link.shapes) {
        if (shape.kind == Shape::Kind::Box)
          x << pad << "  <geom type=\"box\" pos=\"" << vec(shape.position) << "\" size=\""
            << vec(shape.half_extents) << "\"/>\n";
        else
          x << pad << "  <geom type=\"sphere\" pos=\"" << vec(shape.position) << "\" size=\""
            << shape.radius << "\"/>\n";
      }
      for (int child : children[index]) self(self, child, depth + 1);
      x << pad << "</body>\n";
    };
    emit(emit, 0, 0);
  }
  x << "  </worldbody>\n";

  // Links of one articulation never touch (manibench's contact cliques).
  std::ostringstream excludes = makeStream();
  for (const Articulation& art : model.articulations)
    for (std::size_t i = 0; i < art.links.size(); ++i)
      for (std::size_t j = i + 1; j < art.links.size(); ++j)
        if (!art.links[i].shapes.empty() && !art.links[j].shapes.empty())
          excludes << "    <exclude body1=\"" << mjcfName(art, art.links[i].name) << "\" body2=\""
                   << mjcfName(art, art.links[j].name) << "\"/>\n";
  if (!excludes.str().empty()) x << "  <contact>\n" << excludes.str() << "  </contact>\n";

  // tau = ctrl - kp q - kd qdot with ctrl = kp q_target + kd v_target: the
  // drive law of manibench::DriveCommand, clamped like it to the effort.
  if (!model.drives.empty()) {
    x << "  <actuator>\n";
    for (const Drive& drive : model.drives) {
      const Articulation& art = model.articulations.at(drive.articulation);
      const Link* link = nullptr;
      for (const Link& l : art.links)
        if (l.joint != Link::Joint::Root && l.joint_name == drive.joint) link = &l;
      if (link == nullptr)
        throw std::invalid_argument("bench model: drive on unknown joint '" + drive.joint + "'");
      x << "    <general name=\"" << mjcfName(art, drive.joint) << "\" joint=\""
        << mjcfName(art, drive.joint)
        << "\" gaintype=\"fixed\" gainprm=\"1\" biastype=\"affine\" biasprm=\"0 "
        << -drive.stiffness << ' ' << -drive.damping << "\" ctrllimited=\"false\"";
      if (link->effort > 0)
        x << " forcelimited=\"true\" forcerange=\"" << -link->effort << ' ' << link->effort << "\"";
      x << "/>\n";
    }
    x << "  </actuator>\n";
  }
  x << "</mujoco>\n";
  return x.str();
}

}  // namespace manibench::bench
