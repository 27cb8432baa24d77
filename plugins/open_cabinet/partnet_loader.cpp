// PartNet-Mobility cabinets (asset-facts.md): <folder>/<id>/mobility.urdf,
// semantics.txt, textured_objs/*.obj. Handles are the visuals whose name
// contains "handle"; a target is a link carrying one whose parent joint is
// revolute/continuous (door) or prismatic (drawer). The grasp frame comes
// from the handle meshes' bounding box in the link frame: x out of the
// cabinet front (which faces -x once the base joint turns Y-up into Z-up),
// z along the box's longer side across that.
#include "open_cabinet.hpp"

#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>

namespace open_cabinet {

using manibench::sdk::Error;
namespace fs = std::filesystem;

namespace {

Eigen::Isometry3d toIsometry(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

// The vertices of an OBJ file ("v x y z" lines), scaled.
std::vector<Eigen::Vector3d> readObjVertices(const fs::path& path, const Eigen::Vector3d& scale) {
  std::ifstream in(path);
  if (!in) throw Error("PartNet: cannot read mesh " + path.string(), MB_NOT_FOUND);
  std::vector<Eigen::Vector3d> out;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.size() < 2 || line[0] != 'v' || line[1] != ' ') continue;
    std::istringstream s(line.substr(2));
    Eigen::Vector3d v;
    if (!(s >> v.x() >> v.y() >> v.z()))
      throw Error("PartNet: " + path.string() + ":" + std::to_string(number) + ": bad vertex line", MB_INVALID_ARGUMENT);
    out.push_back(v.cwiseProduct(scale));
  }
  return out;
}

struct Bounds {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  void add(const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  bool empty() const { return !(lo.x() <= hi.x()); }
};

// Points of a visual in its link's frame (mesh vertices or box corners).
std::vector<Eigen::Vector3d> visualPoints(const urdf::Visual& v, const fs::path& dir) {
  std::vector<Eigen::Vector3d> local;
  if (!v.geometry) return local;
  if (v.geometry->type == urdf::Geometry::MESH) {
    const auto& m = static_cast<const urdf::Mesh&>(*v.geometry);
    local = readObjVertices(dir / m.filename, Eigen::Vector3d(m.scale.x, m.scale.y, m.scale.z));
  } else if (v.geometry->type == urdf::Geometry::BOX) {
    const auto& b = static_cast<const urdf::Box&>(*v.geometry);
    for (int i = 0; i < 8; ++i)
      local.emplace_back((i & 1 ? 0.5 : -0.5) * b.dim.x, (i & 2 ? 0.5 : -0.5) * b.dim.y, (i & 4 ? 0.5 : -0.5) * b.dim.z);
  }
  const Eigen::Isometry3d t = toIsometry(v.origin);
  for (Eigen::Vector3d& p : local) p = t * p;
  return local;
}

// PartNet-Mobility's <limit> tags give lower/upper only; URDF (urdfdom)
// wants effort and velocity too. Adds what is missing.
std::string completeJointLimits(const std::string& urdf) {
  static const std::regex limit_tag(R"(<limit\b[^>]*>)");
  std::string out;
  std::size_t last = 0;
  for (auto it = std::sregex_iterator(urdf.begin(), urdf.end(), limit_tag); it != std::sregex_iterator(); ++it) {
    std::string tag = it->str();
    const std::size_t close = tag.rfind(tag.size() >= 2 && tag[tag.size() - 2] == '/' ? "/>" : ">");
    std::string extra;
    if (tag.find("effort") == std::string::npos) extra += " effort=\"100\"";
    if (tag.find("velocity") == std::string::npos) extra += " velocity=\"1\"";
    tag.insert(close, extra);
    out += urdf.substr(last, std::size_t(it->position()) - last) + tag;
    last = std::size_t(it->position() + it->length());
  }
  return out + urdf.substr(last);
}

}  // namespace

std::vector<std::string> listPartNetCabinets(const std::string& folder) {
  std::vector<std::string> ids;
  for (const fs::directory_entry& e : fs::directory_iterator(folder))
    if (e.is_directory() && fs::exists(e.path() / "mobility.urdf")) ids.push_back(e.path().filename().string());
  std::sort(ids.begin(), ids.end());
  return ids;
}

CabinetModel loadPartNetCabinet(const std::string& folder, const std::string& id) {
  const fs::path dir = fs::path(folder) / id;
  const fs::path urdf_path = dir / "mobility.urdf";
  std::ifstream in(urdf_path);
  if (!in) throw Error("PartNet: no cabinet '" + id + "' (" + urdf_path.string() + " is missing)", MB_NOT_FOUND);
  std::stringstream text;
  text << in.rdbuf();
  const std::string urdf_text = completeJointLimits(text.str());
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(urdf_text);
  if (!model) throw Error("PartNet: " + urdf_path.string() + " is not a valid URDF", MB_INVALID_ARGUMENT);

  // Link poses in the cabinet frame with every joint at zero.
  std::map<std::string, Eigen::Isometry3d> world;
  std::vector<urdf::LinkConstSharedPtr> order{model->getRoot()};
  world[model->getRoot()->name] = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < order.size(); ++i)
    for (const urdf::LinkSharedPtr& child : order[i]->child_links) {
      world[child->name] = world[order[i]->name] * toIsometry(child->parent_joint->parent_to_joint_origin_transform);
      order.push_back(child);
    }

  CabinetModel cabinet;
  cabinet.id = id;
  cabinet.urdf = urdf_text;
  cabinet.base_dir = dir.string();
  Bounds all;
  int doors = 0, drawers = 0;
  for (const urdf::LinkConstSharedPtr& link : order) {
    Bounds handle;
    for (const urdf::VisualSharedPtr& v : link->visual_array) {
      const std::vector<Eigen::Vector3d> points = visualPoints(*v, dir);
      const bool is_handle = v->name.find("handle") != std::string::npos;
      for (const Eigen::Vector3d& p : points) {
        all.add(world[link->name] * p);
        if (is_handle) handle.add(p);
      }
    }
    const urdf::JointConstSharedPtr joint = link->parent_joint;
    if (handle.empty() || !joint) continue;
    TargetLink t;
    t.link = link->name;
    t.joint = joint->name;
    if (joint->type == urdf::Joint::REVOLUTE || joint->type == urdf::Joint::CONTINUOUS)
      t.kind = TargetKind::kDoor;
    else if (joint->type == urdf::Joint::PRISMATIC)
      t.kind = TargetKind::kDrawer;
    else
      continue;
    t.axis = Eigen::Vector3d(joint->axis.x, joint->axis.y, joint->axis.z).normalized();
    // Outward (-x of the cabinet) in the link frame; the grip runs along
    // the longer of the box's two other sides.
    const Eigen::Matrix3d r = world[link->name].linear();
    const Eigen::Vector3d out = r.transpose() * Eigen::Vector3d(-1, 0, 0);
    const Eigen::Vector3d extent = handle.hi - handle.lo;
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
    t.handle_position = (handle.lo + handle.hi) / 2;
    t.handle_half_length = extent[grip_axis] / 2;
    t.handle_type = "mesh";
    (t.kind == TargetKind::kDoor ? doors : drawers)++;
    cabinet.targets.push_back(t);
  }
  if (all.empty()) throw Error("PartNet: " + urdf_path.string() + " has no visual geometry", MB_INVALID_ARGUMENT);
  cabinet.placement = Eigen::Vector3d(0, 0, -all.lo.z());  // bottom on the ground
  cabinet.lower = all.lo + cabinet.placement;
  cabinet.upper = all.hi + cabinet.placement;
  std::ostringstream summary;
  summary << "PartNet-Mobility " << id << ", " << doors << " doors, " << drawers << " drawers with handles";
  cabinet.summary = summary.str();
  return cabinet;
}

}  // namespace open_cabinet
