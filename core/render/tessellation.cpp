#include "tessellation.hpp"

#include <cmath>

namespace manibench {
namespace {

constexpr int kSlices = 16;         // around the axis
constexpr int kHemisphereRings = 4;  // pole to equator

void addVertex(TriangleMesh& mesh, float x, float y, float z, float nx, float ny, float nz) {
  mesh.vertices.insert(mesh.vertices.end(), {x, y, z, nx, ny, nz});
}

// A point of a profile curve in the (r, z) half plane, with its normal.
struct ProfilePoint {
  double r, z, normal_r, normal_z;
};

// Revolves a smooth profile (ordered from bottom to top, or from the axis
// outward for a bottom cap) about z. Triangles at points on the axis would
// be degenerate and are skipped.
void addRevolved(TriangleMesh& mesh, const std::vector<ProfilePoint>& profile) {
  const auto base = static_cast<std::uint32_t>(mesh.getVertexCount());
  for (const ProfilePoint& p : profile) {
    for (int j = 0; j <= kSlices; ++j) {
      const double angle = 2 * M_PI * (j % kSlices) / kSlices;
      const double c = std::cos(angle), s = std::sin(angle);
      addVertex(mesh, static_cast<float>(p.r * c), static_cast<float>(p.r * s),
                static_cast<float>(p.z), static_cast<float>(p.normal_r * c),
                static_cast<float>(p.normal_r * s), static_cast<float>(p.normal_z));
    }
  }
  const std::uint32_t row = kSlices + 1;
  for (std::size_t i = 0; i + 1 < profile.size(); ++i) {
    for (std::uint32_t j = 0; j < static_cast<std::uint32_t>(kSlices); ++j) {
      const std::uint32_t a = base + static_cast<std::uint32_t>(i) * row + j, b = a + 1;
      const std::uint32_t d = a + row, c = d + 1;
      if (profile[i].r > 0) mesh.indices.insert(mesh.indices.end(), {a, b, c});
      if (profile[i + 1].r > 0) mesh.indices.insert(mesh.indices.end(), {a, c, d});
    }
  }
}

// Quarter circle of a hemisphere centred at height z0: `upper` from the
// equator to the pole, else from the pole to the equator.
void appendHemisphere(std::vector<ProfilePoint>& profile, double radius, double z0, bool upper) {
  for (int k = 0; k <= kHemisphereRings; ++k) {
    const double t = static_cast<double>(k) / kHemisphereRings;
    const double phi = upper ? t * M_PI / 2 : -M_PI / 2 + t * M_PI / 2;
    const double c = std::cos(phi), s = std::sin(phi);
    profile.push_back({std::abs(c) < 1e-12 ? 0.0 : radius * c, z0 + radius * s, c, s});
  }
}

}  // namespace

TriangleMesh makeBoxMesh(double size_x, double size_y, double size_z) {
  TriangleMesh mesh;
  const float half[3] = {static_cast<float>(size_x / 2), static_cast<float>(size_y / 2),
                         static_cast<float>(size_z / 2)};
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign = -1; sign <= 1; sign += 2) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // u x v = +axis
      const auto base = static_cast<std::uint32_t>(mesh.getVertexCount());
      const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
      for (int k = 0; k < 4; ++k) {
        float p[3], n[3] = {0, 0, 0};
        p[axis] = sign * half[axis];
        p[u] = su[k] * half[u];
        p[v] = sv[k] * half[v];
        n[axis] = static_cast<float>(sign);
        addVertex(mesh, p[0], p[1], p[2], n[0], n[1], n[2]);
      }
      if (sign > 0) {
        mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
      } else {
        mesh.indices.insert(mesh.indices.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
      }
    }
  }
  return mesh;
}

TriangleMesh makeSphereMesh(double radius) {
  std::vector<ProfilePoint> profile;
  appendHemisphere(profile, radius, 0, false);
  profile.pop_back();  // the equator once
  appendHemisphere(profile, radius, 0, true);
  TriangleMesh mesh;
  addRevolved(mesh, profile);
  return mesh;
}

TriangleMesh makeCylinderMesh(double radius, double length) {
  const double h = length / 2;
  TriangleMesh mesh;
  addRevolved(mesh, {{0, -h, 0, -1}, {radius, -h, 0, -1}});  // bottom cap
  addRevolved(mesh, {{radius, -h, 1, 0}, {radius, h, 1, 0}});
  addRevolved(mesh, {{radius, h, 0, 1}, {0, h, 0, 1}});  // top cap
  return mesh;
}

TriangleMesh makeCapsuleMesh(double radius, double length) {
  std::vector<ProfilePoint> profile;
  appendHemisphere(profile, radius, -length / 2, false);
  appendHemisphere(profile, radius, length / 2, true);  // the side joins the equators
  TriangleMesh mesh;
  addRevolved(mesh, profile);
  return mesh;
}

}  // namespace manibench
