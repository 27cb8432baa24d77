// Triangle meshes for the procedural buckets: convex lofts between two
// polygons (the pieces the generator builds a bucket from), their mass
// properties, OBJ text and surface samples.
#include "move_bucket.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <unordered_map>

namespace move_bucket {

void TriangleMesh::append(const TriangleMesh& other) {
  const auto offset = uint32_t(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  for (const auto& t : other.triangles) triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

double TriangleMesh::calcArea() const {
  double area = 0;
  for (const auto& t : triangles)
    area += 0.5 * (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]).norm();
  return area;
}

// Volume integrals of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx over the solid a
// closed, outward-oriented triangle mesh bounds (divergence theorem; the
// subexpressions of D. Eberly, "Polyhedral Mass Properties", 2002).
MassProperties calcMassProperties(const TriangleMesh& mesh, double density) {
  double integral[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  auto sub = [](double w0, double w1, double w2, double& f1, double& f2, double& f3, double& g0, double& g1,
                double& g2) {
    const double t0 = w0 + w1, t1 = w0 * w0, t2 = t1 + w1 * t0;
    f1 = t0 + w2;
    f2 = t2 + w2 * f1;
    f3 = w0 * t1 + w1 * t2 + w2 * f2;
    g0 = f2 + w0 * (f1 + w0);
    g1 = f2 + w1 * (f1 + w1);
    g2 = f2 + w2 * (f1 + w2);
  };
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& p0 = mesh.vertices[t[0]];
    const Eigen::Vector3d& p1 = mesh.vertices[t[1]];
    const Eigen::Vector3d& p2 = mesh.vertices[t[2]];
    const Eigen::Vector3d d = (p1 - p0).cross(p2 - p0);
    double f1x, f2x, f3x, g0x, g1x, g2x, f1y, f2y, f3y, g0y, g1y, g2y, f1z, f2z, f3z, g0z, g1z, g2z;
    sub(p0.x(), p1.x(), p2.x(), f1x, f2x, f3x, g0x, g1x, g2x);
    sub(p0.y(), p1.y(), p2.y(), f1y, f2y, f3y, g0y, g1y, g2y);
    sub(p0.z(), p1.z(), p2.z(), f1z, f2z, f3z, g0z, g1z, g2z);
    integral[0] += d.x() * f1x;
    integral[1] += d.x() * f2x;
    integral[2] += d.y() * f2y;
    integral[3] += d.z() * f2z;
    integral[4] += d.x() * f3x;
    integral[5] += d.y() * f3y;
    integral[6] += d.z() * f3z;
    integral[7] += d.x() * (p0.y() * g0x + p1.y() * g1x + p2.y() * g2x);
    integral[8] += d.y() * (p0.z() * g0y + p1.z() * g1y + p2.z() * g2y);
    integral[9] += d.z() * (p0.x() * g0z + p1.x() * g1z + p2.x() * g2z);
  }
  const double scale[10] = {1.0 / 6, 1.0 / 24, 1.0 / 24, 1.0 / 24, 1.0 / 60,
                            1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (int i = 0; i < 10; ++i) integral[i] *= scale[i] * density;
  MassProperties m;
  m.mass = integral[0];
  if (!(m.mass > 0)) throw Error("mass properties of a mesh that bounds no volume (is it closed and outward?)");
  m.com = Eigen::Vector3d(integral[1], integral[2], integral[3]) / m.mass;
  const Eigen::Vector3d& c = m.com;
  m.inertia(0, 0) = integral[5] + integral[6] - m.mass * (c.y() * c.y() + c.z() * c.z());
  m.inertia(1, 1) = integral[4] + integral[6] - m.mass * (c.z() * c.z() + c.x() * c.x());
  m.inertia(2, 2) = integral[4] + integral[5] - m.mass * (c.x() * c.x() + c.y() * c.y());
  m.inertia(0, 1) = m.inertia(1, 0) = -(integral[7] - m.mass * c.x() * c.y());
  m.inertia(1, 2) = m.inertia(2, 1) = -(integral[8] - m.mass * c.y() * c.z());
  m.inertia(0, 2) = m.inertia(2, 0) = -(integral[9] - m.mass * c.z() * c.x());
  return m;
}

MassProperties combine(const std::vector<MassProperties>& parts) {
  MassProperties total;
  for (const MassProperties& p : parts) {
    total.mass += p.mass;
    total.com += p.mass * p.com;
  }
  if (!(total.mass > 0)) throw Error("combined mass properties of nothing");
  total.com /= total.mass;
  for (const MassProperties& p : parts) {
    const Eigen::Vector3d d = p.com - total.com;
    total.inertia += p.inertia + p.mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  return total;
}

namespace {

double signedArea(const std::vector<Eigen::Vector2d>& ring) {
  double a = 0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Eigen::Vector2d& p = ring[i];
    const Eigen::Vector2d& q = ring[(i + 1) % ring.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return a / 2;
}

}  // namespace

TriangleMesh makeLoft(const std::vector<Eigen::Vector2d>& bottom, double z0, const std::vector<Eigen::Vector2d>& top,
                      double z1) {
  if (bottom.size() != top.size() || bottom.size() < 3 || !(z1 > z0))
    throw Error("makeLoft: two rings of the same size (>= 3) with z1 > z0");
  const bool ccw = signedArea(bottom) > 0;
  if (ccw != (signedArea(top) > 0)) throw Error("makeLoft: the rings turn in opposite senses");
  const auto n = uint32_t(bottom.size());
  TriangleMesh mesh;
  for (const Eigen::Vector2d& p : bottom) mesh.vertices.emplace_back(p.x(), p.y(), z0);
  for (const Eigen::Vector2d& p : top) mesh.vertices.emplace_back(p.x(), p.y(), z1);
  // vertex i of the ring in counterclockwise order (seen from +z)
  auto b = [&](uint32_t i) { return ccw ? i % n : (n - i % n) % n; };
  auto t = [&](uint32_t i) { return n + b(i); };
  for (uint32_t i = 1; i + 1 < n; ++i) {
    mesh.triangles.push_back({b(0), b(i + 1), b(i)});  // bottom, facing -z
    mesh.triangles.push_back({t(0), t(i), t(i + 1)});  // top, facing +z
  }
  for (uint32_t i = 0; i < n; ++i) {
    mesh.triangles.push_back({b(i), b(i + 1), t(i + 1)});
    mesh.triangles.push_back({b(i), t(i + 1), t(i)});
  }
  return mesh;
}

namespace {

std::string fmt(double x) {
  std::ostringstream s;
  s << std::setprecision(9) << x;
  return s.str();
}

}  // namespace

std::string writeObj(const TriangleMesh& mesh, const std::string& name, bool smooth) {
  // Per-corner normals. Smooth: the area-weighted normals of the triangles
  // around the corner's position (across pieces: positions are welded at
  // 1e-7 m) whose face turns by less than 30 degrees from this one, so
  // that creases (rim top, bottom edge) stay sharp.
  std::vector<Eigen::Vector3d> face(mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& t = mesh.triangles[i];
    face[i] = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
  }
  auto key = [](const Eigen::Vector3d& p) {
    const auto q = [](double x) { return int64_t(std::llround(x * 1e7)); };
    return std::to_string(q(p.x())) + "," + std::to_string(q(p.y())) + "," + std::to_string(q(p.z()));
  };
  std::unordered_map<std::string, std::vector<std::size_t>> around;
  if (smooth)
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
      for (uint32_t v : mesh.triangles[i]) around[key(mesh.vertices[v])].push_back(i);
  const double crease = std::cos(30.0 * manibench::sdk::kPi / 180.0);
  std::ostringstream obj;
  obj << "# manibench procedural bucket mesh\no " << name << "\n";
  for (const Eigen::Vector3d& v : mesh.vertices) obj << "v " << fmt(v.x()) << " " << fmt(v.y()) << " " << fmt(v.z()) << "\n";
  std::vector<std::array<std::size_t, 3>> normal_index(mesh.triangles.size());
  std::size_t normals = 0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Eigen::Vector3d own = face[i].normalized();
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d n = face[i];
      if (smooth) {
        n.setZero();
        for (std::size_t j : around[key(mesh.vertices[mesh.triangles[i][std::size_t(c)]])])
          if (face[j].normalized().dot(own) > crease) n += face[j];
      }
      n.normalize();
      obj << "vn " << fmt(n.x()) << " " << fmt(n.y()) << " " << fmt(n.z()) << "\n";
      normal_index[i][std::size_t(c)] = ++normals;
    }
  }
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    obj << "f";
    for (int c = 0; c < 3; ++c) obj << " " << mesh.triangles[i][std::size_t(c)] + 1 << "//" << normal_index[i][std::size_t(c)];
    obj << "\n";
  }
  return obj.str();
}

std::vector<Eigen::Vector3d> sampleSurface(const TriangleMesh& mesh, std::size_t count, uint64_t seed) {
  std::vector<double> cumulative;
  double total = 0;
  for (const auto& t : mesh.triangles) {
    total += 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
    cumulative.push_back(total);
  }
  if (!(total > 0)) throw Error("sampleSurface: the mesh has no area");
  Random rng(seed);
  std::vector<Eigen::Vector3d> points;
  points.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double pick = rng.uniform(0, total);
    const std::size_t k = std::size_t(std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
    const auto& t = mesh.triangles[std::min(k, mesh.triangles.size() - 1)];
    const double r1 = std::sqrt(rng.uniform(0, 1)), r2 = rng.uniform(0, 1);
    points.push_back((1 - r1) * mesh.vertices[t[0]] + r1 * (1 - r2) * mesh.vertices[t[1]] +
                     r1 * r2 * mesh.vertices[t[2]]);
  }
  return points;
}

}  // namespace move_bucket
