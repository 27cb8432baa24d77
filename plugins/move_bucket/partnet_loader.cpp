// PartNet-Mobility buckets (ManiSkill v1's 29 + 10) over the SDK's PartNet
// reader (manibench/kit/partnet.hpp: folders, splits, mobility.urdf, OBJ
// vertices). What this family adds is what a bucket is:
//   - the body: every link rigidly attached to the root (through fixed
//     joints); the bail: the revolute or continuous joint whose child
//     semantics.txt labels a handle (else the first such joint);
//   - the bucket frame the task and the expert work in (BucketModel): the
//     body's bounding box, bottom centre as origin, z up. A new root link
//     carries that frame, fixed to PartNet's root, so that the frame is a
//     link of the articulation like a generated bucket's;
//   - the rim and the floor measured on the body's mesh vertices (PartNet
//     meshes are not closed: no volumes, no rays); the reward's surface
//     points sampled on its triangles.
// Collision: ManiSkill's buckets came as hand-made convex pieces
// (supplement B.9); a PartNet body is one concave mesh whose hull would
// fill the bucket, so the body's collision meshes are decomposed into
// convex pieces (kit/convex_decomposition.hpp, cached on disk), each a
// <collision> the host takes as a hull; the handle keeps its meshes.
// Links without <inertial> get mass from those hulls at the default
// density (1000, the facts'), so the model's mass is left at 0.
#include "move_bucket.hpp"

#include <manibench/kit/convex_decomposition.hpp>
#include <manibench/kit/partnet.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <set>
#include <sstream>

namespace move_bucket {

namespace {

constexpr const char* kFrameLink = "move_bucket_frame";

// The links held to the root by fixed joints only, the root included.
std::set<std::string> findBodyLinks(const partnet::Object& object) {
  std::set<std::string> body = {object.getRoot().name};
  for (const partnet::Link& link : object.links) {  // parents come first
    const partnet::Joint* joint = object.findParentJoint(link.name);
    if (joint != nullptr && joint->type == partnet::JointType::kFixed && body.count(joint->parent) > 0) body.insert(link.name);
  }
  return body;
}

const partnet::Joint* findBail(const partnet::Object& object) {
  const partnet::Joint* first = nullptr;
  for (const partnet::Joint& j : object.joints) {
    if (j.type != partnet::JointType::kRevolute && j.type != partnet::JointType::kContinuous) continue;
    const partnet::Semantic* s = object.findSemantic(j.child);
    if (s != nullptr && s->label.find("handle") != std::string::npos) return &j;
    if (first == nullptr) first = &j;
  }
  return first;
}

// An OBJ file's triangles over its vertices, multiplied by `scale`.
TriangleMesh readObjMesh(const std::string& path, const Eigen::Vector3d& scale) {
  partnet::ObjMesh obj = partnet::readObjMesh(path, scale);
  TriangleMesh mesh;
  mesh.vertices = std::move(obj.vertices);
  mesh.triangles = std::move(obj.triangles);
  return mesh;
}

// Where the inside of the rim crosses the axis `side` * y, from rim
// vertices (x, y): on each side of the axis the vertices nearest to it in
// angle (within 0.15 rad of the nearest) and of those the one nearest the
// centre (the inside, not the outside at the same angle); the crossing
// is on the chord between the two. Exact for polygonal rims, within
// r (1 - cos 0.15) for round ones.
std::optional<double> findInnerCrossing(const std::vector<Eigen::Vector2d>& rim, double side) {
  std::optional<Eigen::Vector2d> nearest[2];  // x < 0, x >= 0
  for (int half = 0; half < 2; ++half) {
    double min_angle = 1e9;
    for (const Eigen::Vector2d& p : rim)
      if (side * p.y() > 0 && (p.x() >= 0) == (half == 1))
        min_angle = std::min(min_angle, std::atan2(std::abs(p.x()), side * p.y()));
    for (const Eigen::Vector2d& p : rim)
      if (side * p.y() > 0 && (p.x() >= 0) == (half == 1) &&
          std::atan2(std::abs(p.x()), side * p.y()) <= min_angle + 0.15 && (!nearest[half] || p.norm() < nearest[half]->norm()))
        nearest[half] = p;
  }
  if (!nearest[0] && !nearest[1]) return std::nullopt;
  if (!nearest[0] || !nearest[1]) return side * (nearest[0] ? *nearest[0] : *nearest[1]).y();
  const Eigen::Vector2d a = *nearest[0], b = *nearest[1];
  const double t = b.x() - a.x() > 1e-12 ? -a.x() / (b.x() - a.x()) : 0.5;
  return side * (a.y() + t * (b.y() - a.y()));
}


// HACD's concavity bounds how far a piece's hull may fill in from the
// surface: the expert's fingers (open 2 x 40 mm) straddle a 1-2 cm rim, so
// the inside of the wall must stay within about 1 cm of the mesh. At the
// kit's default (0.1 of the diagonal: 5 cm here) pieces spanning a quarter
// of the rim filled 5 cm of its inside and the fingers stopped on them
// 2.8 cm above the grip, on every bucket. (The kit's coverage check then
// took out the lid HACD made over the flat rims of 100431, 100441 and
// 100454, on which the fingers stood 1-1.5 cm above the rim: expert 11/40
// -> 31/40.)
//
// The cap on HACD's input: the 20 body and handle meshes of the 14 real
// buckets we measured (208-8,748 welded triangles) decomposed in 0.1-10 s
// on the loaded 2-core VM, and 100477's body (63,680) 362 s; 10,000 leaves
// every mesh we measured as it is and bounds a first load to tens of
// seconds a part (docs/partnet.md, "Collision geometry").
const convex::DecompositionOptions kDecomposition = [] {
  convex::DecompositionOptions o;
  o.concavity = 0.02;
  o.max_triangles = 10000;
  return o;
}();

// Each link's collision meshes, merged in its frame, as convex pieces (the
// kit's HACD, cached under `cache_root`): one hull of a bucket's body would
// fill it, and the ball must sit inside; one hull of a U-shaped handle is a
// plate across the rim.
std::map<std::string, std::vector<std::string>> decomposeLinks(const partnet::Object& object,
                                                               const std::string& cache_root) {
  std::map<std::string, std::vector<std::string>> pieces;
  for (const partnet::Link& link : object.links) {
    convex::Mesh merged;
    bool concave = false;
    for (const partnet::Shape& c : link.collisions) {
      if (c.geometry.kind != partnet::Geometry::Kind::kMesh) continue;
      const partnet::ObjMesh mesh =
          partnet::readObjMesh((std::filesystem::path(object.dir) / c.geometry.filename).string(), c.geometry.scale);
      concave = concave || !convex::isConvex({mesh.vertices, mesh.triangles});
      const uint32_t offset = uint32_t(merged.vertices.size());
      for (const Eigen::Vector3d& p : mesh.vertices) merged.vertices.push_back(c.origin * p);
      for (const auto& t : mesh.triangles) merged.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    }
    // A link whose meshes are convex pieces already (a hand decomposition,
    // as ManiSkill's buckets and our fixtures) keeps them.
    if (concave) pieces[link.name] = convex::decomposeCached(merged, cache_root, kDecomposition);
  }
  return pieces;
}

// The body as a shell of kShellThickness at kShellDensity over its surface
// (bucket frame; flipped duplicate faces counted once): PartNet gives no
// masses, and the host's default (its collision hulls' volume) counts the
// pieces' overlaps and the chords of a curved wall: 7-30 kg for the four
// real buckets at 0.3, none of which two grippers lift.
MassProperties calcShellMass(const TriangleMesh& surface) {
  convex::Mesh mesh{surface.vertices, surface.triangles};
  mesh = convex::detail::weld(mesh);
  MassProperties m;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // of r r^T about the origin
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const double mass = kShellDensity * kShellThickness * 0.5 * (b - a).cross(c - a).norm();
    const Eigen::Vector3d sum = a + b + c;
    m.mass += mass;
    first += mass * sum / 3;
    // A triangle's second moment: area / 12 (a a^T + b b^T + c c^T + s s^T).
    second += mass / 12 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + sum * sum.transpose());
  }
  if (!(m.mass > 0)) return m;
  m.com = first / m.mass;
  const Eigen::Matrix3d about_com = second - m.mass * m.com * m.com.transpose();
  m.inertia = about_com.trace() * Eigen::Matrix3d::Identity() - about_com;
  return m;
}

// The bucket's URDF: PartNet's, its concave links as convex pieces (cached
// under `cache_root`; none when it is ""), a decomposed body's mass as the
// shell's, and a new root link in the bucket frame (`origin`: the frame's
// origin in the object frame) with PartNet's root fixed in it.
// `decomposed_body` says whether the body's meshes became pieces.
std::string makeUrdf(const partnet::Object& object, const std::set<std::string>& body_links,
                     const Eigen::Vector3d& origin, const MassProperties& shell, const std::string& cache_root,
                     bool& decomposed_body) {
  std::string urdf = object.urdf;
  decomposed_body = false;
  if (!cache_root.empty()) {
    const std::map<std::string, std::vector<std::string>> pieces = decomposeLinks(object, cache_root);
    if (!pieces.empty()) urdf = partnet::replaceCollisionMeshes(urdf, pieces);
    for (const std::string& link : body_links) decomposed_body = decomposed_body || pieces.count(link) > 0;
  }
  // A decomposed body's mass on the frame link, none on the body's own
  // links (a body of convex pieces keeps the host's mass from their hulls,
  // which is right for solid pieces).
  if (decomposed_body)
  urdf = partnet::editLinks(urdf, [&](const std::string& name, boost::property_tree::ptree& link) {
    if (body_links.count(name) == 0) return;
    for (auto it = link.begin(); it != link.end();) it = it->first == "inertial" ? link.erase(it) : std::next(it);
    boost::property_tree::ptree inertial;
    inertial.put("mass.<xmlattr>.value", "0");
    for (const char* k : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"}) inertial.put(std::string("inertia.<xmlattr>.") + k, "0");
    link.add_child("inertial", inertial);
  });
  // The new root: the bucket frame, PartNet's root fixed in it.
  std::ostringstream frame;
  frame << std::setprecision(17) << "\n  <link name=\"" << kFrameLink << "\">\n"
        << (decomposed_body ? inertialXml(shell) : "") << "  </link>\n  <joint name=\"" << kFrameLink
        << "_joint\" type=\"fixed\"><parent link=\"" << kFrameLink << "\"/><child link=\"" << object.getRoot().name
        << "\"/><origin xyz=\"" << -origin.x() << " " << -origin.y() << " " << -origin.z() << "\"/></joint>";
  return partnet::prependElements(urdf, frame.str(), "PartNet: " + object.urdf_file);
}

}  // namespace

BucketModel loadPartNetBucket(const std::string& folder, const std::string& id, double scale,
                              const std::string& cache_root) {
  const partnet::Object object = partnet::loadObject(folder, id, scale);
  const std::string& path = object.urdf_file;
  if (object.findLink(kFrameLink) != nullptr)
    throw Error("PartNet: " + path + ": link name '" + kFrameLink + "' is taken (MoveBucket adds it)",
                MB_INVALID_ARGUMENT);
  const std::map<std::string, Eigen::Isometry3d> pose = object.calcLinkPoses();
  const std::set<std::string> body_links = findBodyLinks(object);
  std::vector<Eigen::Vector3d> points;  // the body's visual vertices, object frame
  partnet::Bounds box;
  for (const partnet::Link& link : object.links) {
    if (body_links.count(link.name) == 0) continue;
    for (const partnet::Shape& v : link.visuals)
      for (const Eigen::Vector3d& p : object.calcShapePoints(v)) {
        points.push_back(pose.at(link.name) * p);
        box.add(points.back());
      }
  }
  if (box.empty() || !(box.extent().minCoeff() > 0))
    throw Error("PartNet: " + path + ": the bucket body (the links fixed to the root) has no visual geometry",
                MB_INVALID_ARGUMENT);
  // The bucket frame: origin at the bottom centre of the body's box.
  const Eigen::Vector3d origin(box.center().x(), box.center().y(), box.lo.z());
  for (Eigen::Vector3d& p : points) p -= origin;

  BucketModel model;
  model.id = id;
  model.base_dir = object.dir;
  model.body_link = kFrameLink;
  model.body_parts.assign(body_links.begin(), body_links.end());
  model.lower = box.lo - origin;
  model.upper = box.hi - origin;
  const double height = model.upper.z();
  model.rim_height = height;
  // The rim: vertices in the top 8 % of the height. Outer: their farthest
  // reach along x and y; inner: where the rim's inside crosses the y axis
  // (where the expert grips), on either side.
  const double band = height - 0.08 * height;
  std::vector<Eigen::Vector2d> rim;
  for (const Eigen::Vector3d& p : points)
    if (p.z() >= band) {
      rim.push_back(p.head<2>());
      model.rim_outer_y = std::max(model.rim_outer_y, std::abs(p.y()));
      model.rim_outer_x = std::max(model.rim_outer_x, std::abs(p.x()));
    }
  double inner = 0;
  for (const double side : {1.0, -1.0}) {
    const std::optional<double> y = findInnerCrossing(rim, side);
    if (!y || !(*y < model.rim_outer_y - 1e-4) || !(*y > 0))
      throw Error("PartNet: " + path + ": cannot find the rim's inside where it crosses the bucket's " +
                      (side > 0 ? "+" : "-") + "y axis (no wall vertices in the top 8 % of the body inside its rim)",
                  MB_INVALID_ARGUMENT);
    inner += *y / 2;
  }
  model.rim_inner_y = inner;
  // The floor: the lowest vertex level above the underside (the bottom
  // slab's top face and the walls' feet) in the lower quarter; the ball is
  // set on it.
  model.floor_height = height;
  for (const Eigen::Vector3d& p : points)
    if (p.z() > 1e-3 && p.z() < height / 4) model.floor_height = std::min(model.floor_height, p.z());
  if (!(model.floor_height < height / 4))
    throw Error("PartNet: " + path + ": no bottom found (no body vertices between 1 mm and a quarter of the height)",
                MB_INVALID_ARGUMENT);
  // Surface points for the reward, area-weighted on the body's mesh
  // triangles (as ManiSkill samples its meshes); bodies of primitives only
  // get their vertices.
  TriangleMesh surface;
  for (const partnet::Link& link : object.links)
    if (body_links.count(link.name) > 0)
      for (const partnet::Shape& v : link.visuals)
        if (v.geometry.kind == partnet::Geometry::Kind::kMesh) {
          TriangleMesh mesh = readObjMesh((std::filesystem::path(object.dir) / v.geometry.filename).string(),
                                          v.geometry.scale);
          for (Eigen::Vector3d& p : mesh.vertices) p = pose.at(link.name) * (v.origin * p) - origin;
          surface.append(mesh);
        }
  model.surface_points =
      surface.calcArea() > 0 ? sampleSurface(surface, 1024, hashString("surface:partnet:" + id)) : points;
  const MassProperties shell = calcShellMass(surface);

  if (const partnet::Joint* bail = findBail(object)) {
    model.bail_joint = bail->name;
    if (bail->limited && bail->type == partnet::JointType::kRevolute) {
      model.bail_lower = bail->lower;
      model.bail_upper = bail->upper;
    }
  }
  bool decomposed_body = false;
  model.urdf = makeUrdf(object, body_links, origin, shell, cache_root, decomposed_body);

  std::ostringstream summary;
  summary << std::fixed << std::setprecision(2) << "PartNet-Mobility " << id << ", " << height << " m tall, rim "
          << 2 * model.rim_outer_x << " x " << 2 * model.rim_outer_y << " m"
          << (model.bail_joint.empty() ? "" : ", handle on " + model.bail_joint)
          << (decomposed_body ? ", body decomposed" : "");
  model.summary = summary.str();
  return model;
}

}  // namespace move_bucket
