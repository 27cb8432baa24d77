// Headless rasterizer for Scene visuals: one process-wide EGL display and
// OpenGL 3.3+ core context (a GPU through EGL_EXT_platform_device when there
// is one, else Mesa's llvmpipe), and per scene static vertex buffers drawn
// with the link poses of the current step. Each camera gets color, metric
// depth and per-pixel visual/link segmentation; calcCameraPoints turns depth
// into points. Sources: core/render/ (part of manibench_core, which links
// libEGL and libOpenGL privately). Neither EGL nor GL headers leak from here.
//
// Threads and processes: every GL call of the process goes through the one
// context, serialized by a mutex (any thread may render, one at a time). EGL
// does not survive fork(): a worker process must create its renderers after
// the fork; using a context inherited from the parent throws RenderError.
#pragma once

#include <manibench/error.hpp>
#include <manibench/scene.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench {

// EGL could not start, software rendering was refused, the context was
// inherited across fork(), or a GL object could not be created.
class RenderError : public Error {
 public:
  using Error::Error;
};

struct RenderOptions {
  // false: throw RenderError rather than fall back to a software rasterizer
  // (llvmpipe/softpipe), for users who expect their GPU to be used.
  bool allow_software = true;
  // Print the chosen EGL device and GL_RENDERER to stderr when the context
  // is created (once per process).
  bool verbose = false;
  // Index into eglQueryDevicesEXT to use; -1: hardware devices first, then
  // software ones, then Mesa's surfaceless platform.
  int device = -1;
};

// What RenderContext::get chose.
struct RenderDeviceInfo {
  std::string platform;     // "EGL_EXT_platform_device" or "EGL_MESA_platform_surfaceless"
  int device_index = -1;    // index among eglQueryDevicesEXT, -1 on surfaceless
  std::string device;       // e.g. "software (EGL_MESA_device_software)", "/dev/dri/renderD128"
  std::string gl_vendor, gl_renderer, gl_version;
  bool software = false;    // llvmpipe/softpipe/swrast
};

class RenderContext {
 public:
  // The process-wide context, created on the first call with `options`
  // (later calls reuse it; they throw if they refuse software and it is
  // software). Throws RenderError naming what was tried and how to fix it.
  static RenderContext& get(const RenderOptions& options = {});
  // Whether this process (not a parent before fork) has created it.
  static bool exists();

  const RenderDeviceInfo& getInfo() const;
  // One line: platform, device, GL_RENDERER, GL_VERSION.
  std::string describe() const;

  RenderContext(const RenderContext&) = delete;
  RenderContext& operator=(const RenderContext&) = delete;
  ~RenderContext();  // never runs: the display lives until the process ends

  struct Impl;
  Impl& impl() { return *impl_; }  // for core/render only

 private:
  explicit RenderContext(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Camera model (SAPIEN convention): the camera looks along its +x axis with
// +z up (+y left). Square pixels; the horizontal fov follows from the aspect.
struct CameraSpec {
  std::string name;  // keys the camera's framebuffer inside a SceneRenderer
  int width = 400, height = 160;
  double fovy = 1.0471975511965976;  // vertical field of view, rad
  double near = 0.1, far = 10.0;     // clipping distances, m
};

struct DirectionalLight {
  Eigen::Vector3f direction{0, 0, -1};  // direction the light travels, world
  Eigen::Vector3f color{1, 1, 1};       // linear RGB intensity
  bool shadow = false;                  // accepted, not rendered (no shadows yet)
};

struct PointLight {
  Eigen::Vector3f position{0, 0, 0};  // world, m
  Eigen::Vector3f color{1, 1, 1};     // linear RGB intensity at 1 m (falls off with 1/r^2)
};

// color = base * (ambient + sum of Lambert terms) + 0.1 * Blinn-Phong
// specular (exponent 32) per light. No shadows or textures yet. The defaults
// are ManiSkill's: ambient 0.3, two directional lights. Each distinct pair
// of light counts compiles one shader program (changing counts per frame is
// possible but costs a compile the first time).
struct LightingSpec {
  static constexpr int kMaxLights = 8;  // per kind
  Eigen::Vector3f ambient{0.3f, 0.3f, 0.3f};
  std::vector<DirectionalLight> directional{
      {Eigen::Vector3f(1, 1, -1), Eigen::Vector3f(1, 1, 1), true},
      {Eigen::Vector3f(0, 0, -1), Eigen::Vector3f(1, 1, 1), false}};
  std::vector<PointLight> point;
  Eigen::Vector4f background{0, 0, 0, 1};  // color where nothing is hit
  // The scene's ground (Scene::addGround), drawn as an unbounded plane,
  // lit like the visuals, seen from above only. Its pixels have depth but
  // visual and link -1 (background: in no mask). Plain grey by default.
  bool draw_ground = true;
  Eigen::Vector4f ground_color{0.35f, 0.35f, 0.35f, 1};
};

// One camera's images; row 0 is the TOP row, pixel (row, col) at index
// row * width + col.
struct CameraImages {
  std::string camera;
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;  // 4 per pixel, 8-bit, lit color clamped to [0, 1]
  std::vector<float> depth;        // m along the optical axis; 0: nothing hit
  std::vector<std::int32_t> visual;  // index into Scene::getVisualShapes(); -1: background or ground
  std::vector<std::int32_t> link;    // that visual's link id; -1: background or ground
  // Camera pose in the world, SAPIEN frame (x forward, y left, z up).
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();
  // OpenCV intrinsics: u = fx X/Z + cx with X right, Y down, Z forward;
  // pixel (row, col) has its centre at u = col + 0.5, v = row + 0.5.
  Eigen::Matrix3d intrinsic = Eigen::Matrix3d::Identity();
  double near = 0, far = 0;
};

// GL depth d in [0, 1] -> metres along the optical axis of a camera with
// clipping distances `near` and `far`: z = 2 n f / (f + n - (2 d - 1)(f - n)).
inline float calcLinearDepth(float window_depth, double near, double far) {
  return static_cast<float>(2 * near * far /
                            ((far + near) - (2.0 * window_depth - 1.0) * (far - near)));
}

// One camera's framebuffer as OpenGL returns it, for consumers that convert
// only what they need (the observation module): rows run from the BOTTOM
// row up, segmentation as drawn, depth as stored. `CameraImages` is its
// converted form (SceneRenderer::render).
struct RawCameraImages {
  // Segmentation of the ground plane (a hit in no visual); 0 is nothing,
  // visual v is v + 1.
  static constexpr std::uint32_t kGroundSegment = 0xFFFFFFFFu;
  std::string camera;
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;      // 4 per pixel
  std::vector<std::uint32_t> segment;  // per pixel, see kGroundSegment
  std::vector<float> depth;            // window depth in [0, 1] (1: far plane)
  std::uint32_t visual_count = 0;      // segments 1..visual_count are visuals
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d intrinsic = Eigen::Matrix3d::Identity();  // as CameraImages'
  double near = 0, far = 0;

  // Index into the arrays of image pixel (row from the top, col).
  std::size_t getIndex(int row, int col) const {
    return static_cast<std::size_t>(height - 1 - row) * static_cast<std::size_t>(width) +
           static_cast<std::size_t>(col);
  }
  // Whether the pixel at `index` shows a visual or the ground.
  bool isHit(std::size_t index) const {
    const std::uint32_t s = segment[index];
    return s != 0 && (s <= visual_count || s == kGroundSegment) && depth[index] < 1.0f;
  }
  // The visual at a hit pixel's `index` (-1: the ground).
  int getVisual(std::size_t index) const {
    const std::uint32_t s = segment[index];
    return s <= visual_count ? static_cast<int>(s) - 1 : -1;
  }
  // Metres along the optical axis at `index` (0 where nothing was hit).
  float calcDepth(std::size_t index) const {
    return isHit(index) ? calcLinearDepth(depth[index], near, far) : 0.0f;
  }
};

// The world-frame (or, with the identity, camera-frame) point of image
// pixel (row from the top, col) at `depth` metres: the one unprojection of
// calcCameraPoints and the point-cloud observation.
inline Eigen::Vector3f calcPixelPoint(const Eigen::Matrix3d& intrinsic,
                                      const Eigen::Matrix3d& rotation,
                                      const Eigen::Vector3d& translation, int row, int col,
                                      float depth) {
  const double fx = intrinsic(0, 0), fy = intrinsic(1, 1);
  const double cx = intrinsic(0, 2), cy = intrinsic(1, 2);
  const double z = depth;
  // OpenCV ray (right, down, forward) -> SAPIEN camera (forward, left, up).
  const double right = (col + 0.5 - cx) / fx * z, down = (row + 0.5 - cy) / fy * z;
  const Eigen::Vector3d p(z, -right, -down);
  return (rotation * p + translation).cast<float>();
}

// Renders one Scene (which must outlive it). The constructor uploads all
// visual geometry once (build the scene first: render() refuses a scene that
// gained visuals since); render() only reads link poses (the scene must be
// finalized) and draws. Any thread may render; calls are serialized. Not
// copyable; destruction frees the scene's GL objects (buffers, framebuffers;
// shader programs are shared process-wide). Textures and transparency are
// not rendered: each visual is drawn opaque in its material color.
class SceneRenderer {
 public:
  explicit SceneRenderer(const Scene& scene, LightingSpec lighting = {},
                         const RenderOptions& options = {});
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  // Renders `camera` placed at `camera_pose_world` (SAPIEN camera frame)
  // into `out` (resized as needed; reuse it to avoid allocations).
  void render(const CameraSpec& camera, const Pose& camera_pose_world, CameraImages& out);
  // The same in two halves, so that a caller draws every camera of a step
  // before reading any back (a GPU then does not idle between cameras):
  // draw() renders into the camera's own framebuffer, readBack() copies
  // what the last draw() of that camera made into `out` (resized as
  // needed), unconverted. readBack() of a camera never drawn throws.
  void draw(const CameraSpec& camera, const Pose& camera_pose_world);
  void readBack(const CameraSpec& camera, RawCameraImages& out);
  // readBack() of the colour alone (`out`'s segment and depth are left
  // empty): what a window showing the image needs.
  void readBackColor(const CameraSpec& camera, RawCameraImages& out);

  void setLighting(const LightingSpec& lighting);
  const LightingSpec& getLighting() const;
  // Per visual (index into Scene::getVisualShapes()): hide it from every
  // camera (e.g. goal markers), or override its color (config materials;
  // a plain color, its meshes' textures no longer drawn).
  void setVisualVisible(int visual, bool visible);
  void setVisualColor(int visual, const Eigen::Vector4f& rgba);

  // Triangles drawn per camera with every visual visible (primitives as
  // tessellated here, plus mesh triangles; the ground's 2 not included).
  std::size_t getTriangleCount() const;
  // Distinct texture image files uploaded (meshes whose material has a
  // diffuse texture that could be read, docs/rendering.md).
  std::size_t getTextureCount() const;
  const RenderDeviceInfo& getDeviceInfo() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The 3D points of the pixels with depth > 0, in pixel order (row-major from
// the top row): in the camera frame (SAPIEN: x forward, y left, z up) or, if
// `world`, in the world frame. `pixels`, if given, receives each point's
// pixel index (row * width + col) to pick its color or segmentation.
Eigen::Matrix3Xf calcCameraPoints(const CameraImages& images, bool world,
                                  std::vector<int>* pixels = nullptr);

// Camera pose from a look-at: camera at `eye` with its +x toward `target`
// and +z as close to `up` as possible.
Pose calcLookAtPose(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                    const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

}  // namespace manibench
