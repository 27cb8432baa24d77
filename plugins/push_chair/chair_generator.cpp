// Procedural office chairs: a 5-leg star base on casters (each a swivel
// joint about the vertical and a wheel joint), a gas-lift column, a seat on
// a swivel joint, a backrest (fixed, or reclining on a joint) and optional
// armrests, at the sizes of real office chairs (asset-facts.md: seat
// 0.38-0.56 m, base 0.66-0.71 m across). Collision geometry is convex
// primitives (boxes, cylinders, sphere wheels); masses and inertias come
// from the primitives at ManiSkill's chair density, 200 kg/m^3. The
// parameters of a chair come from a hash of its id, so an id always names
// the same chair on every platform.
//
// Splits: train 3000-3029 (30 chairs), test 3100-3109 (10). The test split
// holds designs training never shows: headrest and curved (wrap-around)
// backrests, loop armrests and height-adjustable armrests (two prismatic
// joints), and seats up to 0.56 m wide (train up to 0.52 m).
#include "push_chair.hpp"

#include <iomanip>
#include <optional>
#include <sstream>

namespace push_chair {

namespace {

constexpr double kDensity = 200;  // kg/m^3, ManiSkill's chairs
const NumberedIds kIds{{3000, 30}, {3100, 10}};
constexpr double kMechanismHeight = 0.05;  // seat mechanism box under the cushion
constexpr double kMaxChairHeight = 1.2;    // stays below the robot's arms at lift 0.9
constexpr double kSurfaceSpacing = 0.03;   // reward point sampling, m

using Color = std::array<double, 3>;

// One primitive of a link, in the link frame.
struct Part {
  enum class Kind { kBox, kCylinder, kSphere };
  std::string name;
  Kind kind = Kind::kBox;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // box sides; cylinder (r, r, length); sphere (r, r, r)
  Color color{};
  bool visual = true, collision = true;  // mass comes from the colliding parts
};

Eigen::Isometry3d at(const Eigen::Vector3d& p, const Eigen::Matrix3d& r = Eigen::Matrix3d::Identity()) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() = p;
  return t;
}
Eigen::Matrix3d rotZ(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }
Eigen::Matrix3d rotY(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
Eigen::Matrix3d rotX(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }

Part box(const std::string& name, const Eigen::Isometry3d& pose, const Eigen::Vector3d& size, const Color& color) {
  Part p;
  p.name = name;
  p.pose = pose;
  p.size = size;
  p.color = color;
  return p;
}
Part cylinder(const std::string& name, const Eigen::Isometry3d& pose, double radius, double length, const Color& color) {
  Part p = box(name, pose, Eigen::Vector3d(radius, radius, length), color);
  p.kind = Part::Kind::kCylinder;
  return p;
}
// A box whose x axis runs from `a` to `b` (its length), with the given
// cross-section; `up` picks the roll (the box's z stays closest to it).
Part beam(const std::string& name, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double width, double thickness,
          const Color& color) {
  const Eigen::Vector3d x = (b - a).normalized();
  Eigen::Vector3d y = Eigen::Vector3d::UnitZ().cross(x);
  if (y.norm() < 1e-6) y = Eigen::Vector3d::UnitY();
  y.normalize();
  Eigen::Matrix3d r;
  r << x, y, x.cross(y);
  return box(name, at((a + b) / 2, r), Eigen::Vector3d((b - a).norm(), width, thickness), color);
}

void calcMass(const Part& p, double& m, Eigen::Matrix3d& inertia) {  // about the part's centre, part frame
  const Eigen::Vector3d s = p.size;
  switch (p.kind) {
    case Part::Kind::kBox: {
      m = kDensity * s.prod();
      const Eigen::Vector3d q = s.cwiseProduct(s);
      inertia = (m / 12.0) * Eigen::Vector3d(q.y() + q.z(), q.x() + q.z(), q.x() + q.y()).asDiagonal();
      break;
    }
    case Part::Kind::kCylinder: {
      const double r = s.x(), l = s.z();
      m = kDensity * kPi * r * r * l;
      const double side = m * (3 * r * r + l * l) / 12.0;
      inertia = Eigen::Vector3d(side, side, m * r * r / 2).asDiagonal();
      break;
    }
    case Part::Kind::kSphere: {
      const double r = s.x();
      m = kDensity * 4.0 / 3.0 * kPi * r * r * r;
      inertia = (0.4 * m * r * r) * Eigen::Matrix3d::Identity();
      break;
    }
  }
}

std::string fmt(double x) {
  std::ostringstream s;
  s << std::setprecision(9) << (std::abs(x) < 1e-12 ? 0.0 : x);
  return s.str();
}
std::string vec(const Eigen::Vector3d& v) { return fmt(v.x()) + " " + fmt(v.y()) + " " + fmt(v.z()); }
std::string origin(const Eigen::Isometry3d& t) {
  const Eigen::Vector3d ypr = t.linear().eulerAngles(2, 1, 0);  // R = Rz(yaw) Ry(pitch) Rx(roll)
  return "<origin xyz=\"" + vec(t.translation()) + "\" rpy=\"" + fmt(ypr[2]) + " " + fmt(ypr[1]) + " " +
         fmt(ypr[0]) + "\"/>";
}
std::string geometry(const Part& p) {
  switch (p.kind) {
    case Part::Kind::kBox: return "<geometry><box size=\"" + vec(p.size) + "\"/></geometry>";
    case Part::Kind::kCylinder:
      return "<geometry><cylinder radius=\"" + fmt(p.size.x()) + "\" length=\"" + fmt(p.size.z()) + "\"/></geometry>";
    case Part::Kind::kSphere: return "<geometry><sphere radius=\"" + fmt(p.size.x()) + "\"/></geometry>";
  }
  return "";
}

// One link: the combined inertia of its colliding parts about their centre
// of mass, then a visual and a collision per part.
std::string writeLink(const std::string& name, const std::vector<Part>& parts) {
  struct PartMass {
    const Part* part;
    double m;
    Eigen::Matrix3d i;  // about the part's centre, in its frame
  };
  std::vector<PartMass> colliding;
  for (const Part& p : parts)
    if (p.collision) {
      colliding.push_back({&p, 0, Eigen::Matrix3d::Zero()});
      calcMass(p, colliding.back().m, colliding.back().i);
    }
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  for (const PartMass& c : colliding) {
    mass += c.m;
    com += c.m * c.part->pose.translation();
  }
  if (!(mass > 0)) throw Error("chair generator: link '" + name + "' has no mass", MB_ERROR);  // a generator bug
  com /= mass;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const PartMass& c : colliding) {
    const Eigen::Matrix3d r = c.part->pose.linear();
    const Eigen::Vector3d d = c.part->pose.translation() - com;
    inertia += r * c.i * r.transpose() + c.m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  std::ostringstream x;
  x << "  <link name=\"" << name << "\">\n    <inertial><origin xyz=\"" << vec(com) << "\"/><mass value=\""
    << fmt(mass) << "\"/><inertia ixx=\"" << fmt(inertia(0, 0)) << "\" ixy=\"" << fmt(inertia(0, 1))
    << "\" ixz=\"" << fmt(inertia(0, 2)) << "\" iyy=\"" << fmt(inertia(1, 1)) << "\" iyz=\""
    << fmt(inertia(1, 2)) << "\" izz=\"" << fmt(inertia(2, 2)) << "\"/></inertial>\n";
  for (const Part& p : parts) {
    const std::string g = origin(p.pose) + geometry(p);
    if (p.visual)
      x << "    <visual name=\"" << p.name << "\">" << g << "<material name=\"" << p.name
        << "_color\"><color rgba=\"" << fmt(p.color[0]) << " " << fmt(p.color[1]) << " " << fmt(p.color[2])
        << " 1\"/></material></visual>\n";
    if (p.collision) x << "    <collision name=\"" << p.name << "\">" << g << "</collision>\n";
  }
  x << "  </link>\n";
  return x.str();
}

std::string writeJoint(const std::string& name, const std::string& type, const std::string& parent,
                       const std::string& child, const Eigen::Isometry3d& pose, const Eigen::Vector3d& axis,
                       double lower = 0, double upper = 0) {
  std::ostringstream x;
  x << "  <joint name=\"" << name << "\" type=\"" << type << "\">\n    <parent link=\"" << parent
    << "\"/>\n    <child link=\"" << child << "\"/>\n    " << origin(pose) << "\n    <axis xyz=\"" << vec(axis)
    << "\"/>\n";
  if (type == "revolute" || type == "prismatic")
    x << "    <limit lower=\"" << fmt(lower) << "\" upper=\"" << fmt(upper) << "\" effort=\"100\" velocity=\"2\"/>\n";
  x << "  </joint>\n";
  return x.str();
}

// Surface points of a link's colliding parts, in the link frame.
std::vector<Eigen::Vector3d> samplePartSurfaces(const std::vector<Part>& parts) {
  std::vector<Eigen::Vector3d> out;
  for (const Part& p : parts) {
    if (!p.collision) continue;
    if (p.kind == Part::Kind::kBox) {
      const std::vector<Eigen::Vector3d> s = sampleBoxSurface(p.pose, p.size, kSurfaceSpacing);
      out.insert(out.end(), s.begin(), s.end());
      continue;
    }
    const double r = p.size.x();
    const double l = p.kind == Part::Kind::kCylinder ? p.size.z() : 0.0;
    const int around = std::max(8, int(std::ceil(2 * kPi * r / kSurfaceSpacing)));
    const int along = std::max(1, int(std::ceil(l / kSurfaceSpacing)));
    for (int i = 0; i < around; ++i) {
      const double a = 2 * kPi * i / around;
      if (p.kind == Part::Kind::kCylinder) {
        for (int k = 0; k <= along; ++k)
          out.push_back(p.pose * Eigen::Vector3d(r * std::cos(a), r * std::sin(a), -l / 2 + l * k / along));
      } else {
        for (int k = 1; k < 4; ++k) {
          const double b = kPi * k / 4;
          out.push_back(p.pose * Eigen::Vector3d(r * std::sin(b) * std::cos(a), r * std::sin(b) * std::sin(a),
                                                 r * std::cos(b)));
        }
      }
    }
    if (p.kind == Part::Kind::kSphere) {
      out.push_back(p.pose * Eigen::Vector3d(0, 0, r));
      out.push_back(p.pose * Eigen::Vector3d(0, 0, -r));
    }
  }
  return out;
}

Color pick(Random& rng, const std::vector<Color>& palette, double spread) {
  Color c = palette[std::size_t(rng.integer(0, int(palette.size()) - 1))];
  for (double& x : c) x = std::clamp(x + rng.uniform(-spread, spread), 0.0, 1.0);
  return c;
}

}  // namespace

std::vector<Eigen::Vector3d> sampleBoxSurface(const Eigen::Isometry3d& pose, const Eigen::Vector3d& size,
                                              double spacing) {
  std::vector<Eigen::Vector3d> out;
  const Eigen::Vector3d h = size / 2;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int nu = std::max(1, int(std::ceil(size[u] / spacing))), nv = std::max(1, int(std::ceil(size[v] / spacing)));
    for (const double side : {-1.0, 1.0})
      for (int i = 0; i <= nu; ++i)
        for (int j = 0; j <= nv; ++j) {
          Eigen::Vector3d p;
          p[axis] = side * h[axis];
          p[u] = -h[u] + size[u] * i / nu;
          p[v] = -h[v] + size[v] * j / nv;
          out.push_back(pose * p);
        }
  }
  return out;
}

std::string toString(BackrestShape shape) {
  switch (shape) {
    case BackrestShape::kRectangular: return "rectangular";
    case BackrestShape::kRounded: return "rounded";
    case BackrestShape::kHeadrest: return "headrest";
    case BackrestShape::kCurved: return "curved";
  }
  return "?";
}

std::string toString(ArmrestType type) {
  switch (type) {
    case ArmrestType::kNone: return "none";
    case ArmrestType::kFixedT: return "T";
    case ArmrestType::kLoop: return "loop";
    case ArmrestType::kAdjustableT: return "adjustable T";
  }
  return "?";
}

std::vector<std::string> listGeneratedChairs(const std::string& split) { return kIds.list(split); }

ChairParams getChairParams(const std::string& chair_id) {
  const bool test = kIds.requireTest(chair_id, "generated chair");
  Random rng(hashString("manibench.push_chair.v1:" + chair_id));
  ChairParams p;
  // base: 0.66-0.71 m across the leg ends
  p.base_radius = rng.uniform(0.31, 0.335);
  p.hub_radius = rng.uniform(0.045, 0.055);
  p.wheel_radius = rng.uniform(0.025, 0.0325);
  p.caster_trail = rng.uniform(0.025, 0.04);
  p.caster_drop = rng.uniform(0.04, 0.05);
  p.hub_height = p.wheel_radius + p.caster_drop + rng.uniform(0.035, 0.055);
  p.column_radius = rng.uniform(0.025, 0.03);
  // seat
  p.seat_height = test ? rng.uniform(0.44, 0.52) : rng.uniform(0.42, 0.50);
  p.seat_width = test ? rng.uniform(0.50, 0.56) : rng.uniform(0.44, 0.52);
  p.seat_depth = test ? rng.uniform(0.44, 0.52) : rng.uniform(0.42, 0.50);
  p.seat_thickness = rng.uniform(0.06, 0.09);
  p.seat_offset = rng.uniform(0.0, 0.04);
  // backrest
  p.backrest = test ? (rng.chance(0.5) ? BackrestShape::kHeadrest : BackrestShape::kCurved)
                     : (rng.chance(0.5) ? BackrestShape::kRectangular : BackrestShape::kRounded);
  p.backrest_width = p.seat_width * rng.uniform(0.85, 1.0);
  p.backrest_height = rng.uniform(0.40, 0.60);
  p.backrest_thickness = rng.uniform(0.04, 0.06);
  p.backrest_gap = rng.uniform(0.05, 0.10);
  p.backrest_angle = rng.uniform(0.08, 0.22);
  p.reclining = rng.chance(0.5);
  // armrests
  const double a = rng.uniform(0, 1);
  if (test)
    p.armrest = a < 0.3 ? ArmrestType::kNone : a < 0.65 ? ArmrestType::kLoop : ArmrestType::kAdjustableT;
  else
    p.armrest = a < 0.4 ? ArmrestType::kNone : ArmrestType::kFixedT;
  p.armrest_height = rng.uniform(0.18, 0.25);
  p.frame_color = pick(rng, {{0.08, 0.08, 0.09}, {0.35, 0.36, 0.38}, {0.72, 0.73, 0.75}}, 0.04);
  p.seat_color = pick(rng, {{0.10, 0.10, 0.12}, {0.55, 0.08, 0.08}, {0.12, 0.22, 0.45}, {0.35, 0.35, 0.38},
                             {0.15, 0.35, 0.20}, {0.45, 0.30, 0.18}},
                      0.05);
  // whole chair below kMaxChairHeight
  const double headrest = p.backrest == BackrestShape::kHeadrest ? 0.20 : 0.0;
  const double room = kMaxChairHeight - (p.seat_height + p.backrest_gap + headrest);
  p.backrest_height = std::min(p.backrest_height, room / std::cos(p.backrest_angle));
  return p;
}

ChairModel generateChair(const std::string& chair_id) { return generateChair(chair_id, getChairParams(chair_id)); }

namespace {

const Color kDark{0.05, 0.05, 0.05};
const Color kMetal{0.75, 0.76, 0.78};
constexpr double kHubHalf = 0.03;

// The swivel mounts' height and the column's top (the seat's frame).
double calcMountHeight(const ChairParams& p) { return p.wheel_radius + p.caster_drop; }
double calcColumnTop(const ChairParams& p) { return p.seat_height - p.seat_thickness - kMechanismHeight; }

// The base link: hub, legs, leg-end caps, gas-lift column.
std::vector<Part> makeBase(const ChairParams& p) {
  const Color& frame = p.frame_color;
  const double mount = calcMountHeight(p), column_top = calcColumnTop(p);
  std::vector<Part> base;
  base.push_back(cylinder("hub", at({0, 0, p.hub_height}), p.hub_radius, 2 * kHubHalf, frame));
  for (int k = 0; k < p.legs; ++k) {
    const double a = 2 * kPi * k / p.legs;
    const Eigen::Vector3d dir(std::cos(a), std::sin(a), 0);
    const Eigen::Vector3d inner = 0.5 * p.hub_radius * dir + Eigen::Vector3d(0, 0, p.hub_height);
    const Eigen::Vector3d outer = p.base_radius * dir + Eigen::Vector3d(0, 0, mount + 0.03);
    base.push_back(beam("leg_" + std::to_string(k), inner, outer, 0.045, 0.03, frame));
    base.push_back(cylinder("leg_cap_" + std::to_string(k), at(p.base_radius * dir + Eigen::Vector3d(0, 0, mount + 0.0125)),
                            0.02, 0.025, frame));
  }
  const double column_bottom = p.hub_height + kHubHalf;
  base.push_back(cylinder("column", at({0, 0, (column_bottom + column_top) / 2}), p.column_radius,
                          column_top - column_bottom, kMetal));
  base.push_back(cylinder("column_sleeve", at({0, 0, column_bottom + 0.06}), p.column_radius + 0.008, 0.12, frame));
  base.back().collision = false;
  return base;
}

// The casters: the fork turns about the vertical at the leg end, the wheel
// trails behind the swivel axis (along the fork's -x). Their links go to
// `urdf`, their joints to `joints_xml` and the chair.
void addCasters(const ChairParams& p, ChairModel& chair, std::ostream& urdf, std::vector<std::string>& joints_xml) {
  const double mount = calcMountHeight(p);
  for (int k = 0; k < p.legs; ++k) {
    const std::string n = std::to_string(k);
    const double a = 2 * kPi * k / p.legs;
    std::vector<Part> fork = {box("fork_" + n, at({-p.caster_trail / 2, 0, -p.caster_drop / 2 + 0.005}),
                                  Eigen::Vector3d(p.caster_trail + 0.025, 0.03, p.caster_drop), kDark)};
    urdf << writeLink("caster_" + n, fork);
    joints_xml.push_back(writeJoint("caster_swivel_" + n, "continuous", "base", "caster_" + n,
                                    at(Eigen::Vector3d(p.base_radius * std::cos(a), p.base_radius * std::sin(a), mount),
                                       rotZ(a + kPi)),
                                    Eigen::Vector3d::UnitZ()));
    chair.joints.push_back({"caster_swivel_" + n, JointRole::kCasterSwivel, p.caster_trail});
    // wheel: a sphere collides (smooth rolling on the floor), a twin-wheel
    // cylinder shows
    Part tread = cylinder("wheel_" + n, at(Eigen::Vector3d::Zero(), rotX(kPi / 2)), p.wheel_radius, 0.024, kDark);
    tread.collision = false;
    Part ball = tread;
    ball.name = "wheel_" + n + "_contact";
    ball.kind = Part::Kind::kSphere;
    ball.size = Eigen::Vector3d::Constant(p.wheel_radius);
    ball.pose = Eigen::Isometry3d::Identity();
    ball.visual = false;
    ball.collision = true;
    const std::vector<Part> wheel = {tread, ball};
    urdf << writeLink("wheel_" + n, wheel);
    joints_xml.push_back(writeJoint("caster_wheel_" + n, "continuous", "caster_" + n, "wheel_" + n,
                                    at({-p.caster_trail, 0, -p.caster_drop}), Eigen::Vector3d::UnitY()));
    chair.joints.push_back({"caster_wheel_" + n, JointRole::kWheel, p.wheel_radius});
    chair.wheel_links.push_back("wheel_" + n);
    chair.surface.push_back({"wheel_" + n, samplePartSurfaces(wheel)});
  }
}

// Where a reclining backrest is hinged, in the seat frame: under the
// cushion's rear.
Eigen::Vector3d calcBackrestHinge(const ChairParams& p) {
  return Eigen::Vector3d(p.seat_offset - p.seat_depth / 2 + 0.06, 0, 0.02);
}

// The backrest in the seat frame: a spine from under the cushion's rear,
// behind it and up to the panel(s), leaning back by backrest_angle.
std::vector<Part> makeBackrest(const ChairParams& p) {
  const Color& frame = p.frame_color;
  const double cushion_top = kMechanismHeight + p.seat_thickness;
  std::vector<Part> back;
  const Eigen::Vector3d hinge = calcBackrestHinge(p);
  const double rear = p.seat_offset - p.seat_depth / 2 - 0.03;
  const Eigen::Matrix3d lean = rotY(-p.backrest_angle);
  const Eigen::Vector3d panel_bottom(rear - 0.01, 0, cushion_top + p.backrest_gap);
  const Eigen::Vector3d up = lean * Eigen::Vector3d::UnitZ();
  back.push_back(beam("spine_low", hinge, Eigen::Vector3d(rear, 0, 0.02), 0.06, 0.025, frame));
  back.push_back(beam("spine_up", Eigen::Vector3d(rear, 0, 0.02), panel_bottom + 0.12 * up, 0.06, 0.025, frame));
  const double w = p.backrest_width, h = p.backrest_height, t = p.backrest_thickness;
  auto panel = [&](const std::string& name, double z0, double z1, double width, const Eigen::Vector3d& side_offset,
                   const Eigen::Matrix3d& turn) {
    back.push_back(box(name, at(panel_bottom + lean * (side_offset + Eigen::Vector3d(0, 0, (z0 + z1) / 2)), lean * turn),
                       Eigen::Vector3d(t, width, z1 - z0), p.seat_color));
  };
  switch (p.backrest) {
    case BackrestShape::kRectangular:
      panel("backrest", 0, h, w, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
      break;
    case BackrestShape::kRounded:  // a narrower top on a wide lower panel
      panel("backrest", 0, 0.7 * h, w, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
      panel("backrest_top", 0.7 * h, h, 0.75 * w, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
      break;
    case BackrestShape::kHeadrest: {  // a headrest on two posts above the panel
      panel("backrest", 0, h, w, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
      for (const double s : {-1.0, 1.0})
        back.push_back(box(s < 0 ? "headrest_post_0" : "headrest_post_1",
                           at(panel_bottom + lean * Eigen::Vector3d(0, s * 0.12, h + 0.03), lean),
                           Eigen::Vector3d(0.015, 0.015, 0.08), kMetal));
      back.push_back(box("headrest", at(panel_bottom + lean * Eigen::Vector3d(0.01, 0, h + 0.12), lean),
                         Eigen::Vector3d(1.2 * t, 0.6 * w, 0.14), p.seat_color));
      break;
    }
    case BackrestShape::kCurved: {  // a centre panel and two wings turned forward
      const double beta = 0.45, w0 = 0.25 * w, w1 = 0.15 * w;
      panel("backrest", 0, h, 2 * w0, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
      panel("backrest_wing_0", 0, h, 2 * w1, Eigen::Vector3d(std::sin(beta) * w1, w0 + std::cos(beta) * w1, 0),
            rotZ(-beta));
      panel("backrest_wing_1", 0, h, 2 * w1, Eigen::Vector3d(std::sin(beta) * w1, -w0 - std::cos(beta) * w1, 0),
            rotZ(beta));
      break;
    }
  }
  return back;
}

// The armrests, on brackets under the cushion: fixed parts join the seat;
// a height-adjustable arm is a link of its own (`arm_links`, its frame at
// `arm_origins` in the seat frame: the sleeve's top).
void addArmrests(const ChairParams& p, std::vector<Part>& seat, std::vector<std::vector<Part>>& arm_links,
                 std::vector<Eigen::Vector3d>& arm_origins) {
  if (p.armrest == ArmrestType::kNone) return;
  const Color& frame = p.frame_color;
  const double cushion_top = kMechanismHeight + p.seat_thickness;
  const double xa = p.seat_offset - 0.02;
  const double pad_top = cushion_top + p.armrest_height;
  for (const double s : {-1.0, 1.0}) {
    const std::string side = s < 0 ? "right" : "left";
    const double ya = s * (p.seat_width / 2 + 0.035);
    auto bracket = [&](double x) {
      seat.push_back(beam("armrest_bracket_" + side + (x == xa ? "" : "_rear"), Eigen::Vector3d(x, s * 0.08, 0.02),
                          Eigen::Vector3d(x, ya + s * 0.0125, 0.02), 0.05, 0.02, frame));
    };
    switch (p.armrest) {
      case ArmrestType::kFixedT:
        bracket(xa);
        seat.push_back(box("armrest_post_" + side, at({xa, ya, (0.01 + pad_top - 0.03) / 2}),
                           Eigen::Vector3d(0.05, 0.025, pad_top - 0.03 - 0.01), frame));
        seat.push_back(box("armrest_pad_" + side, at({xa + 0.03, ya, pad_top - 0.015}), Eigen::Vector3d(0.26, 0.075, 0.03),
                           kDark));
        break;
      case ArmrestType::kLoop: {
        const double xf = p.seat_offset + p.seat_depth / 2 - 0.07, xr = p.seat_offset - p.seat_depth / 2 + 0.07;
        bracket(xf);
        bracket(xr);
        for (const double x : {xf, xr})
          seat.push_back(box("armrest_post_" + side + (x == xf ? "_front" : "_rear"),
                             at({x, ya, (0.01 + pad_top - 0.03) / 2}), Eigen::Vector3d(0.03, 0.025, pad_top - 0.03 - 0.01),
                             frame));
        seat.push_back(box("armrest_pad_" + side, at({(xf + xr) / 2, ya, pad_top - 0.015}),
                           Eigen::Vector3d(xf - xr + 0.05, 0.06, 0.03), kDark));
        break;
      }
      case ArmrestType::kAdjustableT: {
        bracket(xa);
        seat.push_back(box("armrest_sleeve_" + side, at({xa, ya, (0.01 + cushion_top) / 2}),
                           Eigen::Vector3d(0.05, 0.03, cushion_top - 0.01), frame));
        // the arm slides up to 8 cm out of the sleeve; its frame is the sleeve top
        const double above = p.armrest_height - 0.03;
        arm_links.push_back({box("armrest_post_" + side, at({0, 0, above / 2 - 0.02}), Eigen::Vector3d(0.035, 0.02, above + 0.04),
                                 kMetal),
                             box("armrest_pad_" + side, at({0.03, 0, above + 0.015}), Eigen::Vector3d(0.26, 0.075, 0.03), kDark)});
        arm_origins.emplace_back(xa, ya, cushion_top);
        break;
      }
      case ArmrestType::kNone: break;
    }
  }
}

// The chair's size facts and its one-line summary.
void describeChair(const ChairParams& p, ChairModel& chair) {
  chair.root_height = 0;
  chair.footprint_radius = p.base_radius + p.caster_trail + p.wheel_radius;
  const double headrest_top = p.backrest == BackrestShape::kHeadrest ? 0.19 : 0.0;
  chair.height = std::max(p.seat_height + p.backrest_gap + std::cos(p.backrest_angle) * p.backrest_height + headrest_top,
                          p.armrest == ArmrestType::kNone ? 0.0 : p.seat_height + p.armrest_height);
  std::ostringstream summary;
  summary << std::fixed << std::setprecision(2) << "seat " << p.seat_width << " x " << p.seat_depth << " m at "
          << p.seat_height << " m, base " << 2 * (p.base_radius + 0.02) << " m across, " << toString(p.backrest)
          << (p.reclining ? " reclining" : "") << " backrest, armrests " << toString(p.armrest) << ", "
          << chair.joints.size() << " joints";
  chair.summary = summary.str();
}

}  // namespace

// The links in URDF order: base, casters, seat (with a fixed backrest and
// the fixed armrest parts), a reclining backrest, adjustable armrests; then
// the joints.
ChairModel generateChair(const std::string& chair_id, const ChairParams& p) {
  if (p.legs < 3 || !(p.base_radius > p.hub_radius) || !(p.wheel_radius > 0) ||
      !(p.seat_height - p.seat_thickness - kMechanismHeight > p.hub_height + 0.05))
    throw Error("chair " + chair_id + ": inconsistent parameters (legs, radii, heights)", MB_INVALID_ARGUMENT);
  ChairModel chair;
  chair.id = chair_id;
  std::ostringstream urdf;
  urdf << "<?xml version=\"1.0\"?>\n<robot name=\"chair_" << chair_id << "\">\n";
  std::vector<std::string> joints_xml;

  const std::vector<Part> base = makeBase(p);
  urdf << writeLink("base", base);
  chair.surface.push_back({"base", samplePartSurfaces(base)});
  addCasters(p, chair, urdf, joints_xml);

  // seat (frame at the column top, on the swivel)
  const double cushion_top = kMechanismHeight + p.seat_thickness;
  std::vector<Part> seat;
  seat.push_back(box("mechanism", at({0, 0, kMechanismHeight / 2}), Eigen::Vector3d(0.2, 0.2, kMechanismHeight),
                     p.frame_color));
  seat.push_back(box("cushion", at({p.seat_offset, 0, kMechanismHeight + p.seat_thickness / 2}),
                     Eigen::Vector3d(p.seat_depth, p.seat_width, p.seat_thickness), p.seat_color));
  chair.seat_link = "seat";
  chair.seat_top = Eigen::Vector3d(p.seat_offset, 0, cushion_top);
  joints_xml.push_back(writeJoint("seat_swivel", "continuous", "base", "seat", at({0, 0, calcColumnTop(p)}),
                                  Eigen::Vector3d::UnitZ()));
  chair.joints.push_back({"seat_swivel", JointRole::kSeat});

  const std::vector<Part> back = makeBackrest(p);
  std::vector<std::vector<Part>> arm_links;  // adjustable: one link per side
  std::vector<Eigen::Vector3d> arm_origins;
  addArmrests(p, seat, arm_links, arm_origins);
  if (!p.reclining) seat.insert(seat.end(), back.begin(), back.end());
  urdf << writeLink("seat", seat);
  chair.surface.push_back({"seat", samplePartSurfaces(seat)});
  if (p.reclining) {
    const Eigen::Vector3d hinge = calcBackrestHinge(p);
    std::vector<Part> local = back;  // in the hinge's frame
    for (Part& part : local) part.pose = at(-hinge) * part.pose;
    urdf << writeLink("backrest", local);
    chair.surface.push_back({"backrest", samplePartSurfaces(local)});
    // +y turns the top forward: gravity holds the backrest on its lower
    // stop (q = 0, the rest posture); pushed forward it rises to upright
    joints_xml.push_back(writeJoint("backrest_recline", "revolute", "seat", "backrest", at(hinge),
                                    Eigen::Vector3d::UnitY(), 0.0, p.backrest_angle));
    chair.joints.push_back({"backrest_recline", JointRole::kBackrest});
  }
  for (std::size_t i = 0; i < arm_links.size(); ++i) {
    const std::string side = i == 0 ? "right" : "left";
    urdf << writeLink("armrest_" + side, arm_links[i]);
    chair.surface.push_back({"armrest_" + side, samplePartSurfaces(arm_links[i])});
    joints_xml.push_back(writeJoint("armrest_" + side + "_height", "prismatic", "seat", "armrest_" + side,
                                    at(arm_origins[i]), Eigen::Vector3d::UnitZ(), 0.0, 0.08));
    chair.joints.push_back({"armrest_" + side + "_height", JointRole::kArmrest});
  }
  for (const std::string& j : joints_xml) urdf << j;
  urdf << "</robot>\n";
  chair.urdf = urdf.str();
  describeChair(p, chair);
  return chair;
}

}  // namespace push_chair
