// Procedural cabinets: a carcass of boxes on a plinth, a grid of cells, each
// a door (hinged left or right), a drawer or an open shelf, with bar, knob
// or boxed handles. The parameters of a cabinet come from a hash of its id,
// so an id always names the same cabinet, on every platform (no
// std::*_distribution, whose output the standard leaves open).
//
// Splits (ids are plain numbers, grouped by kind and split):
//   door cabinets    train 1000-1041 (42)   test 1100-1109 (10)
//   drawer cabinets  train 2000-2024 (25)   test 2100-2109 (10)
// The test split holds what training never shows: boxed handles (every
// test cabinet has them on at least one front) and wider, taller carcasses
// (up to 1.25 x 1.25 m, train up to 1.0 x 1.1 m).
#include "open_cabinet.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace open_cabinet {

namespace {

const NumberedIds kDoorIds{{1000, 42}, {1100, 10}}, kDrawerIds{{2000, 25}, {2100, 10}};

struct IdInfo {
  TargetKind kind;
  bool test;
};

std::optional<IdInfo> classifyId(const std::string& id) {
  if (const std::optional<bool> test = kDoorIds.classify(id)) return IdInfo{TargetKind::kDoor, *test};
  if (const std::optional<bool> test = kDrawerIds.classify(id)) return IdInfo{TargetKind::kDrawer, *test};
  return std::nullopt;
}

std::array<double, 3> pickColor(Random& rng, std::array<double, 3> base, double spread) {
  std::array<double, 3> c{};
  for (int i = 0; i < 3; ++i) c[i] = std::clamp(base[i] + rng.uniform(-spread, spread), 0.0, 1.0);
  return c;
}

bool isDoor(CellKind k) { return k == CellKind::kDoorLeftHinge || k == CellKind::kDoorRightHinge; }

// ---- URDF writing -------------------------------------------------------------

struct Box {
  std::string name;
  Eigen::Vector3d center, size;
  std::array<double, 3> color;
  double density;
};

std::string fmt(double x) {
  std::ostringstream s;
  s << std::setprecision(9) << x;
  return s.str();
}
std::string vec(const Eigen::Vector3d& v) { return fmt(v.x()) + " " + fmt(v.y()) + " " + fmt(v.z()); }

// A link of boxes: visual and collision per box (same name), and the
// combined inertia about the centre of mass.
std::string writeLink(const std::string& name, const std::vector<Box>& boxes) {
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  for (const Box& b : boxes) {
    const double m = b.density * b.size.prod();
    mass += m;
    com += m * b.center;
  }
  com /= mass;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const Box& b : boxes) {
    const double m = b.density * b.size.prod();
    const Eigen::Vector3d s2 = b.size.cwiseProduct(b.size);
    Eigen::Matrix3d own = Eigen::Vector3d(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y()).asDiagonal();
    own *= m / 12.0;
    const Eigen::Vector3d d = b.center - com;
    inertia += own + m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  std::ostringstream x;
  x << "  <link name=\"" << name << "\">\n    <inertial><origin xyz=\"" << vec(com)
    << "\"/><mass value=\"" << fmt(mass) << "\"/><inertia ixx=\"" << fmt(inertia(0, 0))
    << "\" ixy=\"" << fmt(inertia(0, 1)) << "\" ixz=\"" << fmt(inertia(0, 2)) << "\" iyy=\""
    << fmt(inertia(1, 1)) << "\" iyz=\"" << fmt(inertia(1, 2)) << "\" izz=\"" << fmt(inertia(2, 2))
    << "\"/></inertial>\n";
  for (const Box& b : boxes) {
    const std::string geometry = "<origin xyz=\"" + vec(b.center) + "\"/><geometry><box size=\"" +
                                 vec(b.size) + "\"/></geometry>";
    x << "    <visual name=\"" << b.name << "\">" << geometry << "<material name=\"" << b.name
      << "_color\"><color rgba=\"" << fmt(b.color[0]) << " " << fmt(b.color[1]) << " "
      << fmt(b.color[2]) << " 1\"/></material></visual>\n";
    x << "    <collision name=\"" << b.name << "\">" << geometry << "</collision>\n";
  }
  x << "  </link>\n";
  return x.str();
}

// Handle boxes on a front whose outer face faces -x of the link frame and
// holds `at`; the grip's axis is along `along` (unit y or z), `standoff` in
// front of `at`. Fills the grasp frame of `target`.
void addHandle(const HandleParams& h, const std::string& link, const Eigen::Vector3d& at,
               const Eigen::Vector3d& along, const std::array<double, 3>& color, std::vector<Box>& boxes, TargetLink& target) {
  constexpr double kMetal = 2700;
  const Eigen::Vector3d out(-1, 0, 0);
  const Eigen::Vector3d grip = at + out * h.standoff;
  const Eigen::Vector3d across = along.cross(out).cwiseAbs();
  auto sized = [&](double x, double a, double c) -> Eigen::Vector3d {  // size along (out, along, across)
    return Eigen::Vector3d(x, 0, 0) + along * a + across * c;
  };
  const double post_length = h.standoff - h.thickness / 2;
  const Eigen::Vector3d post_center_x = at + out * (post_length / 2);
  switch (h.type) {
    case HandleType::kBar: {
      boxes.push_back({link + "_handle_grip", grip, sized(h.thickness, h.length, h.thickness), color, kMetal});
      for (int side : {-1, 1})
        boxes.push_back({link + "_handle_post" + (side < 0 ? "0" : "1"),
                         post_center_x + along * (side * (h.length / 2 - h.thickness)),
                         sized(post_length, 0.8 * h.thickness, 0.8 * h.thickness), color, kMetal});
      target.handle_half_length = h.length / 2;
      target.handle_size = Eigen::Vector3d(h.standoff + h.thickness / 2, h.thickness, h.length);
      break;
    }
    case HandleType::kBoxed: {  // a deep rectangular loop: square grip, full posts
      boxes.push_back({link + "_handle_grip", grip, sized(h.thickness, h.length, h.thickness), color, kMetal});
      for (int side : {-1, 1})
        boxes.push_back({link + "_handle_post" + (side < 0 ? "0" : "1"),
                         post_center_x + along * (side * (h.length / 2 + h.thickness / 2)),
                         sized(post_length + h.thickness, h.thickness, h.thickness), color, kMetal});
      target.handle_half_length = h.length / 2;
      target.handle_size = Eigen::Vector3d(h.standoff + h.thickness / 2, h.thickness, h.length + 2 * h.thickness);
      break;
    }
    case HandleType::kKnob: {  // head of size `length` on a thin stem
      boxes.push_back({link + "_handle_knob", grip, sized(h.length, h.length, h.length), color, kMetal});
      const double stem = h.standoff - h.length / 2;
      boxes.push_back({link + "_handle_stem", at + out * (stem / 2), sized(stem, 0.012, 0.012), color, kMetal});
      target.handle_half_length = h.length / 2;
      target.handle_size = Eigen::Vector3d(h.standoff + h.length / 2, h.length, h.length);
      break;
    }
  }
  target.handle_position = grip;
  target.handle_type = toString(h.type);
  // grasp frame: x out of the panel, z along the grip, y = z x x
  target.handle_rotation.col(0) = out;
  target.handle_rotation.col(2) = along;
  target.handle_rotation.col(1) = along.cross(out);
}

}  // namespace

std::string toString(HandleType type) {
  switch (type) {
    case HandleType::kBar: return "bar";
    case HandleType::kKnob: return "knob";
    case HandleType::kBoxed: return "boxed";
  }
  return "?";
}

std::vector<const TargetLink*> CabinetModel::getTargets(TargetKind kind) const {
  std::vector<const TargetLink*> out;
  for (const TargetLink& t : targets)
    if (t.kind == kind) out.push_back(&t);
  return out;
}

std::vector<std::string> CabinetModel::getRefused(TargetKind kind) const {
  std::vector<std::string> out;
  for (const auto& [k, why] : refused)
    if (k == kind) out.push_back(why);
  return out;
}

std::vector<std::string> listGeneratedCabinets(TargetKind kind, const std::string& split) {
  return (kind == TargetKind::kDoor ? kDoorIds : kDrawerIds).list(split);
}

CabinetParams getCabinetParams(const std::string& cabinet_id) {
  const std::optional<IdInfo> info = classifyId(cabinet_id);
  if (!info)
    throw Error("no generated cabinet '" + cabinet_id + "' (door cabinets " + kDoorIds.describe() +
                    "; drawer cabinets " + kDrawerIds.describe() + ")",
                MB_NOT_FOUND);
  Random rng(hashString("manibench.open_cabinet.v1:" + cabinet_id));
  CabinetParams p;
  const bool door = info->kind == TargetKind::kDoor;
  const bool test = info->test;
  // carcass
  p.width = test ? rng.uniform(0.7, 1.25) : rng.uniform(0.5, 1.0);
  p.height = test ? rng.uniform(0.7, 1.25) : rng.uniform(0.55, 1.1);
  p.depth = rng.uniform(0.38, 0.6);
  p.wall = rng.uniform(0.015, 0.03);
  // grid: door cells at most ~0.6 m wide, drawer cells 0.14-0.4 m tall
  p.cols = p.width > 0.65 ? 2 : 1;
  if (door) {
    p.rows = p.height > 0.85 ? rng.integer(1, 2) : 1;
  } else {
    const int most = std::max(1, int((p.height - 0.04) / 0.16));
    const int least = std::max(1, int(std::ceil((p.height - 0.04) / 0.4)));
    p.rows = rng.integer(least, std::min(most, 4));
  }
  const double cell_h = (p.height - 2 * p.wall - (p.rows - 1) * p.wall) / p.rows;
  for (int r = 0; r < p.rows; ++r)
    for (int c = 0; c < p.cols; ++c) {
      CellKind k;
      const CellKind door_kind =
          p.cols == 2 ? (c == 0 ? CellKind::kDoorRightHinge : CellKind::kDoorLeftHinge)
                      : (rng.chance(0.5) ? CellKind::kDoorLeftHinge : CellKind::kDoorRightHinge);
      const double other = rng.uniform(0, 1);
      if (door) {
        k = other < 0.8 ? door_kind : (other < 0.9 || cell_h > 0.45 ? CellKind::kShelf : CellKind::kDrawer);
      } else {
        k = other < 0.85 ? CellKind::kDrawer
                         : (cell_h >= 0.3 && other < 0.93 ? door_kind : CellKind::kShelf);
      }
      p.cells.push_back(k);
    }
  // at least one front of the task's kind
  const auto wanted = [door](CellKind k) { return door ? isDoor(k) : k == CellKind::kDrawer; };
  if (std::none_of(p.cells.begin(), p.cells.end(), wanted))
    p.cells[std::size_t(rng.integer(0, int(p.cells.size()) - 1))] =
        door ? (p.cols == 2 ? CellKind::kDoorLeftHinge : CellKind::kDoorRightHinge) : CellKind::kDrawer;
  if (p.cols == 2)  // keep double doors mirrored
    for (int r = 0; r < p.rows; ++r)
      for (int c = 0; c < 2; ++c) {
        CellKind& k = p.cells[std::size_t(r * 2 + c)];
        if (isDoor(k)) k = c == 0 ? CellKind::kDoorRightHinge : CellKind::kDoorLeftHinge;
      }
  for (std::size_t i = 0; i < p.cells.size(); ++i)
    p.door_limits.push_back(rng.uniform(90.0, 120.0) * kPi / 180.0);
  // handle: boxed only in the test split
  const double t = rng.uniform(0, 1);
  p.handle.type = test ? (t < 0.6 ? HandleType::kBoxed : (t < 0.8 ? HandleType::kBar : HandleType::kKnob))
                       : (t < 0.7 ? HandleType::kBar : HandleType::kKnob);
  switch (p.handle.type) {
    case HandleType::kBar:
      p.handle.length = rng.uniform(0.10, 0.22);
      p.handle.thickness = rng.uniform(0.012, 0.02);
      break;
    case HandleType::kBoxed:
      p.handle.length = rng.uniform(0.10, 0.18);
      p.handle.thickness = rng.uniform(0.022, 0.03);
      break;
    case HandleType::kKnob:
      p.handle.length = rng.uniform(0.028, 0.04);
      p.handle.thickness = 0.012;
      break;
  }
  p.handle.standoff = rng.uniform(0.045, 0.065);
  p.handle.offset = rng.uniform(0.05, 0.08);
  p.body_color = pickColor(rng, {0.55, 0.42, 0.3}, 0.25);
  p.front_color = pickColor(rng, {0.7, 0.65, 0.55}, 0.3);
  p.handle_color = pickColor(rng, {0.3, 0.3, 0.32}, 0.2);
  return p;
}

CabinetModel generateCabinet(const std::string& cabinet_id) {
  const CabinetParams p = getCabinetParams(cabinet_id);
  constexpr double kWood = 600, kFront = 0.02, kGap = 0.003, kPlinth = 0.08;
  const double W = p.width, H = p.height, D = p.depth, t = p.wall;
  const double z0 = kPlinth;  // carcass bottom
  CabinetModel model;
  model.id = cabinet_id;
  model.lower = Eigen::Vector3d(-D / 2 - kFront, -W / 2, 0);
  model.upper = Eigen::Vector3d(D / 2, W / 2, z0 + H);

  std::vector<Box> carcass;
  const auto body = p.body_color;
  carcass.push_back({"plinth", {0.02, 0, kPlinth / 2}, {D - 0.04, W - 0.04, kPlinth}, body, kWood});
  carcass.push_back({"bottom", {0, 0, z0 + t / 2}, {D, W, t}, body, kWood});
  carcass.push_back({"top", {0, 0, z0 + H - t / 2}, {D, W, t}, body, kWood});
  for (int s : {-1, 1})
    carcass.push_back({s < 0 ? "side_right" : "side_left", {0, s * (W / 2 - t / 2), z0 + H / 2}, {D, t, H}, body, kWood});
  carcass.push_back({"back", {D / 2 - t / 2, 0, z0 + H / 2}, {t, W - 2 * t, H - 2 * t}, body, kWood});
  const double cell_w = (W - 2 * t - (p.cols - 1) * t) / p.cols;
  const double cell_h = (H - 2 * t - (p.rows - 1) * t) / p.rows;
  for (int r = 1; r < p.rows; ++r)
    carcass.push_back({"shelf_" + std::to_string(r), {t / 2, 0, z0 + t + r * (cell_h + t) - t / 2}, {D - t, W - 2 * t, t}, body, kWood});
  if (p.cols == 2)
    carcass.push_back({"divider", {t / 2, 0, z0 + H / 2}, {D - t, t, H - 2 * t}, body, kWood});

  std::ostringstream links, joints;
  int n_doors = 0, n_drawers = 0;
  for (int r = 0; r < p.rows; ++r)
    for (int c = 0; c < p.cols; ++c) {
      const std::size_t cell = std::size_t(r * p.cols + c);
      const CellKind kind = p.cells[cell];
      if (kind == CellKind::kShelf) continue;
      const std::string link = "link_" + std::to_string(model.targets.size());
      const double cy = -W / 2 + t + c * (cell_w + t) + cell_w / 2;
      const double cz = z0 + t + r * (cell_h + t) + cell_h / 2;
      // overlay front: covers the cell and half of each surrounding wall
      const double pw = cell_w + t - 2 * kGap, ph = cell_h + t - 2 * kGap;
      std::vector<Box> boxes;
      TargetLink target;
      target.link = link;
      target.joint = "joint_" + std::to_string(model.targets.size());
      std::ostringstream joint;
      if (isDoor(kind)) {
        // hinge on the front's outer face, at its -y edge (right hinge, seen
        // from the front) or its +y edge; the door extends from it along +-y
        const double side = kind == CellKind::kDoorRightHinge ? 1.0 : -1.0;
        const Eigen::Vector3d hinge(-D / 2 - kFront, cy - side * pw / 2, cz);
        boxes.push_back({link + "_panel", {kFront / 2, side * pw / 2, 0}, {kFront, pw, ph}, p.front_color, kWood});
        HandleParams h = p.handle;
        h.length = std::min(h.length, 0.5 * ph);
        const double reach_z = std::clamp(0.0, 0.5 - cz, 1.1 - cz);  // keep it within the arm's reach
        const double grip_z = std::clamp(reach_z, -ph / 2 + h.length / 2 + 0.02, ph / 2 - h.length / 2 - 0.02);
        addHandle(h, link, {0, side * (pw - h.offset), grip_z}, Eigen::Vector3d::UnitZ(), p.handle_color,
                  boxes, target);
        target.kind = TargetKind::kDoor;
        target.axis = Eigen::Vector3d(0, 0, side);
        joint << "  <joint name=\"" << target.joint << "\" type=\"revolute\"><parent link=\"base\"/><child link=\""
              << link << "\"/><origin xyz=\"" << vec(hinge) << "\"/><axis xyz=\"0 0 " << fmt(side)
              << "\"/><limit lower=\"0\" upper=\"" << fmt(p.door_limits[cell])
              << "\" effort=\"100\" velocity=\"3\"/><dynamics damping=\"10\" friction=\"0.1\"/></joint>\n";
        ++n_doors;
      } else {
        // drawer: frame at the middle of the front's back face; it slides
        // out along -x up to most of its depth
        const double tray = D - t - 0.03, wall = 0.01, tray_h = std::max(0.6 * cell_h, 0.05);
        boxes.push_back({link + "_front", {-kFront / 2, 0, 0}, {kFront, pw, ph}, p.front_color, kWood});
        boxes.push_back({link + "_tray_bottom", {tray / 2, 0, -cell_h / 2 + wall}, {tray, cell_w - 0.01, wall}, p.body_color, kWood});
        for (int s : {-1, 1})
          boxes.push_back({link + (s < 0 ? "_tray_right" : "_tray_left"), {tray / 2, s * (cell_w / 2 - 0.005 - wall / 2), -cell_h / 2 + tray_h / 2 + wall / 2}, {tray, wall, tray_h}, p.body_color, kWood});
        boxes.push_back({link + "_tray_back", {tray - wall / 2, 0, -cell_h / 2 + tray_h / 2 + wall / 2}, {wall, cell_w - 0.01 - 2 * wall, tray_h}, p.body_color, kWood});
        HandleParams h = p.handle;
        h.length = std::min(h.length, 0.7 * pw);
        addHandle(h, link, {-kFront, 0, 0}, Eigen::Vector3d::UnitY(), p.handle_color, boxes, target);
        target.kind = TargetKind::kDrawer;
        target.axis = Eigen::Vector3d(-1, 0, 0);
        const double travel = tray * (0.75 + 0.15 * double(hashString(link + cabinet_id) % 1000) / 1000.0);
        joint << "  <joint name=\"" << target.joint << "\" type=\"prismatic\"><parent link=\"base\"/><child link=\""
              << link << "\"/><origin xyz=\"" << vec({-D / 2, cy, cz}) << "\"/><axis xyz=\"-1 0 0\"/><limit lower=\"0\" upper=\""
              << fmt(travel) << "\" effort=\"100\" velocity=\"1\"/><dynamics damping=\"10\" friction=\"0.1\"/></joint>\n";
        ++n_drawers;
      }
      links << writeLink(link, boxes);
      joints << joint.str();
      model.targets.push_back(target);
    }
  std::ostringstream urdf;
  urdf << "<?xml version=\"1.0\"?>\n<!-- manibench procedural cabinet " << cabinet_id << " -->\n<robot name=\"cabinet_"
       << cabinet_id << "\">\n"
       << writeLink("base", carcass) << links.str() << joints.str() << "</robot>\n";
  model.urdf = urdf.str();
  std::ostringstream summary;
  summary << std::fixed << std::setprecision(2) << W << "x" << D << "x" << H + kPlinth << " m, " << p.rows << "x"
          << p.cols << " cells, " << n_doors << " doors, " << n_drawers << " drawers, " << toString(p.handle.type)
          << " handles";
  model.summary = summary.str();
  return model;
}

std::pair<std::string, std::string> splitObjectId(const std::string& object_id) {
  const std::size_t at = object_id.rfind("_link_");
  if (at == std::string::npos || at == 0 || at + 6 >= object_id.size())
    throw Error("object id '" + object_id + "' is not of the form <cabinet>_link_<k> (see `manibench objects`)",
                MB_NOT_FOUND);
  return {object_id.substr(0, at), object_id.substr(at + 1)};
}

}  // namespace open_cabinet
