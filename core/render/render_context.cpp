// Headless EGL initialization: EGL_EXT_platform_device (hardware devices
// before software ones), then EGL_MESA_platform_surfaceless; desktop OpenGL
// core profile 4.5, 4.3 or 3.3. One display and context per process, never
// terminated: eglTerminate is per display, not reference counted, and would
// break every other renderer of the process.
#include "render_context_impl.hpp"

#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <cstdio>
#include <cstdlib>
#include <dirent.h>
#include <cstring>
#include <iostream>
#include <sstream>
#include <unistd.h>
#include <utility>
#include <vector>

#ifndef EGL_DRM_RENDER_NODE_FILE_EXT
#define EGL_DRM_RENDER_NODE_FILE_EXT 0x3377
#endif

namespace manibench {
namespace {

bool hasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

const char* getEglErrorName(EGLint error) {
  switch (error) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
  }
}

std::string describeEglError() { return getEglErrorName(eglGetError()); }

// The EGL vendor JSON files GLVND reads by default, or " none".
std::string listVendorFiles() {
  std::string out;
  for (const char* directory : {"/etc/glvnd/egl_vendor.d", "/usr/share/glvnd/egl_vendor.d"}) {
    if (DIR* dir = opendir(directory)) {
      while (const dirent* entry = readdir(dir)) {
        const std::string name = entry->d_name;
        if (name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0) {
          out += std::string(" ") + directory + "/" + name;
        }
      }
      closedir(dir);
    }
  }
  return out.empty() ? " none" : out;
}

bool isSoftwareRenderer(const std::string& renderer) {
  for (const char* name : {"llvmpipe", "softpipe", "swrast", "SWR", "lavapipe"}) {
    if (renderer.find(name) != std::string::npos) return true;
  }
  return false;
}

std::string getGlString(GLenum name) {
  const GLubyte* s = glGetString(name);
  return s != nullptr ? reinterpret_cast<const char*>(s) : "";
}

struct Candidate {
  EGLDisplay display = EGL_NO_DISPLAY;
  RenderDeviceInfo info;
};

// Creates a core-profile context on an initialized display and makes it
// current; false (with the reason in `log`) if none of the versions works.
bool createContext(EGLDisplay display, RenderContext::Impl& out, std::ostringstream& log) {
  if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
    log << "    eglBindAPI(EGL_OPENGL_API) failed: " << describeEglError()
        << " (the driver offers no desktop OpenGL)\n";
    return false;
  }
  const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
  const bool surfaceless = hasExtension(extensions, "EGL_KHR_surfaceless_context");
  const EGLint config_attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                      EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (eglChooseConfig(display, config_attributes, &config, 1, &count) != EGL_TRUE || count < 1) {
    if (!surfaceless || !hasExtension(extensions, "EGL_KHR_no_config_context")) {
      log << "    eglChooseConfig found no OpenGL config: " << describeEglError() << "\n";
      return false;
    }
    config = nullptr;  // EGL_NO_CONFIG_KHR
  }
  for (const std::pair<int, int>& version : {std::pair{4, 5}, {4, 3}, {3, 3}}) {
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, version.first,
                                 EGL_CONTEXT_MINOR_VERSION, version.second,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT) {
      log << "    OpenGL " << version.first << "." << version.second
          << " core context: " << describeEglError() << "\n";
      continue;
    }
    EGLSurface surface = EGL_NO_SURFACE;
    if (!surfaceless && config != nullptr) {
      const EGLint pbuffer[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
      surface = eglCreatePbufferSurface(display, config, pbuffer);
    }
    if (eglMakeCurrent(display, surface, surface, context) != EGL_TRUE) {
      log << "    eglMakeCurrent: " << describeEglError() << "\n";
      if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
      eglDestroyContext(display, context);
      continue;
    }
    out.display = display;
    out.context = context;
    out.surface = surface;
    return true;
  }
  return false;
}

void releaseContext(RenderContext::Impl& impl) {
  eglMakeCurrent(impl.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (impl.surface != EGL_NO_SURFACE) eglDestroySurface(impl.display, impl.surface);
  eglDestroyContext(impl.display, impl.context);
  impl.display = EGL_NO_DISPLAY;
  impl.context = EGL_NO_CONTEXT;
  impl.surface = EGL_NO_SURFACE;
}

// Fills the GL part of `info` from the current context; false (logged) when
// software is refused and this is software.
bool acceptRenderer(RenderContext::Impl& impl, const RenderOptions& options,
                    std::ostringstream& log) {
  impl.info.gl_vendor = getGlString(GL_VENDOR);
  impl.info.gl_renderer = getGlString(GL_RENDERER);
  impl.info.gl_version = getGlString(GL_VERSION);
  impl.info.software = impl.info.software || isSoftwareRenderer(impl.info.gl_renderer);
  log << "    GL_RENDERER " << impl.info.gl_renderer << ", GL_VERSION " << impl.info.gl_version
      << "\n";
  if (impl.info.software && !options.allow_software) {
    log << "    refused: software rendering is not allowed\n";
    releaseContext(impl);
    return false;
  }
  return true;
}

std::unique_ptr<RenderContext::Impl> createRenderContext(const RenderOptions& options) {
  auto impl = std::make_unique<RenderContext::Impl>();
  std::ostringstream log;
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client == nullptr) {
    log << "  libEGL offers no client extensions (" << describeEglError()
        << "): it is not GLVND's libEGL 1.5, or no vendor library loaded\n";
  }
  auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));

  // 1) One EGLDevice per GPU (NVIDIA, Mesa render nodes) plus Mesa's
  //    software device: hardware first.
  if (getPlatformDisplay != nullptr && hasExtension(client, "EGL_EXT_platform_device") &&
      hasExtension(client, "EGL_EXT_device_enumeration")) {
    auto queryDevices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto queryDeviceString = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    std::vector<EGLDeviceEXT> devices(32);
    EGLint device_count = 0;
    if (queryDevices == nullptr || queryDeviceString == nullptr ||
        queryDevices(static_cast<EGLint>(devices.size()), devices.data(), &device_count) !=
            EGL_TRUE) {
      log << "  EGL_EXT_platform_device: eglQueryDevicesEXT failed: " << describeEglError()
          << "\n";
      device_count = 0;
    } else if (device_count == 0) {
      log << "  EGL_EXT_platform_device: no EGL devices\n";
    }
    std::vector<int> order;
    std::vector<int> software;
    for (int i = 0; i < device_count; ++i) {
      const bool is_software =
          hasExtension(queryDeviceString(devices[i], EGL_EXTENSIONS), "EGL_MESA_device_software");
      if (options.device >= 0 && options.device != i) continue;
      (is_software ? software : order).push_back(i);
    }
    if (options.device >= device_count) {
      log << "  EGL_EXT_platform_device: device " << options.device << " requested, only "
          << device_count << " found\n";
    }
    order.insert(order.end(), software.begin(), software.end());
    for (int i : order) {
      const char* device_extensions = queryDeviceString(devices[i], EGL_EXTENSIONS);
      RenderDeviceInfo info;
      info.platform = "EGL_EXT_platform_device";
      info.device_index = i;
      info.software = hasExtension(device_extensions, "EGL_MESA_device_software");
      if (info.software) {
        info.device = "software (EGL_MESA_device_software)";
      } else if (hasExtension(device_extensions, "EGL_EXT_device_drm_render_node")) {
        const char* node = queryDeviceString(devices[i], EGL_DRM_RENDER_NODE_FILE_EXT);
        info.device = node != nullptr ? node : "DRM render node";
      } else if (hasExtension(device_extensions, "EGL_EXT_device_drm")) {
        const char* file = queryDeviceString(devices[i], EGL_DRM_DEVICE_FILE_EXT);
        info.device = file != nullptr ? file : "DRM device";
      } else {
        info.device = "hardware device";
      }
      log << "  EGL_EXT_platform_device device " << i << " (" << info.device << "):\n";
      if (info.software && !options.allow_software) {
        log << "    skipped: software rendering is not allowed\n";
        continue;
      }
      EGLDisplay display = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
      EGLint major = 0, minor = 0;
      if (display == EGL_NO_DISPLAY || eglInitialize(display, &major, &minor) != EGL_TRUE) {
        log << "    eglInitialize: " << describeEglError() << "\n";
        continue;
      }
      impl->info = info;
      if (createContext(display, *impl, log) && acceptRenderer(*impl, options, log)) {
        impl->pid = getpid();
        return impl;
      }
      // The display stays initialized: EGL displays are shared process-wide.
    }
  } else {
    log << "  EGL_EXT_platform_device: not offered by libEGL\n";
  }

  // 2) Mesa's surfaceless platform (a render node if usable, else llvmpipe).
  if (options.device >= 0) {
    log << "  EGL_MESA_platform_surfaceless: skipped, a device index was requested\n";
  } else if (getPlatformDisplay != nullptr &&
             hasExtension(client, "EGL_MESA_platform_surfaceless")) {
    log << "  EGL_MESA_platform_surfaceless:\n";
    EGLDisplay display =
        getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (display == EGL_NO_DISPLAY || eglInitialize(display, &major, &minor) != EGL_TRUE) {
      log << "    eglInitialize: " << describeEglError() << "\n";
    } else {
      impl->info = RenderDeviceInfo{};
      impl->info.platform = "EGL_MESA_platform_surfaceless";
      impl->info.device = "Mesa surfaceless";
      if (createContext(display, *impl, log) && acceptRenderer(*impl, options, log)) {
        impl->pid = getpid();
        return impl;
      }
    }
  } else {
    log << "  EGL_MESA_platform_surfaceless: not offered by libEGL\n";
  }

  // GLVND finds vendor libraries through JSON files; name what it can see.
  const char* vendor_override = std::getenv("__EGL_VENDOR_LIBRARY_FILENAMES");
  if (vendor_override != nullptr) {
    log << "  __EGL_VENDOR_LIBRARY_FILENAMES=" << vendor_override << "\n";
  } else {
    log << "  GLVND vendor files:" << listVendorFiles() << "\n";
  }
  log << "  EGL client extensions: " << (client != nullptr ? client : "(none)") << "\n";
  std::string message =
      options.allow_software
          ? "cannot start headless OpenGL through EGL; tried:\n"
          : "no hardware OpenGL device through EGL (software rendering refused); tried:\n";
  message += log.str();
  message +=
      "To fix: a GPU needs its vendor's EGL library registered with GLVND (NVIDIA: the "
      "driver's libEGL_nvidia and /usr/share/glvnd/egl_vendor.d/10_nvidia.json; in a "
      "container NVIDIA_DRIVER_CAPABILITIES must include 'graphics'); software rendering needs "
      "Mesa: Debian packages libegl1 libegl-mesa0 libgl1-mesa-dri libopengl0 and "
      "/usr/share/glvnd/egl_vendor.d/50_mesa.json. __EGL_VENDOR_LIBRARY_FILENAMES selects a "
      "vendor JSON; EGL_LOG_LEVEL=debug makes Mesa explain its failures.";
  if (!options.allow_software) {
    message += " Or allow software rendering (llvmpipe, slow).";
  }
  throw RenderError(message);
}

// The context lives until the process ends (never deleted: no destructor
// may touch EGL at exit, when a fork child or driver threads may be gone).
RenderContext* g_context = nullptr;
std::mutex g_context_mutex;

}  // namespace

void checkRenderProcess(const RenderContext::Impl& impl, const char* what) {
  const pid_t self = getpid();
  if (impl.pid == self) return;
  throw RenderError(std::string(what) + ": the OpenGL context was created by process " +
                    std::to_string(impl.pid) + ", and this is process " +
                    std::to_string(self) +
                    " (a fork() child). EGL does not survive fork(); create the renderer in "
                    "the worker after forking (or start workers with exec/posix_spawn).");
}

RenderLock::RenderLock(RenderContext::Impl& impl, const char* what) : impl_(impl) {
  checkRenderProcess(impl, what);  // before the mutex: a fork may have copied it locked
  lock_ = std::unique_lock<std::mutex>(impl.mutex);
  if (eglGetCurrentContext() != impl.context &&
      eglMakeCurrent(impl.display, impl.surface, impl.surface, impl.context) != EGL_TRUE) {
    throw RenderError(std::string(what) + ": eglMakeCurrent failed: " + describeEglError());
  }
}

RenderLock::~RenderLock() {
  eglMakeCurrent(impl_.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

RenderContext::RenderContext(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RenderContext::~RenderContext() = default;

RenderContext& RenderContext::get(const RenderOptions& options) {
  std::lock_guard<std::mutex> guard(g_context_mutex);
  if (g_context != nullptr) {
    checkRenderProcess(*g_context->impl_, "RenderContext::get");
    if (g_context->impl_->info.software && !options.allow_software) {
      throw RenderError(
          "software rendering refused, but this process already renders in software with " +
          g_context->describe());
    }
    return *g_context;
  }
  std::unique_ptr<Impl> impl = createRenderContext(options);
  // Leave it current on no thread: RenderLock binds it where it is used.
  eglMakeCurrent(impl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  g_context = new RenderContext(std::move(impl));
  if (options.verbose) std::cerr << "manibench: rendering with " << g_context->describe() << "\n";
  return *g_context;
}

bool RenderContext::exists() {
  std::lock_guard<std::mutex> guard(g_context_mutex);
  return g_context != nullptr && g_context->impl_->pid == getpid();
}

const RenderDeviceInfo& RenderContext::getInfo() const { return impl_->info; }

std::string RenderContext::describe() const {
  const RenderDeviceInfo& info = impl_->info;
  std::string out = info.platform;
  if (info.device_index >= 0) out += " device " + std::to_string(info.device_index);
  out += " (" + info.device + "), GL_RENDERER " + info.gl_renderer + ", OpenGL " +
         info.gl_version;
  if (info.software) out += " [software]";
  return out;
}

}  // namespace manibench
