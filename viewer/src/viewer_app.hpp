// The viewer's loop: input (keys, mouse) -> steps (real time, paused,
// single steps) -> the scene image (ViewComposer) -> the window with the
// overlay. viewer_app.cpp has the loop and the input, overlay.cpp what the
// overlay shows.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "free_camera.hpp"
#include "session.hpp"
#include "step_clock.hpp"
#include "teleop.hpp"
#include "view_composer.hpp"
#include "window.hpp"

namespace manibench::viewer {

struct ViewerOptions {
  int width = 1280, height = 720;
  bool paused = false;       // --paused
  bool vsync = true;
  std::string screenshot_dir = ".";
  // --measure: the frame rate over this long, then quit; the free camera
  // turns a little every frame, so that every frame renders the scene anew.
  double measure_seconds = 0;
  std::string title;
};

class ViewerApp {
 public:
  // Opens the window first (a missing display fails before anything is
  // built), then takes the session.
  ViewerApp(ViewerOptions options);
  ~ViewerApp();
  // Runs until the window closes, Esc, or a stop signal; returns the exit
  // status. The session is closed (its recording finished) on the way out.
  // `view`: the first view (--camera, --masks, --points).
  int run(Session& session, const ViewSettings& view);

 private:
  void onKey(int key, int action, int mods);
  void onDrag(int button, double dx, double dy, int mods);
  void takeSteps(double now);
  void stepOnce(const Eigen::VectorXd& teleop_action);
  void aimAtRobot();
  void followRobot();
  // The robot's base (base_link when it has one, else its root) and its
  // heading.
  std::optional<Pose> findRobotBase() const;
  void takeScreenshot();
  void drawOverlay();  // overlay.cpp
  void drawTimeline();  // overlay.cpp
  void drawKeymap();    // overlay.cpp
  void reportReplay();
  void finishMeasurement(double now);
  // One frame: the scene image if anything it shows changed, the overlay.
  void drawFrame();
  // Closes the session (the recording's last episode and the file) and
  // says what was recorded.
  void finishSession();

  ViewerOptions options_;
  std::unique_ptr<Window> window_;
  Session* session_ = nullptr;
  std::unique_ptr<Teleop> teleop_;
  std::string teleop_unavailable_;  // why, in Teleop mode without one
  FreeCamera camera_;
  ViewComposer composer_;
  std::unique_ptr<StepClock> clock_;
  ViewSettings view_;
  bool paused_ = false;
  bool follow_ = true;
  bool show_overlay_ = true, show_keymap_ = true;
  std::deque<Eigen::VectorXd> queued_steps_;  // single steps, with the keys held when asked
  std::optional<Eigen::Vector3d> followed_base_;
  uint64_t followed_episode_ = ~0ull;
  double over_since_ = -1;  // when the episode ended (policy mode moves on)
  bool replay_reported_ = false;
  int screenshot_count_ = 0;
  bool wants_screenshot_ = false;
  double now_ = 0;
  // What the last scene image showed: the same again is not rendered again
  // (a paused scene, frames between two steps); the loop then waits for
  // input or the next step instead of spinning.
  struct SceneKey {
    uint64_t episode = ~0ull;
    uint32_t step = 0;
    int camera = 0, width = 0, height = 0;
    bool masks = false, points = false;
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    Eigen::Vector4d orientation = Eigen::Vector4d::Zero();
    bool operator==(const SceneKey& o) const {
      return episode == o.episode && step == o.step && camera == o.camera && width == o.width &&
             height == o.height && masks == o.masks && points == o.points && position == o.position &&
             orientation == o.orientation;
    }
  };
  SceneKey scene_key_;
  double wait_seconds_ = 0;

  // Frame statistics (overlay; --measure).
  // Scene images per second over the last second (frames that show
  // nothing new are not counted).
  double scene_rate_ = 0, rate_window_start_ = -1;
  uint64_t rate_window_frames_ = 0;
  double physics_seconds_ = 0;  // this frame's steps
  struct Totals {
    uint64_t frames = 0, steps = 0;
    double start = -1, physics = 0, render = 0, compose = 0, present = 0;
    double cpu_start = 0;  // the process's CPU seconds (every thread: llvmpipe's too)
  } totals_;
  int exit_status_ = 0;
};

}  // namespace manibench::viewer
