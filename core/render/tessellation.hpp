// Internal to core/render: triangle meshes of the URDF primitives, in
// the shape frame (centred; cylinders and capsules along z), counterclockwise
// seen from outside, with unit normals. Kept coarse: llvmpipe's vertex stage
// runs on one core, so every triangle counts.
#pragma once

#include <cstdint>
#include <vector>

namespace manibench {

struct TriangleMesh {
  std::vector<float> vertices;  // x y z nx ny nz per vertex
  std::vector<std::uint32_t> indices;
  std::size_t getVertexCount() const { return vertices.size() / 6; }
  std::size_t getTriangleCount() const { return indices.size() / 3; }
};

TriangleMesh makeBoxMesh(double size_x, double size_y, double size_z);  // full extents
TriangleMesh makeSphereMesh(double radius);
TriangleMesh makeCylinderMesh(double radius, double length);
TriangleMesh makeCapsuleMesh(double radius, double length);  // length without the caps

}  // namespace manibench
