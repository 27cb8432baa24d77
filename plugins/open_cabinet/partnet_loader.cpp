// PartNet-Mobility cabinets (asset-facts.md) over the SDK's PartNet reader
// (manibench/kit/partnet.hpp: folders, mobility.urdf, OBJ vertices). What
// this family adds is what a handle and a target are: handles are the
// visuals whose name (the kit names unnamed ones after their mesh's part
// in result.json) contains "handle"; a target is a link carrying one
// whose parent joint is revolute/continuous (door) or prismatic (drawer).
// The grasp frame comes from the handle meshes' bounding box in the link
// frame: x out of the cabinet front (which faces -x once the base joint
// turns Y-up into Z-up), z along the box's longer side across that.
#include "open_cabinet.hpp"

#include <manibench/kit/partnet.hpp>

#include <algorithm>
#include <iomanip>
#include <limits>
#include <sstream>

namespace open_cabinet {

namespace {

// Above the ground by half the thickness the host gives flat collision
// meshes (core/scene/contact/convex_hull.hpp, kMinHullThickness): PartNet's
// lowest faces (a door's bottom edge, a plinth) are often planar, and as
// 1 cm solids about their plane they would reach 5 mm into the ground. A
// door resting on the ground with friction 1 did not open (41083's
// second door stayed at 0.02 rad under the expert's pull).
constexpr double kGroundClearance = 0.005;

}  // namespace

CabinetModel loadPartNetCabinet(const std::string& folder, const std::string& id, const ObjectFacts& facts) {
  // The scale rule needs the unscaled size first (the visual bounds'
  // diagonal with every joint at 0, the rule's measure): every length of
  // the file scales alike, so the object is read again at its scale.
  double diagonal = 0;
  if (facts.needsDiagonal(id)) diagonal = partnet::loadObject(folder, id).calcVisualBounds().extent().norm();
  const double scale = facts.calcScale(id, diagonal);
  const partnet::Object object = partnet::loadObject(folder, id, scale);
  // Closed: each joint at its lower limit, as the task's reset sets them.
  const std::map<std::string, double> closed = object.getLowerLimits();
  const std::map<std::string, Eigen::Isometry3d> pose = object.calcLinkPoses(closed);

  CabinetModel cabinet;
  cabinet.id = id;
  cabinet.urdf = object.urdf;
  cabinet.base_dir = object.dir;
  int doors = 0, drawers = 0;
  for (const partnet::Link& link : object.links) {
    partnet::Bounds handle;
    for (const partnet::Shape& v : link.visuals)
      if (v.name.find("handle") != std::string::npos)
        for (const Eigen::Vector3d& p : object.calcShapePoints(v)) handle.add(p);
    const partnet::Joint* joint = object.findParentJoint(link.name);
    if (handle.empty() || joint == nullptr) continue;
    TargetLink t;
    t.link = link.name;
    t.joint = joint->name;
    const bool revolute = joint->type == partnet::JointType::kRevolute || joint->type == partnet::JointType::kContinuous;
    const bool prismatic = joint->type == partnet::JointType::kPrismatic;
    // semantics.txt says what the part is (a handled lid or a sliding door
    // is no target); without an entry for the link, its joint decides.
    if (const partnet::Semantic* semantic = object.findSemantic(link.name)) {
      const bool door = semantic->label.find("door") != std::string::npos;
      const bool drawer = semantic->label.find("drawer") != std::string::npos;
      if (door && revolute)
        t.kind = TargetKind::kDoor;
      else if (drawer && prismatic)
        t.kind = TargetKind::kDrawer;
      else
        continue;
    } else if (revolute) {
      t.kind = TargetKind::kDoor;
    } else if (prismatic) {
      t.kind = TargetKind::kDrawer;
    } else {
      continue;
    }
    t.axis = joint->axis;
    // Outward (-x of the cabinet) in the link frame; the grip runs along
    // the longer of the box's two other sides.
    const Eigen::Matrix3d r = pose.at(link.name).linear();
    const Eigen::Vector3d out = r.transpose() * Eigen::Vector3d(-1, 0, 0);
    const Eigen::Vector3d extent = handle.extent();
    Eigen::Index normal_axis;
    out.cwiseAbs().maxCoeff(&normal_axis);
    Eigen::Index grip_axis = -1;
    for (Eigen::Index a = 0; a < 3; ++a)
      if (a != normal_axis && (grip_axis < 0 || extent[a] > extent[grip_axis])) grip_axis = a;
    Eigen::Vector3d along = Eigen::Vector3d::Zero();
    along[grip_axis] = 1;
    const Eigen::Vector3d x = (out - out.dot(along) * along).normalized();
    t.handle_rotation.col(0) = x;
    t.handle_rotation.col(2) = along;
    t.handle_rotation.col(1) = along.cross(x);
    t.handle_position = handle.center();
    t.handle_half_length = extent[grip_axis] / 2;
    {  // the handle's points in its grasp frame (rotation only: extents)
      partnet::Bounds local;
      for (const partnet::Shape& v : link.visuals)
        if (v.name.find("handle") != std::string::npos)
          for (const Eigen::Vector3d& p : object.calcShapePoints(v)) local.add(t.handle_rotation.transpose() * p);
      t.handle_size = local.extent();
    }
    t.handle_type = "mesh";
    (t.kind == TargetKind::kDoor ? doors : drawers)++;
    cabinet.targets.push_back(t);
  }
  const partnet::Bounds all = object.calcVisualBounds(closed);
  if (all.empty())
    throw Error("PartNet: " + object.urdf_file + " has no visual geometry", MB_INVALID_ARGUMENT);
  // ManiSkill v1 lifts the cabinet, joints at their lower limits (as the
  // task's reset sets them), so that its collision box touches the ground
  // (here: the meshes' box, kGroundClearance above it); the visual and
  // collision meshes are the same files.
  cabinet.placement = Eigen::Vector3d(0, 0, -all.lo.z() + kGroundClearance);
  cabinet.lower = all.lo + cabinet.placement;
  cabinet.upper = all.hi + cabinet.placement;
  cabinet.scale = scale;
  // v1's own ids had this many targets of each kind (their object facts'
  // doors and drawers): its link_k is the k-th such link in link order, as
  // ours, so the first ones are kept.
  const double keep_doors = facts.findNumber(id, "doors"), keep_drawers = facts.findNumber(id, "drawers");
  if (keep_doors >= 0 || keep_drawers >= 0) {
    std::vector<TargetLink> kept;
    int kept_doors = 0, kept_drawers = 0;
    for (const TargetLink& t : cabinet.targets) {
      int& count = t.kind == TargetKind::kDoor ? kept_doors : kept_drawers;
      const double keep = t.kind == TargetKind::kDoor ? keep_doors : keep_drawers;
      if (keep < 0 || count < keep) {
        ++count;
        kept.push_back(t);
      }
    }
    cabinet.targets = std::move(kept);
    doors = kept_doors;
    drawers = kept_drawers;
  }
  // A target that, opened to B.4's threshold, would reach into the ground
  // cannot be opened where the task stands the cabinet: a flap hinged at
  // its bottom edge whose front (panel, handle) lies in front of the hinge
  // turns below it, and the ground's contact holds it part-way (docs/
  // partnet.md: two flaps of the survey stopped at 40-55 %, under any
  // pull). Refused with the depth, so that a survey counts only doors a
  // robot can open.
  std::vector<TargetLink> reachable;
  for (const TargetLink& t : cabinet.targets) {
    const partnet::Joint* joint = object.findJoint(t.joint);
    std::map<std::string, double> q = closed;
    if (joint->limited) q[t.joint] = joint->lower + kOpenFraction * (joint->upper - joint->lower);
    const Eigen::Isometry3d link_pose = object.calcLinkPoses(q).at(t.link);
    double lowest = std::numeric_limits<double>::infinity();
    for (const partnet::Link& link : object.links)
      if (link.name == t.link)
        for (const partnet::Shape& v : link.visuals)
          for (const Eigen::Vector3d& p : object.calcShapePoints(v)) lowest = std::min(lowest, (link_pose * p).z());
    const double depth = -(lowest + cabinet.placement.z());
    if (depth > 0) {
      std::ostringstream why;
      why << t.link << ": it reaches " << std::fixed << std::setprecision(1) << 100 * depth
          << " cm into the ground before it opens " << int(100 * kOpenFraction) << " %";
      cabinet.refused.emplace_back(t.kind, why.str());
      (t.kind == TargetKind::kDoor ? doors : drawers)--;
    } else {
      reachable.push_back(t);
    }
  }
  cabinet.targets = std::move(reachable);
  std::ostringstream summary;
  summary << "PartNet-Mobility " << id << " at scale " << scale << (facts.hasOwnScale(id) ? " (its object facts')" : "") << ", " << doors
          << " doors, " << drawers << " drawers with handles";
  for (const auto& [kind, why] : cabinet.refused) summary << "; refused: " << why;
  cabinet.summary = summary.str();
  return cabinet;
}

}  // namespace open_cabinet
