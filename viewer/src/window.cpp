#include "window.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <X11/Xlib.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <iostream>

#include "image_io.hpp"

namespace manibench::viewer {
namespace {

// teleop.cpp's Shift codes are GLFW's.
static_assert(GLFW_KEY_LEFT_SHIFT == 340 && GLFW_KEY_RIGHT_SHIFT == 344, "GLFW key codes");
static_assert(GLFW_KEY_W == 'W' && GLFW_KEY_1 == '1' && GLFW_KEY_MINUS == '-' && GLFW_KEY_EQUAL == '=',
              "GLFW key codes are ASCII for characters");

std::string g_glfw_error;  // the last GLFW error, for DisplayError
void onGlfwError(int code, const char* description) { g_glfw_error = description ? description : "?"; }

// Xlib calls its I/O error handler when the connection to the X server
// breaks and exits when the handler returns: the window's owner saves what
// it can first.
std::function<void()> g_on_display_lost;
int onDisplayLost(Display*) {
  std::cerr << "manibench: error: the connection to the display was lost (the window was killed or "
               "the X server stopped)\n";
  if (g_on_display_lost) g_on_display_lost();
  std::cout << std::flush;
  std::_Exit(1);
}

Window* getWindow(GLFWwindow* window) { return static_cast<Window*>(glfwGetWindowUserPointer(window)); }

const char* kHeadless =
    "; without one, `manibench render TASK --out DIR` writes the cameras' images, masks and point "
    "clouds, and `manibench render TASK --out DIR --video FILE.mp4 --policy NAME` an episode's video";

}  // namespace

Window::Window(int width, int height, const std::string& title, WindowInput input, bool vsync)
    : input_(std::move(input)) {
  glfwSetErrorCallback(onGlfwError);
  if (glfwInit() != GLFW_TRUE)
    throw DisplayError("the viewer needs a display (" + g_glfw_error + ")" + kHeadless);
  g_on_display_lost = input_.on_display_lost;
  XSetIOErrorHandler(onDisplayLost);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (window_ == nullptr) {
    const std::string why = g_glfw_error;
    glfwTerminate();
    throw DisplayError("the viewer cannot open an OpenGL 3.3 window on this display (" + why +
                       ")" + kHeadless);
  }
  glfwSetWindowUserPointer(window_, this);
  // Ours first: ImGui's backend chains to them.
  glfwSetKeyCallback(window_, onKey);
  glfwSetMouseButtonCallback(window_, onMouseButton);
  glfwSetCursorPosCallback(window_, onCursor);
  glfwSetScrollCallback(window_, onScroll);
  glfwSetWindowFocusCallback(window_, onFocus);
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(vsync ? 1 : 0);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the user's folder
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imgui_ready_ = true;

  glGenFramebuffers(1, &read_framebuffer_);
  glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

Window::~Window() {
  if (window_ == nullptr) return;
  glfwMakeContextCurrent(window_);
  if (read_framebuffer_) glDeleteFramebuffers(1, &read_framebuffer_);
  if (texture_) glDeleteTextures(1, &texture_);
  if (imgui_ready_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  glfwMakeContextCurrent(nullptr);
  glfwDestroyWindow(window_);
  glfwTerminate();
}

bool Window::shouldClose() const { return glfwWindowShouldClose(window_) == GLFW_TRUE; }
void Window::requestClose() { glfwSetWindowShouldClose(window_, GLFW_TRUE); }
void Window::pollEvents() { glfwPollEvents(); }
void Window::waitEvents(double seconds) { glfwWaitEventsTimeout(seconds); }
void Window::getFramebufferSize(int& width, int& height) const {
  glfwGetFramebufferSize(window_, &width, &height);
}
void Window::releaseContext() { glfwMakeContextCurrent(nullptr); }

void Window::onKey(GLFWwindow* window, int key, int, int action, int mods) {
  Window& self = *getWindow(window);
  // A key let go reaches us even when ImGui holds the keyboard, so that no
  // key stays held.
  if (action != GLFW_RELEASE && ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureKeyboard) return;
  if (self.input_.on_key) self.input_.on_key(key, action, mods);
}

void Window::onMouseButton(GLFWwindow* window, int button, int action, int mods) {
  Window& self = *getWindow(window);
  if (action == GLFW_RELEASE) {
    if (button == self.drag_button_) self.drag_button_ = -1;
    return;
  }
  if (ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse) return;
  // The drag starts where the last motion event left the cursor (asking the
  // server now would give where it is after events not yet read).
  self.drag_button_ = button;
}

void Window::onCursor(GLFWwindow* window, double x, double y) {
  Window& self = *getWindow(window);
  const double dx = x - self.cursor_x_, dy = y - self.cursor_y_;
  self.cursor_x_ = x;
  self.cursor_y_ = y;
  if (self.drag_button_ < 0 || !self.input_.on_drag) return;
  int mods = 0;
  if (glfwGetKey(window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS || glfwGetKey(window, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS)
    mods |= GLFW_MOD_SHIFT;
  self.input_.on_drag(self.drag_button_, dx, dy, mods);
}

void Window::onScroll(GLFWwindow* window, double, double dy) {
  Window& self = *getWindow(window);
  if (ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse) return;
  if (self.input_.on_scroll) self.input_.on_scroll(dy);
}

void Window::onFocus(GLFWwindow* window, int focused) {
  Window& self = *getWindow(window);
  if (!focused) {
    self.drag_button_ = -1;
    if (self.input_.on_focus_lost) self.input_.on_focus_lost();
  }
}

void Window::beginFrame(const std::vector<std::uint8_t>* rgba, int width, int height) {
  glfwMakeContextCurrent(window_);
  if (rgba != nullptr) {
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (width != texture_width_ || height != texture_height_) {
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba->data());
      glBindFramebuffer(GL_READ_FRAMEBUFFER, read_framebuffer_);
      glFramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture_, 0);
      glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
      texture_width_ = width;
      texture_height_ = height;
    } else {
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba->data());
    }
  }
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

void Window::endFrame() {
  int width = 0, height = 0;
  glfwGetFramebufferSize(window_, &width, &height);
  ImGui::Render();
  glViewport(0, 0, width, height);
  // The scene, fitted (same aspect; bars where it differs), copied by a
  // blit: as a textured quad under the overlay, presenting took 17.1 ms a
  // frame at 1280x720 on llvmpipe against 12.5 ms (medians of 5 alternated
  // pairs, OpenCabinetDrawer-v0, load 7-7.6: 24.6 -> 29.2 frames/s).
  // Cleared only where bars are.
  const double scale = texture_width_ > 0 && texture_height_ > 0
                           ? std::min(double(width) / texture_width_, double(height) / texture_height_)
                           : 0;
  const int w = int(texture_width_ * scale + 0.5), h = int(texture_height_ * scale + 0.5);
  if (w != width || h != height) {
    glClearColor(0.08f, 0.08f, 0.08f, 1);
    glClear(GL_COLOR_BUFFER_BIT);
  }
  if (w > 0 && h > 0) {
    const int x = (width - w) / 2, y = (height - h) / 2;
    glBindFramebuffer(GL_READ_FRAMEBUFFER, read_framebuffer_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    glBlitFramebuffer(0, 0, texture_width_, texture_height_, x, y, x + w, y + h, GL_COLOR_BUFFER_BIT,
                      GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  }
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  if (!screenshot_path_.empty()) writeScreenshot();
  glfwSwapBuffers(window_);
}

void Window::writeScreenshot() {
  int width = 0, height = 0;
  glfwGetFramebufferSize(window_, &width, &height);
  std::vector<std::uint8_t> bottom_up(std::size_t(width) * std::size_t(height) * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, bottom_up.data());
  std::vector<std::uint8_t> top_down(bottom_up.size());
  const std::size_t row = std::size_t(width) * 3;
  for (int r = 0; r < height; ++r)
    std::copy_n(&bottom_up[std::size_t(height - 1 - r) * row], row, &top_down[std::size_t(r) * row]);
  const std::string path = screenshot_path_;
  screenshot_path_.clear();
  cli::writePng8(path, width, height, 3, top_down);
  last_screenshot_ = path;
}

}  // namespace manibench::viewer
