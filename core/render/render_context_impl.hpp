// Internal to core/render: the process-wide EGL display/context behind
// RenderContext, and the lock every GL user takes.
#pragma once

#include <manibench/renderer.hpp>

#include <EGL/egl.h>

#include <map>
#include <mutex>
#include <utility>
#include <string>
#include <sys/types.h>

namespace manibench {

// A linked shader program and its uniform locations (GLuint, GLint).
struct ShaderProgram {
  unsigned int id = 0;
  int model_view = -1, projection = -1, normal_matrix = -1, color = -1, segment = -1;
  int ambient = -1, directional_to_light = -1, directional_color = -1;
  int point_position = -1, point_color = -1;
  int textured = -1;  // u_textured; the sampler u_texture is unit 0, set at link
};

struct RenderContext::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EGLSurface surface = EGL_NO_SURFACE;  // 1x1 pbuffer only without surfaceless contexts
  pid_t pid = 0;                        // the process that created the display
  RenderDeviceInfo info;
  std::mutex mutex;  // one thread at a time makes the context current and draws
  // Shared by every SceneRenderer (guarded by `mutex`), by light counts:
  // llvmpipe compiles a program's code at its first draw, ~100 ms without
  // Mesa's disk cache, so a scene reset must not mean new programs. Bounded
  // by the (kMaxLights + 1)^2 count pairs; never deleted.
  std::map<std::pair<int, int>, ShaderProgram> programs;
};

// Throws RenderError when this process is not the one that created the
// context (a fork() child): EGL and llvmpipe's threads do not survive fork,
// and touching them would hang. Cheap; call it before any EGL/GL work.
void checkRenderProcess(const RenderContext::Impl& impl, const char* what);

// Holds the context's mutex and keeps the context current on this thread
// for the lock's lifetime (released at the end, so another thread may take
// it next).
class RenderLock {
 public:
  RenderLock(RenderContext::Impl& impl, const char* what);
  ~RenderLock();
  RenderLock(const RenderLock&) = delete;
  RenderLock& operator=(const RenderLock&) = delete;

 private:
  RenderContext::Impl& impl_;
  std::unique_lock<std::mutex> lock_;
};

}  // namespace manibench
