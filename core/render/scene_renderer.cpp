// SceneRenderer: all visual geometry of a scene in one vertex and one index
// buffer (uploaded once), one draw per visual part with a model-view matrix
// from the current link pose; per camera an FBO with RGBA8 color, R32UI
// segmentation (visual index + 1) and 32-bit float depth. Past 600 lines
// because it is one class whose parts (upload, camera targets, draw,
// read-back) share its GL state; the shader program, the textures and the
// context-free camera geometry are shader_program.cpp, texture_cache.cpp
// and camera_geometry.cpp.
#include "render_context_impl.hpp"
#include "shader_program.hpp"
#include "tessellation.hpp"
#include "texture_cache.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <unistd.h>
#include <unordered_map>
#include <cstdio>

namespace manibench {
namespace {

void checkGlError(const char* what) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", error);
    throw RenderError(std::string("OpenGL error ") + code + " in " + what);
  }
}

Eigen::Isometry3d toIsometry(const Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = pose.orientation.normalized().toRotationMatrix();
  t.translation() = pose.position;
  return t;
}

// SAPIEN camera (x forward, y left, z up) -> OpenGL camera (x right, y up,
// looking along -z).
Eigen::Matrix3d getGlFromCameraRotation() {
  Eigen::Matrix3d r;
  r << 0, -1, 0,  //
      0, 0, 1,    //
      -1, 0, 0;
  return r;
}

struct DrawItem {
  int visual = 0;
  GLint base_vertex = 0;
  std::size_t first_index = 0;  // into the index buffer
  GLsizei index_count = 0;
  Eigen::Vector4f color = Eigen::Vector4f::Ones();
  GLuint texture = 0;  // the diffuse texture multiplying color; 0 for none
  bool closed = true;  // primitives: back faces can be culled
};

// Floats per vertex in the vertex buffer: position, normal, texture
// coordinates (0 where a mesh has none; see TextureCache for their v).
constexpr std::size_t kVertexFloats = 8;

// Segmentation value of the ground plane (visuals are index + 1, 0 is
// nothing): it counts as a hit for depth but names no visual.
constexpr std::uint32_t kGroundSegment = RawCameraImages::kGroundSegment;

struct CameraTarget {
  GLuint framebuffer = 0;
  GLuint renderbuffers[3] = {0, 0, 0};  // color, segmentation, depth
  int width = 0, height = 0;
  // What the last draw saw, for its readback.
  bool drawn = false;
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d intrinsic = Eigen::Matrix3d::Identity();
  double near = 0, far = 0;
};

// `raw` as CameraImages: rows flipped to run from the top, depth in
// metres (0 where nothing was hit), visual and link ids.
void convertImages(const RawCameraImages& raw, const std::vector<int>& visual_links,
                   CameraImages& out) {
  const int width = raw.width, height = raw.height;
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  out.camera = raw.camera;
  out.width = width;
  out.height = height;
  out.rgba.resize(pixels * 4);
  out.depth.resize(pixels);
  out.visual.resize(pixels);
  out.link.resize(pixels);
  out.camera_to_world = raw.camera_to_world;
  out.intrinsic = raw.intrinsic;
  out.near = raw.near;
  out.far = raw.far;
  for (int row = 0; row < height; ++row) {
    const std::size_t source = raw.getIndex(row, 0);
    const std::size_t destination = static_cast<std::size_t>(row) * width;
    std::copy_n(raw.rgba.data() + source * 4, static_cast<std::size_t>(width) * 4,
                out.rgba.data() + destination * 4);
    for (int col = 0; col < width; ++col) {
      const std::size_t i = source + static_cast<std::size_t>(col);
      const bool hit = raw.isHit(i);
      out.depth[destination + col] = hit ? calcLinearDepth(raw.depth[i], raw.near, raw.far) : 0.0f;
      const int visual = hit ? raw.getVisual(i) : -1;
      out.visual[destination + col] = visual;
      out.link[destination + col] = visual >= 0 ? visual_links[static_cast<std::size_t>(visual)] : -1;
    }
  }
}

// A mesh's vertices as the vertex buffer holds them (kVertexFloats each).
std::vector<float> interleaveVertices(const VisualMesh& mesh) {
  const bool has_coords = mesh.texture_coords.size() == mesh.positions.size();
  std::vector<float> interleaved;
  interleaved.reserve(mesh.positions.size() * kVertexFloats);
  for (std::size_t k = 0; k < mesh.positions.size(); ++k) {
    const Eigen::Vector3f& p = mesh.positions[k];
    const Eigen::Vector3f n = k < mesh.normals.size() ? mesh.normals[k] : Eigen::Vector3f::UnitZ();
    const Eigen::Vector2f t = has_coords ? mesh.texture_coords[k] : Eigen::Vector2f::Zero();
    // 1 - v: the texture's rows are uploaded top first (TextureCache).
    interleaved.insert(interleaved.end(),
                       {p.x(), p.y(), p.z(), n.x(), n.y(), n.z(), t.x(), 1.0f - t.y()});
  }
  return interleaved;
}

}  // namespace

struct SceneRenderer::Impl {
  const Scene& scene;
  RenderContext::Impl& context;
  LightingSpec lighting;
  GLuint vertex_array = 0, vertex_buffer = 0, index_buffer = 0;
  std::vector<DrawItem> items;
  TextureCache textures;
  DrawItem ground;  // unit square z = 0, |x|, |y| <= 1, facing +z
  std::vector<int> visual_links;    // per visual
  std::vector<char> visual_visible;  // per visual
  std::vector<Eigen::Isometry3d> visual_in_link;
  std::vector<int> links;           // distinct links with visuals
  std::vector<int> link_slot;       // per visual: index into links
  std::size_t triangle_count = 0;
  std::map<std::string, CameraTarget> targets;
  RawCameraImages raw;  // render()'s readback scratch
  std::vector<Eigen::Isometry3d> link_poses;

  Impl(const Scene& s, RenderContext::Impl& c, LightingSpec l)
      : scene(s), context(c), lighting(std::move(l)) {}

  void upload();
  // The vertex array of `vertices` (kVertexFloats each) and `indices`.
  void createBuffers(const std::vector<float>& vertices, const std::vector<std::uint32_t>& indices);
  void releaseGl();
  CameraTarget& getTarget(const CameraSpec& camera);
  const ShaderProgram& getProgram();
  // Throws RenderError for a camera or pose no draw can honour.
  void checkDraw(const CameraSpec& camera, const Pose& camera_pose_world) const;
  // Under the context's lock.
  void draw(const CameraSpec& camera, const Pose& camera_pose_world);
  void readBack(const CameraSpec& camera, RawCameraImages& out, bool color_only = false);
  void setLightUniforms(const ShaderProgram& program, const Eigen::Isometry3d& world_to_view) const;
};

namespace {

void validateLighting(const LightingSpec& lighting) {
  if (lighting.directional.size() > static_cast<std::size_t>(LightingSpec::kMaxLights) ||
      lighting.point.size() > static_cast<std::size_t>(LightingSpec::kMaxLights)) {
    throw RenderError("lighting: at most " + std::to_string(LightingSpec::kMaxLights) +
                      " directional and " + std::to_string(LightingSpec::kMaxLights) +
                      " point lights, got " + std::to_string(lighting.directional.size()) +
                      " and " + std::to_string(lighting.point.size()));
  }
  if (!lighting.ground_color.allFinite() || !lighting.background.allFinite() ||
      !lighting.ambient.allFinite()) {
    throw RenderError("lighting: ambient, background and ground colors must be finite");
  }
  for (std::size_t i = 0; i < lighting.directional.size(); ++i) {
    const Eigen::Vector3f& d = lighting.directional[i].direction;
    if (!d.allFinite() || d.norm() < 1e-9f) {
      throw RenderError("lighting: directional light " + std::to_string(i) +
                        " needs a finite nonzero direction");
    }
  }
}

}  // namespace

void SceneRenderer::Impl::upload() {

  // Gather geometry; identical primitives and shared mesh files once.
  std::vector<float> vertices;
  std::vector<std::uint32_t> indices;
  struct Range {
    GLint base_vertex;
    std::size_t first_index;
    GLsizei count;
  };
  std::map<std::tuple<int, double, double, double>, Range> primitive_ranges;
  std::unordered_map<const VisualMesh*, Range> mesh_ranges;
  // `v`: `stride` floats per vertex (6 without texture coordinates).
  const auto append = [&](const float* v, std::size_t stride, std::size_t vertex_count,
                          const std::uint32_t* idx, std::size_t index_count) {
    Range range{static_cast<GLint>(vertices.size() / kVertexFloats), indices.size(),
                static_cast<GLsizei>(index_count)};
    for (std::size_t k = 0; k < vertex_count; ++k) {
      vertices.insert(vertices.end(), v + k * stride, v + (k + 1) * stride);
      vertices.resize(vertices.size() + (kVertexFloats - stride), 0.0f);
    }
    indices.insert(indices.end(), idx, idx + index_count);
    return range;
  };
  const auto addItem = [&](int visual, const Range& range, const Eigen::Vector4f& color,
                           GLuint texture, bool closed) {
    DrawItem item;
    item.visual = visual;
    item.base_vertex = range.base_vertex;
    item.first_index = range.first_index;
    item.index_count = range.count;
    item.color = color;
    item.texture = texture;
    item.closed = closed;
    items.push_back(item);
  };

  const std::vector<VisualShape>& shapes = scene.getVisualShapes();
  std::map<int, int> slot_of_link;
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    const VisualShape& shape = shapes[i];
    const int visual = static_cast<int>(i);
    visual_links.push_back(shape.link);
    visual_visible.push_back(1);
    visual_in_link.push_back(toIsometry(shape.pose_in_link));
    auto [slot, inserted] = slot_of_link.emplace(shape.link, static_cast<int>(links.size()));
    if (inserted) links.push_back(shape.link);
    link_slot.push_back(slot->second);

    if (shape.kind == VisualShape::Kind::Mesh) {
      if (!shape.meshes) continue;
      for (const VisualMesh& mesh : *shape.meshes) {
        if (mesh.indices.empty()) continue;
        auto found = mesh_ranges.find(&mesh);
        if (found == mesh_ranges.end()) {
          const std::vector<float> interleaved = interleaveVertices(mesh);
          found = mesh_ranges
                      .emplace(&mesh, append(interleaved.data(), kVertexFloats,
                                             mesh.positions.size(), mesh.indices.data(),
                                             mesh.indices.size()))
                      .first;
        }
        // A URDF material replaces the file's, texture included (the
        // visual asked for that color).
        const bool textured = !shape.has_material && !mesh.texture.empty() &&
                              mesh.texture_coords.size() == mesh.positions.size();
        // Mesh files may be open or inconsistently wound: no culling.
        addItem(visual, found->second, shape.has_material ? shape.color : mesh.color,
                textured ? textures.findOrLoad(mesh.texture) : 0, /*closed=*/false);
      }
      continue;
    }
    const auto key = std::make_tuple(static_cast<int>(shape.kind), shape.size.x(),
                                     shape.size.y(), shape.size.z());
    auto found = primitive_ranges.find(key);
    if (found == primitive_ranges.end()) {
      TriangleMesh mesh;
      switch (shape.kind) {
        case VisualShape::Kind::Box:
          mesh = makeBoxMesh(shape.size.x(), shape.size.y(), shape.size.z());
          break;
        case VisualShape::Kind::Sphere: mesh = makeSphereMesh(shape.size.x()); break;
        case VisualShape::Kind::Cylinder:
          mesh = makeCylinderMesh(shape.size.x(), shape.size.y());
          break;
        case VisualShape::Kind::Capsule:
          mesh = makeCapsuleMesh(shape.size.x(), shape.size.y());
          break;
        case VisualShape::Kind::Mesh: break;
      }
      found = primitive_ranges
                  .emplace(key, append(mesh.vertices.data(), 6, mesh.getVertexCount(),
                                       mesh.indices.data(), mesh.indices.size()))
                  .first;
    }
    addItem(visual, found->second, shape.color, /*texture=*/0, /*closed=*/true);
  }
  for (const DrawItem& item : items) triangle_count += static_cast<std::size_t>(item.index_count) / 3;
  // The ground quad, always uploaded (4 vertices): whether it is drawn is
  // decided per render from the scene and the lighting.
  {
    const float quad[] = {-1, -1, 0, 0, 0, 1, 1, -1, 0, 0, 0, 1,
                          1,  1,  0, 0, 0, 1, -1, 1, 0, 0, 0, 1};
    const std::uint32_t quad_indices[] = {0, 1, 2, 0, 2, 3};
    const Range range = append(quad, 6, 4, quad_indices, 6);
    ground.visual = -1;
    ground.base_vertex = range.base_vertex;
    ground.first_index = range.first_index;
    ground.index_count = range.count;
  }
  link_poses.resize(links.size());
  createBuffers(vertices, indices);
}

void SceneRenderer::Impl::createBuffers(const std::vector<float>& vertices,
                                        const std::vector<std::uint32_t>& indices) {
  glGenVertexArrays(1, &vertex_array);
  glBindVertexArray(vertex_array);
  glGenBuffers(1, &vertex_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, vertex_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
               vertices.data(), GL_STATIC_DRAW);
  glGenBuffers(1, &index_buffer);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(),
               GL_STATIC_DRAW);
  const GLsizei stride = kVertexFloats * sizeof(float);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, stride,
                        reinterpret_cast<const void*>(6 * sizeof(float)));
  glBindVertexArray(0);
  checkGlError("uploading the scene's geometry");
}

void SceneRenderer::Impl::releaseGl() {
  for (auto& [name, target] : targets) {
    glDeleteFramebuffers(1, &target.framebuffer);
    glDeleteRenderbuffers(3, target.renderbuffers);
  }
  targets.clear();
  textures.release();
  if (vertex_array != 0) glDeleteVertexArrays(1, &vertex_array);
  if (vertex_buffer != 0) glDeleteBuffers(1, &vertex_buffer);
  if (index_buffer != 0) glDeleteBuffers(1, &index_buffer);
  vertex_array = vertex_buffer = index_buffer = 0;
  // Deletion is deferred until the driver's queue drains; finishing here
  // keeps memory flat across many short-lived scenes.
  glFinish();
}

CameraTarget& SceneRenderer::Impl::getTarget(const CameraSpec& camera) {
  CameraTarget& target = targets[camera.name];
  if (target.framebuffer != 0 && target.width == camera.width && target.height == camera.height) {
    return target;
  }
  if (target.framebuffer != 0) {
    glDeleteFramebuffers(1, &target.framebuffer);
    glDeleteRenderbuffers(3, target.renderbuffers);
  }
  target.width = camera.width;
  target.height = camera.height;
  glGenFramebuffers(1, &target.framebuffer);
  glBindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
  glGenRenderbuffers(3, target.renderbuffers);
  const GLenum formats[3] = {GL_RGBA8, GL_R32UI, GL_DEPTH_COMPONENT32F};
  const GLenum attachments[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_DEPTH_ATTACHMENT};
  for (int k = 0; k < 3; ++k) {
    glBindRenderbuffer(GL_RENDERBUFFER, target.renderbuffers[k]);
    glRenderbufferStorage(GL_RENDERBUFFER, formats[k], camera.width, camera.height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, attachments[k], GL_RENDERBUFFER,
                              target.renderbuffers[k]);
  }
  const GLenum draw_buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glDrawBuffers(2, draw_buffers);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    throw RenderError("camera '" + camera.name + "': framebuffer " +
                      std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                      " incomplete (status " + std::to_string(status) + ")");
  }
  checkGlError("creating a camera framebuffer");
  return target;
}

const ShaderProgram& SceneRenderer::Impl::getProgram() {
  const std::pair<int, int> counts{static_cast<int>(lighting.directional.size()),
                                   static_cast<int>(lighting.point.size())};
  std::map<std::pair<int, int>, ShaderProgram>& programs = context.programs;
  auto found = programs.find(counts);
  if (found != programs.end()) return found->second;
  ShaderProgram program;
  program.id = linkSceneProgram(counts.first, counts.second);
  const auto location = [&](const char* name) { return glGetUniformLocation(program.id, name); };
  program.model_view = location("u_model_view");
  program.projection = location("u_projection");
  program.normal_matrix = location("u_normal_matrix");
  program.color = location("u_color");
  program.segment = location("u_segment");
  program.ambient = location("u_ambient");
  program.directional_to_light = location("u_directional_to_light");
  program.directional_color = location("u_directional_color");
  program.point_position = location("u_point_position");
  program.point_color = location("u_point_color");
  program.textured = location("u_textured");
  glUseProgram(program.id);
  glUniform1i(location("u_texture"), 0);
  glUseProgram(0);
  return programs.emplace(counts, program).first->second;
}

namespace {

// Uploads one kind of light: a vector per light (`vectorOf`: the view-frame
// direction towards it, or its view-frame position) and its color.
template <class Light, class VectorOf>
void setLightArray(int vector_uniform, int color_uniform, const std::vector<Light>& lights, VectorOf vectorOf) {
  if (lights.empty()) return;
  std::vector<float> vectors, colors;
  for (const Light& light : lights) {
    const Eigen::Vector3f v = vectorOf(light);
    vectors.insert(vectors.end(), {v.x(), v.y(), v.z()});
    colors.insert(colors.end(), {light.color.x(), light.color.y(), light.color.z()});
  }
  const auto count = static_cast<GLsizei>(lights.size());
  glUniform3fv(vector_uniform, count, vectors.data());
  glUniform3fv(color_uniform, count, colors.data());
}

}  // namespace

void SceneRenderer::Impl::setLightUniforms(const ShaderProgram& uniforms,
                                           const Eigen::Isometry3d& world_to_view) const {
  glUniform3fv(uniforms.ambient, 1, lighting.ambient.data());
  const Eigen::Matrix3f rotation = world_to_view.linear().cast<float>();
  setLightArray(uniforms.directional_to_light, uniforms.directional_color, lighting.directional,
                [&](const DirectionalLight& light) -> Eigen::Vector3f {
                  return -(rotation * light.direction.normalized());
                });
  setLightArray(uniforms.point_position, uniforms.point_color, lighting.point,
                [&](const PointLight& light) -> Eigen::Vector3f {
                  return (world_to_view * light.position.cast<double>()).cast<float>();
                });
}

SceneRenderer::SceneRenderer(const Scene& scene, LightingSpec lighting,
                             const RenderOptions& options) {
  validateLighting(lighting);
  RenderContext& context = RenderContext::get(options);
  impl_ = std::make_unique<Impl>(scene, context.impl(), std::move(lighting));
  RenderLock lock(impl_->context, "SceneRenderer");
  try {
    impl_->upload();
    impl_->getProgram();
  } catch (...) {
    impl_->releaseGl();
    throw;
  }
}

SceneRenderer::~SceneRenderer() {
  if (!impl_) return;
  // In a fork() child the GL objects belong to the parent's context, which
  // this process cannot touch; its copy of them dies with the process.
  if (impl_->context.pid != getpid()) return;
  try {
    RenderLock lock(impl_->context, "~SceneRenderer");
    impl_->releaseGl();
  } catch (const RenderError&) {
    // Nothing sensible to do in a destructor; the context is process-wide.
  }
}

void SceneRenderer::render(const CameraSpec& camera, const Pose& camera_pose_world,
                           CameraImages& out) {
  impl_->checkDraw(camera, camera_pose_world);
  // Under the lock: this renderer's scratch (and the scene's pose cache) is
  // shared by every thread that renders it.
  RenderLock lock(impl_->context, "SceneRenderer::render");
  impl_->draw(camera, camera_pose_world);
  impl_->readBack(camera, impl_->raw);
  convertImages(impl_->raw, impl_->visual_links, out);
}

void SceneRenderer::draw(const CameraSpec& camera, const Pose& camera_pose_world) {
  impl_->checkDraw(camera, camera_pose_world);
  RenderLock lock(impl_->context, "SceneRenderer::draw");
  impl_->draw(camera, camera_pose_world);
}

void SceneRenderer::Impl::checkDraw(const CameraSpec& camera, const Pose& camera_pose_world) const {
  const Impl& d = *this;
  if (camera.width < 1 || camera.height < 1 || camera.width > 16384 || camera.height > 16384) {
    throw RenderError("camera '" + camera.name + "': size " + std::to_string(camera.width) +
                      "x" + std::to_string(camera.height) + " outside 1..16384");
  }
  if (!(camera.fovy > 0 && camera.fovy < M_PI) || !(camera.near > 0) ||
      !(camera.far > camera.near)) {
    throw RenderError("camera '" + camera.name + "': needs 0 < fovy < pi and 0 < near < far");
  }
  if (!camera_pose_world.position.allFinite() || !camera_pose_world.orientation.coeffs().allFinite() ||
      camera_pose_world.orientation.norm() < 1e-9) {
    throw RenderError("camera '" + camera.name + "': pose is not finite");
  }
  if (d.scene.getVisualShapes().size() != d.visual_links.size()) {
    throw RenderError("camera '" + camera.name + "': the scene has " +
                      std::to_string(d.scene.getVisualShapes().size()) + " visuals, the renderer " +
                      std::to_string(d.visual_links.size()) +
                      "; create the SceneRenderer after the scene is built");
  }
}

void SceneRenderer::readBack(const CameraSpec& camera, RawCameraImages& out) {
  RenderLock lock(impl_->context, "SceneRenderer::readBack");
  impl_->readBack(camera, out);
}

void SceneRenderer::readBackColor(const CameraSpec& camera, RawCameraImages& out) {
  RenderLock lock(impl_->context, "SceneRenderer::readBackColor");
  impl_->readBack(camera, out, /*color_only=*/true);
}

void SceneRenderer::Impl::draw(const CameraSpec& camera, const Pose& camera_pose_world) {
  Impl& d = *this;
  for (std::size_t k = 0; k < d.links.size(); ++k) {
    d.link_poses[k] = toIsometry(d.scene.getLinkPose(d.links[k]));
  }
  CameraTarget& target = d.getTarget(camera);
  const int width = camera.width, height = camera.height;

  const Eigen::Isometry3d camera_to_world = toIsometry(camera_pose_world);
  Eigen::Isometry3d world_to_view = Eigen::Isometry3d::Identity();
  world_to_view.linear() = getGlFromCameraRotation();
  world_to_view = world_to_view * camera_to_world.inverse();

  const double aspect = static_cast<double>(width) / height;
  const double focal = 1.0 / std::tan(camera.fovy / 2);
  const double n = camera.near, f = camera.far;
  Eigen::Matrix4f projection = Eigen::Matrix4f::Zero();
  projection(0, 0) = static_cast<float>(focal / aspect);
  projection(1, 1) = static_cast<float>(focal);
  projection(2, 2) = static_cast<float>(-(f + n) / (f - n));
  projection(2, 3) = static_cast<float>(-2 * f * n / (f - n));
  projection(3, 2) = -1;

  glBindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
  glViewport(0, 0, width, height);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  const Eigen::Vector4f& bg = d.lighting.background;
  const GLfloat background[4] = {bg[0], bg[1], bg[2], bg[3]};
  const GLuint no_visual[4] = {0, 0, 0, 0};
  const GLfloat far_depth = 1.0f;
  glClearBufferfv(GL_COLOR, 0, background);
  glClearBufferuiv(GL_COLOR, 1, no_visual);
  glClearBufferfv(GL_DEPTH, 0, &far_depth);

  const ShaderProgram& program = d.getProgram();
  glUseProgram(program.id);
  glUniformMatrix4fv(program.projection, 1, GL_FALSE, projection.data());
  d.setLightUniforms(program, world_to_view);
  // Untextured until an item has a texture (the program is shared: another
  // renderer may have left u_textured set).
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, 0);
  glUniform1i(program.textured, 0);
  GLuint bound_texture = 0;
  glBindVertexArray(d.vertex_array);
  if (d.lighting.draw_ground && d.scene.hasGround()) {
    // An unbounded plane: a square under the camera reaching past every
    // point of the frustum (far times the corner ray's length), so no edge
    // is ever seen and vertices stay within a few far of the camera.
    const double tan_y = std::tan(camera.fovy / 2), tan_x = tan_y * aspect;
    const double reach = f * std::sqrt(1 + tan_x * tan_x + tan_y * tan_y) * 1.01 + 1.0;
    Eigen::Isometry3d plane = Eigen::Isometry3d::Identity();
    plane.translation() = Eigen::Vector3d(camera_to_world.translation().x(),
                                          camera_to_world.translation().y(),
                                          d.scene.getGroundHeight());
    const Eigen::Affine3d model_view =
        world_to_view * plane * Eigen::Scaling(reach, reach, 1.0);
    const Eigen::Matrix4f mv = model_view.matrix().cast<float>();
    const Eigen::Matrix3f normal_matrix = model_view.linear().inverse().transpose().cast<float>();
    glUniformMatrix4fv(program.model_view, 1, GL_FALSE, mv.data());
    glUniformMatrix3fv(program.normal_matrix, 1, GL_FALSE, normal_matrix.data());
    glUniform4fv(program.color, 1, d.lighting.ground_color.data());
    glUniform1ui(program.segment, kGroundSegment);
    glEnable(GL_CULL_FACE);  // seen from above only, as a half-space's surface
    glDrawElementsBaseVertex(
        GL_TRIANGLES, d.ground.index_count, GL_UNSIGNED_INT,
        reinterpret_cast<const void*>(d.ground.first_index * sizeof(std::uint32_t)),
        d.ground.base_vertex);
  }
  bool culling = false;
  glDisable(GL_CULL_FACE);
  for (const DrawItem& item : d.items) {
    if (!d.visual_visible[static_cast<std::size_t>(item.visual)]) continue;
    const auto v = static_cast<std::size_t>(item.visual);
    const Eigen::Isometry3d model_view =
        world_to_view * d.link_poses[static_cast<std::size_t>(d.link_slot[v])] * d.visual_in_link[v];
    const Eigen::Matrix4f mv = model_view.matrix().cast<float>();
    const Eigen::Matrix3f normal_matrix = model_view.linear().inverse().transpose().cast<float>();
    glUniformMatrix4fv(program.model_view, 1, GL_FALSE, mv.data());
    glUniformMatrix3fv(program.normal_matrix, 1, GL_FALSE, normal_matrix.data());
    glUniform4fv(program.color, 1, item.color.data());
    glUniform1ui(program.segment, static_cast<GLuint>(item.visual + 1));
    if (item.texture != bound_texture) {
      bound_texture = item.texture;
      glBindTexture(GL_TEXTURE_2D, bound_texture);
      glUniform1i(program.textured, bound_texture != 0 ? 1 : 0);
    }
    if (item.closed != culling) {
      culling = item.closed;
      if (culling) glEnable(GL_CULL_FACE); else glDisable(GL_CULL_FACE);
    }
    glDrawElementsBaseVertex(
        GL_TRIANGLES, item.index_count, GL_UNSIGNED_INT,
        reinterpret_cast<const void*>(item.first_index * sizeof(std::uint32_t)), item.base_vertex);
  }
  glBindVertexArray(0);
  glBindTexture(GL_TEXTURE_2D, 0);

  target.drawn = true;
  target.camera_to_world = camera_to_world;
  target.near = n;
  target.far = f;
  const double fy = (height / 2.0) * focal;
  target.intrinsic << fy, 0, width / 2.0,  //
      0, fy, height / 2.0,                 //
      0, 0, 1;
}

void SceneRenderer::Impl::readBack(const CameraSpec& camera, RawCameraImages& out, bool color_only) {
  const auto found = targets.find(camera.name);
  if (found == targets.end() || !found->second.drawn || found->second.width != camera.width ||
      found->second.height != camera.height)
    throw RenderError("camera '" + camera.name + "': read back before it was drawn at " +
                      std::to_string(camera.width) + "x" + std::to_string(camera.height));
  const CameraTarget& target = found->second;
  const int width = target.width, height = target.height;
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  out.rgba.resize(pixels * 4);
  out.segment.resize(color_only ? 0 : pixels);
  out.depth.resize(color_only ? 0 : pixels);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, target.framebuffer);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, out.rgba.data());
  if (!color_only) {
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, width, height, GL_RED_INTEGER, GL_UNSIGNED_INT, out.segment.data());
    glReadPixels(0, 0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, out.depth.data());
  }
  checkGlError("reading a camera back");
  out.camera = camera.name;
  out.width = width;
  out.height = height;
  out.visual_count = static_cast<std::uint32_t>(visual_links.size());
  out.camera_to_world = target.camera_to_world;
  out.intrinsic = target.intrinsic;
  out.near = target.near;
  out.far = target.far;
}

void SceneRenderer::setLighting(const LightingSpec& lighting) {
  validateLighting(lighting);
  impl_->lighting = lighting;
}

const LightingSpec& SceneRenderer::getLighting() const { return impl_->lighting; }

void SceneRenderer::setVisualVisible(int visual, bool visible) {
  if (visual < 0 || static_cast<std::size_t>(visual) >= impl_->visual_visible.size()) {
    throw RenderError("setVisualVisible: visual " + std::to_string(visual) + " out of range 0.." +
                      std::to_string(static_cast<long>(impl_->visual_visible.size()) - 1));
  }
  impl_->visual_visible[static_cast<std::size_t>(visual)] = visible ? 1 : 0;
}

void SceneRenderer::setVisualColor(int visual, const Eigen::Vector4f& rgba) {
  if (visual < 0 || static_cast<std::size_t>(visual) >= impl_->visual_visible.size()) {
    throw RenderError("setVisualColor: visual " + std::to_string(visual) + " out of range 0.." +
                      std::to_string(static_cast<long>(impl_->visual_visible.size()) - 1));
  }
  if (!rgba.allFinite()) throw RenderError("setVisualColor: color is not finite");
  for (DrawItem& item : impl_->items) {
    if (item.visual != visual) continue;
    item.color = rgba;
    item.texture = 0;  // a color replaces the file's material, as a URDF material does
  }
}

std::size_t SceneRenderer::getTriangleCount() const { return impl_->triangle_count; }

std::size_t SceneRenderer::getTextureCount() const { return impl_->textures.getCount(); }

const RenderDeviceInfo& SceneRenderer::getDeviceInfo() const { return impl_->context.info; }

}  // namespace manibench
