// PartNet-Mobility chairs over the SDK's PartNet reader
// (manibench/kit/partnet.hpp: folders, mobility.urdf, semantics, OBJ
// vertices, scaling). What this family adds is what a chair's parts are,
// from semantics.txt labels: the wheels ('wheel'; renamed wheel_0, wheel_1,
// ... in the URDF, as many as the chair has, so that the task's contact
// material `wheel_*` finds them), the seat ('seat'; its joint gets the seat's
// friction and damping), caster swivels (the parents of wheels). The chair
// stands with its lowest point on the ground.
#include "push_chair.hpp"

#include <manibench/kit/partnet.hpp>

#include <limits>
#include <set>
#include <sstream>

namespace push_chair {

namespace {

constexpr double kVoxel = 0.02;  // m: reward points, one per voxel of this size

bool hasLabel(const partnet::Semantic* s, const std::string& word) {
  return s != nullptr && s->label.find(word) != std::string::npos;
}

// One point per occupied kVoxel cube (the first seen), so that dense
// meshes do not slow the reward down.
std::vector<Eigen::Vector3d> thinPoints(const std::vector<Eigen::Vector3d>& points) {
  std::map<std::array<long, 3>, Eigen::Vector3d> cells;
  for (const Eigen::Vector3d& p : points)
    cells.emplace(std::array<long, 3>{long(std::floor(p.x() / kVoxel)), long(std::floor(p.y() / kVoxel)),
                                      long(std::floor(p.z() / kVoxel))},
                  p);
  std::vector<Eigen::Vector3d> out;
  for (const auto& [cell, p] : cells) out.push_back(p);
  return out;
}

// PartNet's office chairs have one or two wheels per caster (chair 179:
// 10 on 5) and 3 to 6 casters; ManiSkill v1's wheels all have friction 1.0
// (the task's `wheel_*`). The first wheel of each caster (the wheel's
// parent link) comes first, so that wheel_0.. name one wheel per caster in
// caster order, the casters' second wheels after them.
std::vector<std::string> orderWheels(const partnet::Object& object, const std::vector<std::string>& wheels) {
  std::vector<std::string> first, second;
  std::set<std::string> casters;
  for (const std::string& w : wheels) {
    const partnet::Joint* j = object.findParentJoint(w);
    const std::string caster = j == nullptr ? w : j->parent;
    (casters.insert(caster).second ? first : second).push_back(w);
  }
  first.insert(first.end(), second.begin(), second.end());
  return first;
}

}  // namespace

ChairModel loadPartNetChair(const std::string& folder, const std::string& id, double scale) {
  const partnet::Object object = partnet::loadObject(folder, id, scale);
  const std::string where = "PushChair: PartNet chair " + object.dir;
  const std::map<std::string, Eigen::Isometry3d> pose = object.calcLinkPoses();

  std::vector<std::string> wheels;
  const partnet::Link* seat = nullptr;
  for (const partnet::Link& link : object.links) {
    const partnet::Semantic* s = object.findSemantic(link.name);
    if (hasLabel(s, "wheel")) wheels.push_back(link.name);
    if (seat == nullptr && hasLabel(s, "seat")) seat = &link;
  }
  wheels = orderWheels(object, wheels);
  if (seat == nullptr) throw Error(where + ": semantics.txt labels no link 'seat'", MB_INVALID_ARGUMENT);

  ChairModel chair;
  chair.id = id;
  chair.base_dir = object.dir;
  chair.root_link = object.getRoot().name;
  chair.seat_link = seat->name;
  // Wheels take the names the task's materials use.
  std::map<std::string, std::string> rename;
  for (std::size_t k = 0; k < wheels.size(); ++k) rename[wheels[k]] = "wheel_" + std::to_string(k);
  for (std::size_t k = 0; k < wheels.size(); ++k) chair.wheel_links.push_back("wheel_" + std::to_string(k));
  // A link already named wheel_k that is not the k-th wheel would be
  // renamed onto another's name, or get the wheels' friction.
  for (const partnet::Link& link : object.links)
    if (link.name.rfind("wheel_", 0) == 0 && rename.count(link.name) == 0)
      throw Error(where + ": link '" + link.name + "' is not labelled a wheel but has the name PushChair gives wheels",
                  MB_INVALID_ARGUMENT);
  chair.urdf = partnet::renameLinks(object.urdf, rename);
  auto renamed = [&rename](const std::string& link) {
    const auto it = rename.find(link);
    return it == rename.end() ? link : it->second;
  };

  // Roles of the movable joints, from what they carry; the casters'
  // levers from the wheels' visual bounds (radius: half their height;
  // trail: their centre's horizontal distance from the swivel axis).
  auto wheelBounds = [&](const std::string& w) {
    partnet::Bounds b;
    for (const partnet::Shape& v : object.findLink(w)->visuals)
      for (const Eigen::Vector3d& p : object.calcShapePoints(v)) b.add(pose.at(w) * p);
    return b;
  };
  for (const partnet::Joint& j : object.joints) {
    if (!j.isMovable()) continue;
    ChairJoint c;
    c.name = j.name;
    const partnet::Semantic* s = object.findSemantic(j.child);
    const auto carried = std::find_if(wheels.begin(), wheels.end(), [&](const std::string& w) {
      return object.findParentJoint(w)->parent == j.child;
    });
    if (j.child == seat->name) {
      c.role = JointRole::kSeat;
    } else if (hasLabel(s, "wheel")) {
      c.role = JointRole::kWheel;
      c.lever = wheelBounds(j.child).extent().z() / 2;
    } else if (carried != wheels.end()) {
      c.role = JointRole::kCasterSwivel;
      const Eigen::Isometry3d axis_frame = pose.at(j.child);
      const Eigen::Vector3d axis = axis_frame.linear() * j.axis;
      Eigen::Vector3d offset = wheelBounds(*carried).center() - axis_frame.translation();
      offset -= offset.dot(axis) * axis;
      c.lever = offset.norm();
    } else if (hasLabel(s, "back")) {
      c.role = JointRole::kBackrest;
    } else if (hasLabel(s, "arm")) {
      c.role = JointRole::kArmrest;
    }
    chair.joints.push_back(c);
  }

  // Placement, seat surface, footprint, reward points.
  const partnet::Bounds all = object.calcVisualBounds();
  if (all.empty()) throw Error(where + ": " + object.urdf_file + " has no visual geometry", MB_INVALID_ARGUMENT);
  chair.root_height = -all.lo.z();
  chair.height = all.hi.z() - all.lo.z();
  partnet::Bounds seat_bounds;
  for (const partnet::Shape& v : seat->visuals)
    for (const Eigen::Vector3d& p : object.calcShapePoints(v)) seat_bounds.add(pose.at(seat->name) * p);
  if (seat_bounds.empty()) throw Error(where + ": the seat link has no visual geometry", MB_INVALID_ARGUMENT);
  // The cushion's top: the seat link often carries the backrest too (it
  // turns on the same swivel), so not the top of its bounds but the top of
  // the highest of its parts (PartNet keeps parts in separate meshes) that
  // spans the swivel axis; the backrest stands behind it.
  const Eigen::Vector3d axis = pose.at(seat->name).translation();
  Eigen::Vector3d top(seat_bounds.center().x(), seat_bounds.center().y(), seat_bounds.hi.z());
  double highest = -std::numeric_limits<double>::infinity();
  for (const partnet::Shape& v : seat->visuals) {
    partnet::Bounds part;
    for (const Eigen::Vector3d& p : object.calcShapePoints(v)) part.add(pose.at(seat->name) * p);
    if (!part.empty() && part.lo.x() <= axis.x() && axis.x() <= part.hi.x() && part.lo.y() <= axis.y() &&
        axis.y() <= part.hi.y())
      highest = std::max(highest, part.hi.z());
  }
  if (std::isfinite(highest)) top = Eigen::Vector3d(axis.x(), axis.y(), highest);
  chair.seat_top = pose.at(seat->name).inverse() * top;
  chair.footprint_radius = 0;
  for (const std::string& w : wheels)
    for (const partnet::Shape& v : object.findLink(w)->visuals)
      for (const Eigen::Vector3d& p : object.calcShapePoints(v))
        chair.footprint_radius = std::max(chair.footprint_radius, (pose.at(w) * p).head<2>().norm());
  for (const partnet::Link& link : object.links) {
    std::vector<Eigen::Vector3d> points;
    for (const partnet::Shape& c : link.collisions) {
      const std::vector<Eigen::Vector3d>& p = object.calcShapePoints(c);
      points.insert(points.end(), p.begin(), p.end());
    }
    if (!points.empty()) chair.surface.push_back({renamed(link.name), thinPoints(points)});
  }
  std::ostringstream summary;
  summary << "PartNet-Mobility " << id << " (scale " << scale << "), " << chair.joints.size() << " joints, " << wheels.size() << " wheels, "
          << std::fixed << std::setprecision(2) << chair.height << " m tall";
  chair.summary = summary.str();
  return chair;
}

}  // namespace push_chair
