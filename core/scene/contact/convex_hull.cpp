#include "contact/convex_hull.hpp"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcl/geometry/shape/convex.h>
#include <Eigen/Eigenvalues>
#include <sys/stat.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cassert>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>

#include "contact/qhull_facets.hpp"

namespace manibench {
namespace scene_detail {
namespace {

using SimTK::Vec3;

// Orders a face's vertices counterclockwise about its outward normal.
void orderFaceVertices(const std::vector<Vec3>& vertices, ConvexHull::Face& face) {
  Vec3 center(0);
  for (int v : face.vertices) center += vertices[v];
  center /= static_cast<double>(face.vertices.size());
  const SimTK::UnitVec3 u = face.normal.perp();
  const Vec3 w = SimTK::cross(Vec3(face.normal), Vec3(u));
  std::vector<std::pair<double, int>> by_angle;
  for (int v : face.vertices) {
    const Vec3 r = vertices[v] - center;
    by_angle.emplace_back(std::atan2(SimTK::dot(r, w), SimTK::dot(r, Vec3(u))), v);
  }
  std::sort(by_angle.begin(), by_angle.end());
  for (std::size_t i = 0; i < by_angle.size(); ++i) face.vertices[i] = by_angle[i].second;
}

// Volume, centroid and central inertia of the solid hull at unit density,
// summed over tetrahedra from an interior point to each (fanned) face.
void calcMassProperties(ConvexHull& hull) {
  Vec3 o(0);
  for (const Vec3& v : hull.vertices) o += v;
  o /= static_cast<double>(hull.vertices.size());
  double volume = 0;
  Vec3 first_moment(0);
  SimTK::Mat33 second_moment(0, 0, 0, 0, 0, 0, 0, 0, 0);  // of r r^T about o
  for (const ConvexHull::Face& face : hull.faces) {
    const Vec3 a = hull.vertices[face.vertices[0]] - o;
    for (std::size_t i = 1; i + 1 < face.vertices.size(); ++i) {
      const Vec3 b = hull.vertices[face.vertices[i]] - o;
      const Vec3 c = hull.vertices[face.vertices[i + 1]] - o;
      const double v = SimTK::dot(a, SimTK::cross(b, c)) / 6;
      const Vec3 s = a + b + c;
      volume += v;
      first_moment += v * s / 4;
      second_moment += v / 20 * (a * ~a + b * ~b + c * ~c + s * ~s);
    }
  }
  hull.volume = volume;
  if (!(volume > 0)) return;
  const Vec3 c = first_moment / volume;  // centroid relative to o
  const SimTK::Mat33 identity(1, 0, 0, 0, 1, 0, 0, 0, 1);
  // Inertia about o, then shifted to the centroid.
  // (Not Mat33::trace(): GCC 12 at -O2 miscompiles its strided diagonal
  // view and returns 0.)
  const double trace = second_moment(0, 0) + second_moment(1, 1) + second_moment(2, 2);
  const SimTK::Mat33 I_o = trace * identity - second_moment;
  hull.unit_inertia = I_o - volume * (c.normSqr() * identity - c * ~c);
  hull.centroid = o + c;
}

void buildFclGeometry(ConvexHull& hull) {
  auto vertices = std::make_shared<std::vector<fcl::Vector3d>>();
  for (const Vec3& v : hull.vertices) vertices->emplace_back(v[0], v[1], v[2]);
  auto faces = std::make_shared<std::vector<int>>();
  for (const ConvexHull::Face& face : hull.faces) {
    faces->push_back(static_cast<int>(face.vertices.size()));
    faces->insert(faces->end(), face.vertices.begin(), face.vertices.end());
  }
  hull.fcl_geometry =
      std::make_shared<fcl::Convexd>(vertices, static_cast<int>(hull.faces.size()), faces);
}

}  // namespace

int ConvexHull::findSupportVertex(const SimTK::Vec3& d) const {
  int best = 0;
  double best_value = -SimTK::Infinity;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const double value = SimTK::dot(vertices[i], d);
    if (value > best_value) {
      best_value = value;
      best = static_cast<int>(i);
    }
  }
  return best;
}

std::shared_ptr<const ConvexHull> calcConvexHull(const std::vector<SimTK::Vec3>& points) {
  std::vector<double> xyz;
  xyz.reserve(3 * points.size());
  for (const Vec3& p : points) {
    if (!p.isFinite()) throw std::runtime_error("the mesh has a non-finite vertex");
    xyz.insert(xyz.end(), {p[0], p[1], p[2]});
  }
  std::vector<QhullFacet> facets;
  std::string message;
  switch (runQhull(xyz, facets, message)) {
    case QhullStatus::Ok:
      break;
    case QhullStatus::Flat:
      throw FlatHullError("its points span no volume (" + message + ")");
    case QhullStatus::Failed:
      throw std::runtime_error("Qhull failed: " + message);
  }

  // Keep only hull vertices, in input order (deterministic numbering).
  std::vector<int> index(points.size(), -1);
  for (const QhullFacet& facet : facets)
    for (int p : facet.points) index[p] = 0;
  auto hull = std::make_shared<ConvexHull>();
  for (std::size_t p = 0; p < points.size(); ++p)
    if (index[p] == 0) {
      index[p] = static_cast<int>(hull->vertices.size());
      hull->vertices.push_back(points[p]);
    }
  for (const QhullFacet& facet : facets) {
    ConvexHull::Face face;
    face.normal = SimTK::UnitVec3(Vec3(facet.normal[0], facet.normal[1], facet.normal[2]));
    face.offset = facet.offset;
    for (int p : facet.points) face.vertices.push_back(index[p]);
    orderFaceVertices(hull->vertices, face);
    hull->faces.push_back(std::move(face));
  }

  const std::size_t n = hull->vertices.size();
  hull->vertex_faces.assign(n, {});
  hull->vertex_neighbors.assign(n, {});
  for (std::size_t f = 0; f < hull->faces.size(); ++f) {
    const std::vector<int>& loop = hull->faces[f].vertices;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      hull->vertex_faces[a].push_back(static_cast<int>(f));
      hull->vertex_neighbors[a].push_back(b);
      hull->vertex_neighbors[b].push_back(a);
    }
  }
  for (std::vector<int>& neighbors : hull->vertex_neighbors) {
    std::sort(neighbors.begin(), neighbors.end());
    neighbors.erase(std::unique(neighbors.begin(), neighbors.end()), neighbors.end());
  }

  Vec3 lo(SimTK::Infinity), hi(-SimTK::Infinity);
  for (const Vec3& v : hull->vertices) {
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], v[i]);
      hi[i] = std::max(hi[i], v[i]);
    }
    hull->bounding_radius = std::max(hull->bounding_radius, v.norm());
  }
  hull->box_center = (lo + hi) / 2;
  hull->box_half = (hi - lo) / 2;

  calcMassProperties(*hull);
  if (!(hull->volume > 0)) throw FlatHullError("its hull has no volume");
  buildFclGeometry(*hull);
  return hull;
}

namespace {

// What a mesh file gave, once per process (see the header). When it holds
// more than kMaxEntries, entries nobody else holds are dropped.
template <class T>
class MeshFileCache {
 public:
  template <class Load>
  std::shared_ptr<const T> findOrLoad(const std::string& path, const SimTK::Vec3& scale,
                                      Load load) {
    struct stat info {};
    if (::stat(path.c_str(), &info) != 0) throw std::runtime_error("cannot open the file");
    const Key key{path,
                  scale[0],
                  scale[1],
                  scale[2],
                  static_cast<long long>(info.st_size),
                  static_cast<long long>(info.st_mtim.tv_sec),
                  static_cast<long long>(info.st_mtim.tv_nsec)};
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto found = entries_.find(key);
      if (found != entries_.end()) return found->second;
    }
    // Loaded outside the lock; a concurrent duplicate just does the work
    // twice and both results are identical.
    std::shared_ptr<const T> loaded = load();
    std::lock_guard<std::mutex> lock(mutex_);
    if (entries_.size() >= kMaxEntries)
      for (auto it = entries_.begin(); it != entries_.end();)
        it = it->second.use_count() == 1 ? entries_.erase(it) : std::next(it);
    return entries_.emplace(key, std::move(loaded)).first->second;
  }

 private:
  static constexpr std::size_t kMaxEntries = 1024;
  using Key = std::tuple<std::string, double, double, double, long long, long long, long long>;
  std::mutex mutex_;
  std::map<Key, std::shared_ptr<const T>> entries_;
};

// One reading convention for collision and visual meshes: node transforms
// baked in, Collada in its authored axes (as ROS tools load it).
const aiScene* readMeshFile(Assimp::Importer& importer, const std::string& path,
                            unsigned extra_flags) {
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_PreTransformVertices | extra_flags);
  if (scene == nullptr) throw std::runtime_error(importer.GetErrorString());
  return scene;
}

}  // namespace

std::vector<SimTK::Vec3> loadMeshVertices(const std::string& path, const SimTK::Vec3& scale) {
  Assimp::Importer importer;
  const aiScene* scene = readMeshFile(importer, path, 0);
  std::vector<SimTK::Vec3> points;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      points.emplace_back(p.x * scale[0], p.y * scale[1], p.z * scale[2]);
    }
  }
  if (points.empty()) throw std::runtime_error("the file has no mesh vertices");
  return points;
}

namespace {

std::vector<VisualMesh> readVisualMeshes(const std::string& path, const SimTK::Vec3& scale) {
  Assimp::Importer importer;
  // Points and lines are dropped (a renderer draws surfaces); normals are
  // generated only where the file has none.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      readMeshFile(importer, path,
                   aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_GenSmoothNormals |
                       aiProcess_JoinIdenticalVertices);
  // Normals transform with the inverse scale; a mirroring scale (odd number
  // of negative factors) also flips the winding so faces stay outward.
  const Eigen::Vector3f s(static_cast<float>(scale[0]), static_cast<float>(scale[1]),
                          static_cast<float>(scale[2]));
  const Eigen::Vector3f inverse = s.cwiseInverse();
  const bool mirrored = s[0] * s[1] * s[2] < 0;
  std::string dir;
  const std::size_t slash = path.find_last_of('/');
  if (slash != std::string::npos) dir = path.substr(0, slash + 1);

  std::vector<VisualMesh> meshes;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    VisualMesh out;
    out.positions.reserve(mesh->mNumVertices);
    out.normals.reserve(mesh->mNumVertices);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      out.positions.push_back(Eigen::Vector3f(p.x, p.y, p.z).cwiseProduct(s));
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      if (mesh->HasNormals()) {
        const aiVector3D& a = mesh->mNormals[v];
        n = Eigen::Vector3f(a.x, a.y, a.z).cwiseProduct(inverse);
        const float norm = n.norm();
        n = norm > 0 && std::isfinite(norm) ? Eigen::Vector3f(n / norm) : Eigen::Vector3f::Zero();
      }
      out.normals.push_back(n);
    }
    // Assimp keeps the file's v-up convention (no aiProcess_FlipUVs): the
    // renderer flips rows of the image instead.
    if (mesh->HasTextureCoords(0)) {
      out.texture_coords.reserve(mesh->mNumVertices);
      for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
        const aiVector3D& t = mesh->mTextureCoords[0][v];
        out.texture_coords.emplace_back(t.x, t.y);
      }
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      out.indices.push_back(face.mIndices[0]);
      out.indices.push_back(face.mIndices[mirrored ? 2 : 1]);
      out.indices.push_back(face.mIndices[mirrored ? 1 : 2]);
    }
    if (out.indices.empty()) continue;
    if (mesh->mMaterialIndex < scene->mNumMaterials) {
      const aiMaterial* material = scene->mMaterials[mesh->mMaterialIndex];
      aiColor4D diffuse(1, 1, 1, 1);
      if (material->Get(AI_MATKEY_COLOR_DIFFUSE, diffuse) == AI_SUCCESS)
        out.color = Eigen::Vector4f(diffuse.r, diffuse.g, diffuse.b, 1);
      float opacity = 1;
      if (material->Get(AI_MATKEY_OPACITY, opacity) == AI_SUCCESS) out.color[3] = opacity;
      aiString texture;
      if (material->GetTexture(aiTextureType_DIFFUSE, 0, &texture) == AI_SUCCESS &&
          texture.length > 0) {
        out.texture = texture.C_Str();
        // Embedded textures ("*0") and absolute paths stay as they are;
        // others are relative to the mesh file.
        if (out.texture[0] != '*' && out.texture[0] != '/') out.texture = dir + out.texture;
      }
    }
    meshes.push_back(std::move(out));
  }
  if (meshes.empty()) throw std::runtime_error("the file has no triangles");
  return meshes;
}

}  // namespace

std::shared_ptr<const std::vector<VisualMesh>> loadVisualMeshes(const std::string& path,
                                                                const SimTK::Vec3& scale) {
  static MeshFileCache<std::vector<VisualMesh>> cache;
  return cache.findOrLoad(path, scale, [&] {
    return std::make_shared<const std::vector<VisualMesh>>(readVisualMeshes(path, scale));
  });
}

std::vector<SimTK::Vec3> padThinPoints(const std::vector<SimTK::Vec3>& points, double thickness) {
  if (points.empty()) return points;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Vec3& p : points) mean += Eigen::Vector3d(p[0], p[1], p[2]);
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) {
    const Eigen::Vector3d d = Eigen::Vector3d(p[0], p[1], p[2]) - mean;
    covariance += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  std::vector<Vec3> shifts;  // one per thin direction: half of what it lacks
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d u = solver.eigenvectors().col(axis);
    double lo = SimTK::Infinity, hi = -SimTK::Infinity;
    for (const Vec3& p : points) {
      const double x = u.x() * p[0] + u.y() * p[1] + u.z() * p[2];
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    if (hi - lo < thickness) {
      const double half = (thickness - (hi - lo)) / 2;
      shifts.push_back(Vec3(u.x(), u.y(), u.z()) * half);
    }
  }
  if (shifts.empty()) return points;
  // Every combination of +-shift over the thin directions.
  std::vector<Vec3> out;
  out.reserve(points.size() << shifts.size());
  for (std::size_t signs = 0; signs < (std::size_t(1) << shifts.size()); ++signs)
    for (const Vec3& p : points) {
      Vec3 q = p;
      for (std::size_t k = 0; k < shifts.size(); ++k) q += (signs >> k & 1 ? 1.0 : -1.0) * shifts[k];
      out.push_back(q);
    }
  return out;
}

std::shared_ptr<const ConvexHull> loadConvexHull(const std::string& path,
                                                 const SimTK::Vec3& scale) {
  static MeshFileCache<ConvexHull> cache;
  return cache.findOrLoad(path, scale, [&] {
    return calcConvexHull(padThinPoints(loadMeshVertices(path, scale), kMinHullThickness));
  });
}

}  // namespace scene_detail
}  // namespace manibench
