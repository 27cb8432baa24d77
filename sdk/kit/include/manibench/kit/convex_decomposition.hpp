// Convex pieces of a concave part, for the parts whose convex hull would
// fill a cavity a task needs (a bucket's body must hold the ball): the host
// takes every collision mesh as its convex hull, so such a part is handed
// to it as several meshes, each convex.
//
// The decomposition is HACD (Mamou's hierarchical approximate convex
// decomposition) as Debian's libbullet-extras-dev ships it: Debian 12
// packages neither V-HACD nor CoACD (what ManiSkill2 used), and Bullet's
// other decomposer (Ratcliff's) gave different pieces for the same input
// in 27 of 45 runs and filled the buckets. HACD is bit-identical across
// runs and processes. PartNet's meshes need three things first, measured
// on the 4 real buckets and a drawer (docs/partnet.md):
//   - every face is there twice, flipped (double-sided rendering): exact
//     duplicate vertices are welded and duplicate triangles dropped, else
//     HACD makes flat pieces and loses a drawer's surface (5 % covered);
//   - an open single-sided cup lies on its own hull, so HACD sees nothing
//     concave: the surface is given a thickness (shell) first, outer and
//     inner layers stitched at the open edges;
//   - extra distance points on (without them the cavity stays filled).
// Then a concavity of 0.1 of the bounding-box diagonal gave 21-49 pieces
// in 0.3-1.2 s per part, every bucket and the drawer hollow (at worst 6 %
// of a central cavity box covered, against 100 % for the single hull).
//
// Pieces are cached on disk by the content of the mesh and the options
// (decomposeCached), so a part is decomposed once per machine. A family
// using this header links HACD (libHACD from libbullet-extras-dev, headers
// in /usr/include/bullet: the CMake target manibench::kit_decomposition).
#pragma once

#include <manibench/kit/common.hpp>
#include <manibench/kit/file_cache.hpp>

#include <HACD/hacdHACD.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace manibench::kit::convex {

struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;
};

struct DecompositionOptions {
  double concavity = 0.1;            // allowed concavity, fraction of the bounding-box diagonal
  std::size_t min_pieces = 8;        // HACD stops merging at this many (a lower bound)
  std::size_t max_piece_vertices = 64;
  double shell = 0.005;              // half thickness given to the surface, fraction of the diagonal
  double connect = 0.015;            // parts closer than this are joined, fraction of the diagonal
  double min_coverage = 0.6;         // a piece whose hull is less covered by the surface is split (lids)
  // HACD's time grows faster than the square of the triangles it is given
  // (docs/partnet.md, "Collision geometry"): a welded mesh with more is
  // first simplified by vertex clustering to at most this many (0: never).
  std::size_t max_triangles = 0;
};

namespace detail {

// Exact duplicate vertices welded, triangles that repeat one already kept
// (in any winding) and degenerate ones dropped.
inline Mesh weld(const Mesh& in) {
  Mesh out;
  std::map<std::array<double, 3>, uint32_t> index;
  std::vector<uint32_t> remap(in.vertices.size());
  for (std::size_t i = 0; i < in.vertices.size(); ++i) {
    const Eigen::Vector3d& v = in.vertices[i];
    const auto [it, added] = index.emplace(std::array<double, 3>{v.x(), v.y(), v.z()}, uint32_t(out.vertices.size()));
    if (added) out.vertices.push_back(v);
    remap[i] = it->second;
  }
  std::map<std::array<uint32_t, 3>, bool> seen;
  for (const auto& t : in.triangles) {
    const std::array<uint32_t, 3> r = {remap[t[0]], remap[t[1]], remap[t[2]]};
    if (r[0] == r[1] || r[1] == r[2] || r[0] == r[2]) continue;
    std::array<uint32_t, 3> key = r;
    std::sort(key.begin(), key.end());
    if (!seen.emplace(key, true).second) continue;
    out.triangles.push_back(r);
  }
  return out;
}

// `in` (welded) with its vertices clustered on a grid of cells of side h:
// each cell's vertices replaced by their mean, triangles that collapse or
// repeat dropped. Deterministic: cells are keyed by integer coordinates and
// visited in that order.
inline Mesh cluster(const Mesh& in, double h) {
  Eigen::Vector3d lo = in.vertices.front();
  for (const Eigen::Vector3d& v : in.vertices) lo = lo.cwiseMin(v);
  std::map<std::array<long, 3>, std::pair<Eigen::Vector3d, int>> cells;
  std::vector<std::array<long, 3>> key(in.vertices.size());
  for (std::size_t i = 0; i < in.vertices.size(); ++i) {
    const Eigen::Vector3d c = (in.vertices[i] - lo) / h;
    key[i] = {long(std::floor(c.x())), long(std::floor(c.y())), long(std::floor(c.z()))};
    auto& cell = cells.try_emplace(key[i], Eigen::Vector3d::Zero(), 0).first->second;
    cell.first += in.vertices[i];
    ++cell.second;
  }
  Mesh out;
  std::map<std::array<long, 3>, uint32_t> index;
  for (const auto& [k, cell] : cells) {
    index[k] = uint32_t(out.vertices.size());
    out.vertices.push_back(cell.first / cell.second);
  }
  for (const auto& t : in.triangles) out.triangles.push_back({index[key[t[0]]], index[key[t[1]]], index[key[t[2]]]});
  return weld(out);
}

// `in` (welded) clustered on the finest grid, from 1/1000 of its diagonal
// growing by a quarter each time, that leaves at most `max_triangles`.
inline Mesh simplify(const Mesh& in, std::size_t max_triangles, double diagonal) {
  if (max_triangles == 0 || in.triangles.size() <= max_triangles) return in;
  for (double h = 1e-3 * diagonal;; h *= 1.25) {
    Mesh out = cluster(in, h);
    if (out.triangles.size() <= max_triangles) return out;
  }
}

// The surface as a closed slab of half thickness h: faces oriented alike
// (a walk over edges shared by two faces), each vertex moved +-h along its
// normal, the inner layer flipped, open edges stitched.
inline Mesh solidify(const Mesh& in, double h) {
  std::vector<std::array<uint32_t, 3>> t = in.triangles;
  std::map<std::pair<uint32_t, uint32_t>, std::vector<std::size_t>> edge_faces;
  for (std::size_t f = 0; f < t.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[f][k], b = t[f][(k + 1) % 3];
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  auto runs = [](const std::array<uint32_t, 3>& tri, uint32_t a, uint32_t b) {
    for (int k = 0; k < 3; ++k)
      if (tri[k] == a && tri[(k + 1) % 3] == b) return true;
    return false;
  };
  std::vector<char> visited(t.size(), 0);
  std::vector<std::size_t> stack;
  for (std::size_t start = 0; start < t.size(); ++start) {
    if (visited[start]) continue;
    visited[start] = 1;
    stack.push_back(start);
    while (!stack.empty()) {
      const std::size_t f = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = t[f][k], b = t[f][(k + 1) % 3];
        const auto& faces = edge_faces[{std::min(a, b), std::max(a, b)}];
        if (faces.size() != 2) continue;
        const std::size_t g = faces[0] == f ? faces[1] : faces[0];
        if (visited[g]) continue;
        if (runs(t[g], a, b)) std::swap(t[g][1], t[g][2]);  // a neighbour runs the shared edge b -> a
        visited[g] = 1;
        stack.push_back(g);
      }
    }
  }
  const std::size_t n = in.vertices.size();
  std::vector<Eigen::Vector3d> normal(n, Eigen::Vector3d::Zero());
  for (const auto& tri : t) {
    const Eigen::Vector3d face =
        (in.vertices[tri[1]] - in.vertices[tri[0]]).cross(in.vertices[tri[2]] - in.vertices[tri[0]]);
    for (const uint32_t v : tri) normal[v] += face;
  }
  Mesh out;
  out.vertices.resize(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const double length = normal[i].norm();
    const Eigen::Vector3d d = length > 0 ? Eigen::Vector3d(normal[i] * (h / length)) : Eigen::Vector3d::Zero();
    out.vertices[i] = in.vertices[i] + d;
    out.vertices[i + n] = in.vertices[i] - d;
  }
  const uint32_t m = uint32_t(n);
  for (const auto& tri : t) {
    out.triangles.push_back(tri);
    out.triangles.push_back({tri[2] + m, tri[1] + m, tri[0] + m});
  }
  for (const auto& [edge, faces] : edge_faces) {
    if (faces.size() != 1) continue;
    uint32_t a = edge.first, b = edge.second;
    if (!runs(t[faces[0]], a, b)) std::swap(a, b);
    out.triangles.push_back({b, a, a + m});
    out.triangles.push_back({b, a + m, b + m});
  }
  return out;
}

// Squared distance from p to the triangle abc (Ericson, Real-Time
// Collision Detection, 5.1.5).
inline double calcSquaredDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + ab * (d1 / (d1 - d3)))).squaredNorm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + ac * (d2 / (d2 - d6)))).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).squaredNorm();
  const double denominator = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denominator) + ac * (vc * denominator))).squaredNorm();
}

// The share of a piece's hull surface (area-weighted samples, 4 per face)
// within `reach` of the surface it was made from. HACD measures concavity
// from the surface to the hull along the surface's normals, which a flat
// ring does not see: the hull of a bucket's rim is a lid over the whole
// opening, 0 away along the ring's vertical normals (3 of the 4 real
// buckets got one, on which the grippers stood). Such a lid is covered only
// where the ring is (about 0.3); a piece hugging the surface, as HACD's
// bound keeps the rest, about 1.
inline double calcCoverage(const Mesh& piece, const Mesh& surface, double reach) {
  Eigen::Vector3d lo = piece.vertices.front(), hi = lo;
  for (const Eigen::Vector3d& v : piece.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  lo.array() -= reach;
  hi.array() += reach;
  std::vector<std::size_t> near;  // the surface's triangles whose box meets the piece's, grown by reach
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    const auto& tri = surface.triangles[t];
    Eigen::Vector3d tlo = surface.vertices[tri[0]], thi = tlo;
    for (int k = 1; k < 3; ++k) {
      tlo = tlo.cwiseMin(surface.vertices[tri[k]]);
      thi = thi.cwiseMax(surface.vertices[tri[k]]);
    }
    if ((tlo.array() <= hi.array()).all() && (thi.array() >= lo.array()).all()) near.push_back(t);
  }
  const double reach2 = reach * reach;
  double total = 0, covered = 0;
  for (const auto& face : piece.triangles) {
    const Eigen::Vector3d &a = piece.vertices[face[0]], &b = piece.vertices[face[1]], &c = piece.vertices[face[2]];
    const double area = 0.5 * (b - a).cross(c - a).norm();
    if (!(area > 0)) continue;
    const Eigen::Vector3d samples[4] = {(a + b + c) / 3, (4 * a + b + c) / 6, (a + 4 * b + c) / 6, (a + b + 4 * c) / 6};
    for (const Eigen::Vector3d& p : samples) {
      total += area;
      for (const std::size_t t : near) {
        const auto& tri = surface.triangles[t];
        if (calcSquaredDistance(p, surface.vertices[tri[0]], surface.vertices[tri[1]], surface.vertices[tri[2]]) <=
            reach2) {
          covered += area;
          break;
        }
      }
    }
  }
  return total > 0 ? covered / total : 1.0;
}

// The surface's triangles with every vertex in the piece's hull (within
// `tolerance`): the part of the surface a piece was made of.
inline std::vector<uint32_t> findInside(const Mesh& piece, const Mesh& surface, double tolerance) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : piece.vertices) centre += v;
  centre /= double(piece.vertices.size());
  std::vector<std::pair<Eigen::Vector3d, double>> planes;  // outward normal n, offset: n.x <= offset inside
  for (const auto& f : piece.triangles) {
    const Eigen::Vector3d& a = piece.vertices[f[0]];
    Eigen::Vector3d n = (piece.vertices[f[1]] - a).cross(piece.vertices[f[2]] - a);
    if (!(n.norm() > 0)) continue;
    n.normalize();
    if (n.dot(centre - a) > 0) n = -n;
    planes.emplace_back(n, n.dot(a) + tolerance);
  }
  std::vector<uint32_t> inside;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    bool all = true;
    for (int k = 0; k < 3 && all; ++k)
      for (const auto& [n, offset] : planes)
        if (n.dot(surface.vertices[surface.triangles[t][k]]) > offset) {
          all = false;
          break;
        }
    if (all) inside.push_back(uint32_t(t));
  }
  return inside;
}

// `triangles` of `surface` cut in halves at the median of the longest axis
// of their centres until each part spans at most `extent`; each part is one
// piece (its hull is what the host takes).
inline void bisect(const Mesh& surface, std::vector<uint32_t> triangles, double extent, std::vector<Mesh>& out) {
  auto centre = [&](uint32_t t) {
    const auto& tri = surface.triangles[t];
    return Eigen::Vector3d((surface.vertices[tri[0]] + surface.vertices[tri[1]] + surface.vertices[tri[2]]) / 3);
  };
  Eigen::Vector3d lo = surface.vertices[surface.triangles[triangles[0]][0]], hi = lo, clo = centre(triangles[0]),
                  chi = clo;
  for (const uint32_t t : triangles) {
    for (const uint32_t v : surface.triangles[t]) {
      lo = lo.cwiseMin(surface.vertices[v]);
      hi = hi.cwiseMax(surface.vertices[v]);
    }
    clo = clo.cwiseMin(centre(t));
    chi = chi.cwiseMax(centre(t));
  }
  Eigen::Index axis = 0;
  (chi - clo).maxCoeff(&axis);
  if ((hi - lo).maxCoeff() > extent && triangles.size() > 1 && chi[axis] > clo[axis]) {
    const auto middle = triangles.begin() + std::ptrdiff_t(triangles.size() / 2);
    std::nth_element(triangles.begin(), middle, triangles.end(),
                     [&](uint32_t a, uint32_t b) { return centre(a)[axis] < centre(b)[axis]; });
    bisect(surface, std::vector<uint32_t>(triangles.begin(), middle), extent, out);
    bisect(surface, std::vector<uint32_t>(middle, triangles.end()), extent, out);
    return;
  }
  Mesh part;
  std::map<uint32_t, uint32_t> index;
  for (const uint32_t t : triangles) {
    std::array<uint32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = surface.triangles[t][k];
      const auto [it, added] = index.emplace(v, uint32_t(part.vertices.size()));
      if (added) part.vertices.push_back(surface.vertices[v]);
      tri[k] = it->second;
    }
    part.triangles.push_back(tri);
  }
  out.push_back(std::move(part));
}

}  // namespace detail

// Whether `mesh` is convex already: every triangle's plane has all the
// vertices on one side, within `tolerance` of the bounding-box diagonal (a
// hand-made convex piece, ManiSkill's decompositions; not PartNet's open
// cups, whose triangles on one wall see the opposite wall on both sides).
inline bool isConvex(const Mesh& mesh, double tolerance = 1e-4) {
  if (mesh.vertices.empty()) return true;
  Eigen::Vector3d lo = mesh.vertices.front(), hi = lo;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double eps = tolerance * (hi - lo).norm();
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[t[0]];
    const Eigen::Vector3d n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
    const double length = n.norm();
    if (!(length > 0)) continue;
    bool above = false, below = false;
    for (const Eigen::Vector3d& v : mesh.vertices) {
      const double d = n.dot(v - a) / length;
      above |= d > eps;
      below |= d < -eps;
      if (above && below) return false;
    }
  }
  return true;
}

// The convex pieces of `mesh` (each a closed hull: vertices and triangles),
// in the mesh's frame. Throws Error when HACD finds none.
inline std::vector<Mesh> decompose(const Mesh& mesh, const DecompositionOptions& options = {}) {
  const Mesh welded = detail::weld(mesh);
  if (welded.triangles.empty()) throw Error("convex decomposition: the mesh has no triangles", MB_INVALID_ARGUMENT);
  Eigen::Vector3d lo = welded.vertices.front(), hi = lo;
  for (const Eigen::Vector3d& v : welded.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double diagonal = (hi - lo).norm();
  const Mesh simple = detail::simplify(welded, options.max_triangles, diagonal);
  const Mesh solid = options.shell > 0 ? detail::solidify(simple, options.shell * diagonal) : simple;
  // HACD normalises the points in place; it works in units where the
  // diagonal is 2 * scale.
  std::vector<HACD::Vec3<HACD::Real>> points;
  for (const Eigen::Vector3d& v : solid.vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<HACD::Vec3<long>> triangles;
  for (const auto& t : solid.triangles) triangles.emplace_back(long(t[0]), long(t[1]), long(t[2]));
  constexpr double kScale = 1000;
  HACD::HACD hacd;
  hacd.SetScaleFactor(kScale);
  hacd.SetPoints(points.data());
  hacd.SetNPoints(points.size());
  hacd.SetTriangles(triangles.data());
  hacd.SetNTriangles(triangles.size());
  hacd.SetNClusters(options.min_pieces);
  hacd.SetConcavity(options.concavity * 2 * kScale);
  hacd.SetConnectDist(options.connect * 2 * kScale);
  hacd.SetCompacityWeight(0.1);
  hacd.SetVolumeWeight(0.0);
  hacd.SetNVerticesPerCH(options.max_piece_vertices);
  hacd.SetAddExtraDistPoints(true);
  hacd.SetAddFacesPoints(true);
  hacd.SetAddNeighboursDistPoints(false);
  if (!hacd.Compute(false, false) || hacd.GetNClusters() == 0)
    throw Error("convex decomposition: HACD found no pieces", MB_INVALID_ARGUMENT);
  const double reach = options.concavity * diagonal;  // how far HACD lets a hull lie from the surface
  std::vector<Mesh> pieces;
  for (std::size_t c = 0; c < hacd.GetNClusters(); ++c) {
    std::vector<HACD::Vec3<HACD::Real>> hull_points(hacd.GetNPointsCH(c));
    std::vector<HACD::Vec3<long>> hull_triangles(hacd.GetNTrianglesCH(c));
    hacd.GetCH(c, hull_points.data(), hull_triangles.data());
    Mesh piece;
    for (const auto& p : hull_points) piece.vertices.emplace_back(p.X(), p.Y(), p.Z());
    for (const auto& t : hull_triangles) piece.triangles.push_back({uint32_t(t.X()), uint32_t(t.Y()), uint32_t(t.Z())});
    if (piece.vertices.size() < 3) continue;
    // A piece the surface covers too little of (a lid over a rim) is made
    // again of the surface inside it, in parts no longer than 8 concavities
    // (a 9 cm chord of a 17 cm rim reaches 6 mm into the opening). On the 4
    // real buckets: 4 concavities gave 130-331 pieces and 315 env steps/s,
    // 8 118-233 and 400, 16 fewer again but the expert's grip 25/40
    // instead of 31/40.
    if (options.min_coverage > 0 && detail::calcCoverage(piece, solid, reach) < options.min_coverage) {
      const std::vector<uint32_t> inside = detail::findInside(piece, solid, 1e-6 * diagonal);
      if (!inside.empty()) {
        detail::bisect(solid, inside, 8 * reach, pieces);
        continue;
      }
    }
    pieces.push_back(std::move(piece));
  }
  return pieces;
}

// Wavefront OBJ text of a piece (vertices at full precision, faces).
inline std::string writeObj(const Mesh& mesh) {
  std::ostringstream out;
  out.precision(17);
  for (const Eigen::Vector3d& v : mesh.vertices) out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  return out.str();
}

// The pieces of `mesh` as OBJ files (absolute paths, piece_0.obj ...) in
// <cache_root>/convex/<hash of the mesh and options>/, decomposed only when
// that folder is not there complete.
inline std::vector<std::string> decomposeCached(const Mesh& mesh, const std::string& cache_root,
                                                const DecompositionOptions& options = {}) {
  namespace fs = std::filesystem;
  ContentHash hash;
  hash.add(std::string("hacd-3"));  // this header's algorithm and preprocessing
  hash.add(mesh.vertices.data(), mesh.vertices.size() * sizeof(Eigen::Vector3d));
  hash.add(mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]));
  const double numbers[] = {options.concavity, double(options.min_pieces), double(options.max_piece_vertices),
                            options.shell, options.connect, options.min_coverage, double(options.max_triangles)};
  hash.add(numbers, sizeof numbers);
  const fs::path folder = fs::path(cache_root) / "convex" / hash.str();
  if (!isCompleteFolder(folder.string())) {
    // Minutes on a slow machine for a big mesh: a word before, one after.
    std::cerr << "manibench: convex decomposition of a " << mesh.triangles.size()
              << "-triangle mesh (once per machine, cached in " << folder.string() << ")..." << std::endl;
    const auto start = std::chrono::steady_clock::now();
    std::map<std::string, std::string> files;
    const std::vector<Mesh> pieces = decompose(mesh, options);
    std::cerr << "manibench: convex decomposition done: " << pieces.size() << " pieces in " << std::fixed
              << std::setprecision(1) << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
              << " s" << std::defaultfloat << std::endl;
    for (std::size_t k = 0; k < pieces.size(); ++k) files["piece_" + std::to_string(k) + ".obj"] = writeObj(pieces[k]);
    writeFilesOnce(folder.string(), files, "convex decomposition");
  }
  std::vector<std::string> paths;
  for (std::size_t k = 0;; ++k) {
    const fs::path piece = folder / ("piece_" + std::to_string(k) + ".obj");
    if (!fs::exists(piece)) break;
    paths.push_back(piece.string());
  }
  if (paths.empty()) throw Error("convex decomposition: no pieces in " + folder.string(), MB_ERROR);
  return paths;
}

}  // namespace manibench::kit::convex
