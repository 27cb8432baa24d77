// Procedural buckets (supplement B.9: ManiSkill decomposed its bucket meshes
// into convex pieces by hand because automatic decomposition left bumps and
// seams; ours are built from the pieces). An outline (round, polygonal or
// oval; convex, with a flat face where it crosses the y axis, for the
// grippers) shrinks linearly from the rim to the bottom (taper). The bucket
// is one bottom slab, one wall piece and one rim-lip piece per outline edge,
// each an exact convex loft; an optional bail (handle) turns on a revolute
// joint in two ears below the rim and rests against its limit, below the
// rim, folded down the side. Visual geometry is the same pieces (normals
// smoothed across the round outlines' facets).
//
// Splits (ids are plain numbers):
//   train 3000-3029 (30): round, hexagonal, octagonal
//   test  3100-3109 (10): square and oval, shapes training never shows
#include "move_bucket.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>

namespace move_bucket {

namespace {

const NumberedIds kIds{{3000, 30}, {3100, 10}};
constexpr int kRoundSides = 20;  // facets of round and oval outlines (a multiple of 4)

std::string fmt(double x) {
  std::ostringstream s;
  s << std::setprecision(9) << x;
  return s.str();
}
std::string vec(const Eigen::Vector3d& v) { return fmt(v.x()) + " " + fmt(v.y()) + " " + fmt(v.z()); }
std::string rgba(const std::array<double, 3>& c) { return fmt(c[0]) + " " + fmt(c[1]) + " " + fmt(c[2]) + " 1"; }

// The outer outline at the rim top, counterclockwise, with a face centred
// on +y and one on -y at distance p.radius (the rim's outer apothem).
std::vector<Eigen::Vector2d> makeOutline(const BucketParams& p) {
  const int n = p.sides;
  std::vector<Eigen::Vector2d> ring;
  const double corner = p.radius / std::cos(kPi / n);  // vertex radius for apothem `radius`
  for (int k = 0; k < n; ++k) {
    const double a = kPi / 2 + kPi / n * (2 * k + 1);
    const double sx = p.shape == BucketShape::kOval ? p.aspect : 1.0;
    ring.emplace_back(sx * corner * std::cos(a), corner * std::sin(a));
  }
  return ring;
}

// Per vertex, the offset direction that moves both adjacent edges outward
// by one unit: (n1 + n2) / (1 + n1.n2), n the edges' outward normals.
std::vector<Eigen::Vector2d> calcMiters(const std::vector<Eigen::Vector2d>& ring) {
  const std::size_t n = ring.size();
  std::vector<Eigen::Vector2d> normals(n), miters(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d e = ring[(i + 1) % n] - ring[i];
    normals[i] = Eigen::Vector2d(e.y(), -e.x()).normalized();  // counterclockwise ring: outward
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = normals[(i + n - 1) % n];
    const Eigen::Vector2d& b = normals[i];
    miters[i] = (a + b) / (1 + a.dot(b));
  }
  return miters;
}

std::vector<Eigen::Vector2d> transform(const std::vector<Eigen::Vector2d>& ring, double scale,
                                       const std::vector<Eigen::Vector2d>& miters, double offset) {
  std::vector<Eigen::Vector2d> out;
  for (std::size_t i = 0; i < ring.size(); ++i) out.push_back(scale * ring[i] + offset * miters[i]);
  return out;
}

// Whether `p` (2D) lies outside the convex ring grown by `margin`.
bool isOutside(const std::vector<Eigen::Vector2d>& ring, const Eigen::Vector2d& p, double margin) {
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Eigen::Vector2d e = ring[(i + 1) % ring.size()] - ring[i];
    const Eigen::Vector2d normal = Eigen::Vector2d(e.y(), -e.x()).normalized();
    if (normal.dot(p - ring[i]) > margin) return true;
  }
  return false;
}

MassProperties calcBoxMass(const Eigen::Vector3d& centre, const Eigen::Vector3d& size, double density) {
  MassProperties m;
  m.mass = density * size.prod();
  m.com = centre;
  const Eigen::Vector3d s2 = size.cwiseProduct(size);
  m.inertia = Eigen::Vector3d(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y()).asDiagonal();
  m.inertia *= m.mass / 12.0;
  return m;
}

// A wire segment (solid cylinder of radius r between a and b).
MassProperties calcRodMass(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r, double density) {
  const double length = (b - a).norm();
  const Eigen::Vector3d u = (b - a) / length;
  MassProperties m;
  m.mass = density * kPi * r * r * length;
  m.com = (a + b) / 2;
  const double axial = m.mass * r * r / 2, transverse = m.mass * (3 * r * r + length * length) / 12;
  m.inertia = axial * u * u.transpose() + transverse * (Eigen::Matrix3d::Identity() - u * u.transpose());
  return m;
}


std::array<double, 3> pickColor(Random& rng) {
  static const std::array<std::array<double, 3>, 6> kPlastic = {{{0.80, 0.15, 0.12},
                                                                 {0.15, 0.35, 0.75},
                                                                 {0.20, 0.60, 0.25},
                                                                 {0.90, 0.75, 0.15},
                                                                 {0.55, 0.57, 0.60},
                                                                 {0.95, 0.50, 0.10}}};
  std::array<double, 3> c = kPlastic[std::size_t(rng.integer(0, int(kPlastic.size()) - 1))];
  for (double& x : c) x = std::clamp(x + rng.uniform(-0.06, 0.06), 0.0, 1.0);
  return c;
}

}  // namespace

std::string inertialXml(const MassProperties& m) {
  const Eigen::Matrix3d& I = m.inertia;
  return "    <inertial><origin xyz=\"" + vec(m.com) + "\"/><mass value=\"" + fmt(m.mass) + "\"/><inertia ixx=\"" +
         fmt(I(0, 0)) + "\" ixy=\"" + fmt(I(0, 1)) + "\" ixz=\"" + fmt(I(0, 2)) + "\" iyy=\"" + fmt(I(1, 1)) +
         "\" iyz=\"" + fmt(I(1, 2)) + "\" izz=\"" + fmt(I(2, 2)) + "\"/></inertial>\n";
}

std::string toString(BucketShape shape) {
  switch (shape) {
    case BucketShape::kRound: return "round";
    case BucketShape::kPolygon: return "polygon";
    case BucketShape::kOval: return "oval";
  }
  return "?";
}

std::vector<std::string> listGeneratedBuckets(const std::string& split) { return kIds.list(split); }

BucketParams getBucketParams(const std::string& bucket_id) {
  const bool test = kIds.requireTest(bucket_id, "generated bucket");
  Random rng(hashString("manibench.move_bucket.v1:" + bucket_id));
  BucketParams p;
  const int index = std::stoi(bucket_id) % 100;
  if (test) {  // alternate square / oval
    if (index % 2 == 0) {
      p.shape = BucketShape::kPolygon;
      p.sides = 4;
    } else {
      p.shape = BucketShape::kOval;
      p.sides = kRoundSides;
      p.aspect = rng.uniform(1.15, 1.35);
    }
  } else {  // 3 round, 1 hexagonal, 1 octagonal in every 5
    const int kind = index % 5;
    p.shape = kind < 3 ? BucketShape::kRound : BucketShape::kPolygon;
    p.sides = kind < 3 ? kRoundSides : (kind == 3 ? 6 : 8);
  }
  p.height = rng.uniform(0.24, 0.34);
  p.radius = p.shape == BucketShape::kPolygon && p.sides == 4 ? rng.uniform(0.12, 0.15) : rng.uniform(0.13, 0.18);
  if (p.shape == BucketShape::kOval) p.radius = rng.uniform(0.12, 0.15);
  p.taper = rng.chance(0.25) ? 1.0 : rng.uniform(0.72, 0.95);
  p.wall = rng.uniform(0.005, 0.008);
  p.bottom = rng.uniform(0.008, 0.012);
  p.lip_width = rng.uniform(0.006, 0.012);
  p.lip_height = rng.uniform(0.012, 0.02);
  p.bail = rng.chance(0.5);
  p.bail_drop = rng.uniform(0.045, 0.06);
  p.bail_wire = rng.uniform(0.0035, 0.005);
  p.color = pickColor(rng);
  p.bail_color = {0.6, 0.6, 0.62};
  return p;
}

BucketModel generateBucket(const std::string& bucket_id) { return generateBucket(bucket_id, getBucketParams(bucket_id)); }

std::vector<TriangleMesh> makeBucketPieces(const BucketParams& p) {
  if (!(p.sides >= 4 && p.sides % 2 == 0) || !(p.height > 0.1) || !(p.radius > 0.05) ||
      !(p.taper > 0.3) || !(p.taper <= 1) || !(p.wall > 0.001) || !(p.bottom > 0.001) || !(p.lip_width >= 0) ||
      !(p.lip_height > 0) || !(p.aspect >= 1))
    throw Error("bucket parameters out of range", MB_INVALID_ARGUMENT);
  const std::vector<Eigen::Vector2d> outline = makeOutline(p);
  const std::vector<Eigen::Vector2d> miters = calcMiters(outline);
  const double H = p.height, b = p.bottom;
  auto scale = [&](double z) { return p.taper + (1 - p.taper) * z / H; };
  const std::size_t n = outline.size();
  std::vector<TriangleMesh> pieces;
  pieces.push_back(makeLoft(transform(outline, scale(0), miters, 0), 0, transform(outline, scale(b), miters, 0), b));
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t j = (k + 1) % n;
    auto wallRing = [&](double z) {
      const double s = scale(z);
      return std::vector<Eigen::Vector2d>{s * outline[k], s * outline[j], s * outline[j] - p.wall * miters[j],
                                          s * outline[k] - p.wall * miters[k]};
    };
    pieces.push_back(makeLoft(wallRing(b), b, wallRing(H), H));
  }
  const double lip_bottom = H - p.lip_height;
  if (p.lip_width > 0)
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t j = (k + 1) % n;
      auto lipRing = [&](double z) {
        const double s = scale(z);
        return std::vector<Eigen::Vector2d>{s * outline[k], s * outline[k] + p.lip_width * miters[k],
                                            s * outline[j] + p.lip_width * miters[j], s * outline[j]};
      };
      pieces.push_back(makeLoft(lipRing(lip_bottom), lip_bottom, lipRing(H), H));
    }
  return pieces;
}

BucketModel generateBucket(const std::string& bucket_id, const BucketParams& p) {
  const std::vector<TriangleMesh> pieces = makeBucketPieces(p);
  const std::vector<Eigen::Vector2d> outline = makeOutline(p);
  const std::vector<Eigen::Vector2d> miters = calcMiters(outline);
  const double H = p.height, b = p.bottom, lip_bottom = H - p.lip_height;
  auto scale = [&](double z) { return p.taper + (1 - p.taper) * z / H; };
  const std::size_t n = outline.size();

  BucketModel model;
  model.id = bucket_id;
  TriangleMesh body;
  std::vector<MassProperties> body_mass;
  for (const TriangleMesh& piece : pieces) {
    body.append(piece);
    body_mass.push_back(calcMassProperties(piece, kDensity));
  }
  model.lower = Eigen::Vector3d::Constant(1e9);
  model.upper = -model.lower;
  for (const Eigen::Vector3d& v : body.vertices) {
    model.lower = model.lower.cwiseMin(v);
    model.upper = model.upper.cwiseMax(v);
  }
  const bool round = p.shape != BucketShape::kPolygon;
  model.files["body.obj"] = writeObj(body, "bucket_body", round);
  std::ostringstream collisions;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    std::ostringstream name;
    name << "piece_" << std::setw(2) << std::setfill('0') << i;
    model.files[name.str() + ".obj"] = writeObj(pieces[i], name.str(), false);
    collisions << "    <collision name=\"" << name.str() << "\"><geometry><mesh filename=\"" << name.str()
               << ".obj\"/></geometry></collision>\n";
  }
  model.rim_height = H;
  model.rim_outer_y = p.radius + p.lip_width;
  model.rim_inner_y = p.radius - p.wall;
  model.rim_outer_x = model.upper.x();
  model.floor_height = b;
  model.surface_points = sampleSurface(body, 1024, hashString("surface:" + bucket_id));

  // The bail: ears on the x axis below the rim, deep enough that the wire
  // clears the lip; the wire a half circle of capsules through them.
  std::ostringstream ears, bail_link, bail_joint;
  MassProperties bail_mass;
  if (p.bail) {
    const double zp = H - p.bail_drop;
    // The bail's radius clears the rim all round (a square's corners
    // reach farther than its faces); the ears reach out to it.
    double x_pivot = 0, rim_reach = 0;
    for (std::size_t k = 0; k < n; ++k) {
      x_pivot = std::max(x_pivot, scale(zp) * outline[k].x());
      rim_reach = std::max(rim_reach, (outline[k] + p.lip_width * miters[k]).norm());
    }
    const double R = rim_reach + 0.012;  // the pivots at the ears' outer faces
    const double ear_depth = R - x_pivot;
    for (int side : {-1, 1}) {
      const Eigen::Vector3d centre(side * (x_pivot + ear_depth / 2 - 0.002), 0, zp);
      const Eigen::Vector3d size(ear_depth + 0.004, 0.022, 0.03);
      body_mass.push_back(calcBoxMass(centre, size, kDensity));
      const std::string g = "<origin xyz=\"" + vec(centre) + "\"/><geometry><box size=\"" + vec(size) + "\"/></geometry>";
      const std::string name = side < 0 ? "ear_neg" : "ear_pos";
      ears << "    <visual name=\"" << name << "\">" << g << "<material name=\"bucket_" << name << "\"><color rgba=\""
           << rgba(p.color) << "\"/></material></visual>\n    <collision name=\"" << name << "\">" << g
           << "</collision>\n";
    }
    constexpr int kSegments = 10;
    std::vector<MassProperties> wire;
    bail_link << "  <link name=\"bail\">\n";
    std::ostringstream shapes;
    for (int i = 0; i < kSegments; ++i) {
      const double a0 = kPi * i / kSegments, a1 = kPi * (i + 1) / kSegments;
      const Eigen::Vector3d p0(R * std::cos(a0), 0, R * std::sin(a0)), p1(R * std::cos(a1), 0, R * std::sin(a1));
      const Eigen::Vector3d d = p1 - p0;
      wire.push_back(calcRodMass(p0, p1, p.bail_wire, kDensity));
      const std::string g = "<origin xyz=\"" + vec((p0 + p1) / 2) + "\" rpy=\"0 " + fmt(std::atan2(d.x(), d.z())) +
                            " 0\"/><geometry><capsule radius=\"" + fmt(p.bail_wire) + "\" length=\"" +
                            fmt(d.norm()) + "\"/></geometry>";
      shapes << "    <visual name=\"bail_" << i << "\">" << g << "<material name=\"bail_metal\"><color rgba=\""
             << rgba(p.bail_color) << "\"/></material></visual>\n    <collision name=\"bail_" << i << "\">" << g
             << "</collision>\n";
    }
    bail_mass = combine(wire);
    bail_link << inertialXml(bail_mass) << shapes.str() << "  </link>\n";
    // Limit: the farthest the bail folds down (from upright, either way)
    // with every point of the wire outside the walls and lip by 3 mm and
    // 2 cm above the bottom, less 0.05 rad.
    auto fits = [&](double q) {
      for (int i = 0; i <= 60; ++i) {
        const double a = kPi * i / 60;
        const double z = zp + R * std::sin(a) * std::cos(q);
        const Eigen::Vector2d xy(R * std::cos(a), -R * std::sin(a) * std::sin(q));
        if (z < 0.02 + p.bail_wire) return false;
        const double zc = std::min(z, H);
        const double grow = p.bail_wire + 0.003 + (z >= lip_bottom - p.bail_wire ? p.lip_width : 0.0);
        if (!isOutside(transform(outline, scale(zc), miters, 0), xy, grow)) return false;
      }
      return true;
    };
    double limit = kPi / 2;
    while (limit + 0.005 < 0.95 * kPi && fits(limit + 0.005)) limit += 0.005;
    if (!fits(kPi / 2)) throw Error("bucket " + bucket_id + ": the bail does not clear the walls");
    model.bail_joint = "bail_joint";
    model.bail_lower = -(limit - 0.05);
    model.bail_upper = limit - 0.05;
    bail_joint << "  <joint name=\"bail_joint\" type=\"revolute\"><parent link=\"bucket\"/><child link=\"bail\"/>"
               << "<origin xyz=\"0 0 " << fmt(zp) << "\"/><axis xyz=\"1 0 0\"/><limit lower=\""
               << fmt(model.bail_lower) << "\" upper=\"" << fmt(model.bail_upper)
               << "\" effort=\"10\" velocity=\"10\"/><dynamics damping=\"0.005\" friction=\"0.01\"/></joint>\n";
  }
  const MassProperties body_total = combine(body_mass);
  model.mass = body_total.mass + bail_mass.mass;

  std::ostringstream urdf;
  urdf << "<?xml version=\"1.0\"?>\n<!-- manibench procedural bucket " << bucket_id << " -->\n<robot name=\"bucket_"
       << bucket_id << "\">\n  <link name=\"bucket\">\n"
       << inertialXml(body_total) << "    <visual name=\"body\"><geometry><mesh filename=\"body.obj\"/></geometry>"
       << "<material name=\"bucket_plastic\"><color rgba=\"" << rgba(p.color) << "\"/></material></visual>\n"
       << ears.str() << collisions.str() << "  </link>\n"
       << bail_link.str() << bail_joint.str() << "</robot>\n";
  model.urdf = urdf.str();
  std::ostringstream summary;
  summary << std::fixed << std::setprecision(2);
  if (p.shape == BucketShape::kPolygon)
    summary << p.sides << "-sided";
  else
    summary << toString(p.shape);
  summary << ", " << H << " m tall, rim " << 2 * model.upper.x() << " x " << 2 * model.upper.y() << " m, taper "
          << p.taper << ", " << std::setprecision(1) << model.mass << " kg" << (p.bail ? ", bail" : "") << ", "
          << pieces.size() << " convex pieces";
  model.summary = summary.str();
  return model;
}

}  // namespace move_bucket
