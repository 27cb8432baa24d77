// The viewer's window: GLFW (X11, an OpenGL 3.3 core context through GLX)
// and Dear ImGui for the overlay. The scene is not drawn here: the core's
// SceneRenderer draws it offscreen through its own EGL context, and the
// window shows the image as a texture under the overlay (docs/viewer.md:
// why a blit rather than a shared context). Only one context may be
// current on a thread across GLX and EGL (libglvnd refuses otherwise), so
// the window releases its context while the scene renders
// (releaseContext) and takes it back to present (beginFrame).
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

struct GLFWwindow;

namespace manibench::viewer {

// No display (DISPLAY unset, the X server unreachable, no GLX): the
// message says so in one line and names the headless way.
class DisplayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Input the window passes on (ImGui's widgets get the keyboard and mouse
// first when they want them).
struct WindowInput {
  // GLFW key codes and actions (GLFW_RELEASE, GLFW_PRESS, GLFW_REPEAT: a
  // key held, or one pressed again within 20 ms of its release, which
  // GLFW takes for the X server's autorepeat).
  std::function<void(int key, int action, int mods)> on_key;
  std::function<void(int button, double dx, double dy, int mods)> on_drag;
  std::function<void(double steps)> on_scroll;
  std::function<void()> on_focus_lost;
  // The X connection broke (the window was killed, the server went away):
  // the last chance to save anything; the process then exits with 1.
  std::function<void()> on_display_lost;
};

class Window {
 public:
  // Opens the window (throws DisplayError without a display). `vsync`:
  // present at the display's rate (off for measuring frame rates).
  Window(int width, int height, const std::string& title, WindowInput input, bool vsync);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  bool shouldClose() const;
  void requestClose();
  void pollEvents();
  // Waits for input at most `seconds` (nothing to draw until then).
  void waitEvents(double seconds);
  // The drawable size in pixels.
  void getFramebufferSize(int& width, int& height) const;

  // No context of this window current on the thread (before EGL renders).
  void releaseContext();
  // Makes the context current, uploads the scene image (RGBA, rows from
  // the bottom up; nullptr: the last one again) and starts an ImGui frame:
  // build the overlay after it.
  void beginFrame(const std::vector<std::uint8_t>* rgba, int width, int height);
  // Copies the scene image fitted into the window (letterboxed, nearest
  // texels: a task camera's pixels as the policy gets them), then draws the
  // overlay; writes the screenshot when one was asked for; presents.
  void endFrame();
  // The next endFrame writes what it shows (scene and overlay) to `path`
  // as an RGB PNG.
  void requestScreenshot(const std::string& path) { screenshot_path_ = path; }
  // The path of the last screenshot written (empty: none yet).
  const std::string& getLastScreenshot() const { return last_screenshot_; }

 private:
  static void onKey(GLFWwindow* window, int key, int scancode, int action, int mods);
  static void onMouseButton(GLFWwindow* window, int button, int action, int mods);
  static void onCursor(GLFWwindow* window, double x, double y);
  static void onScroll(GLFWwindow* window, double dx, double dy);
  static void onFocus(GLFWwindow* window, int focused);
  void writeScreenshot();

  GLFWwindow* window_ = nullptr;
  WindowInput input_;
  unsigned int texture_ = 0, read_framebuffer_ = 0;  // the scene image, and a framebuffer to blit it from
  int texture_width_ = 0, texture_height_ = 0;
  int drag_button_ = -1;
  double cursor_x_ = 0, cursor_y_ = 0;
  std::string screenshot_path_, last_screenshot_;
  bool imgui_ready_ = false;
};

}  // namespace manibench::viewer
