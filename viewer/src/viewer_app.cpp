#include "viewer_app.hpp"

#include <GLFW/glfw3.h>  // key and button codes only: the window is window.cpp's
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>

#include "cli.hpp"

namespace manibench::viewer {
namespace {

double cpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

double wallSeconds() {
  static const auto origin = std::chrono::steady_clock::now();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - origin).count();
}

constexpr uint32_t kMaxStepsPerFrame = 4;   // catch-up limit (real time)
constexpr double kWarmUpSeconds = 1.0;      // --measure starts counting after this
constexpr double kPolicyPauseSeconds = 2.0;  // a policy's finished episode stays this long
constexpr int kShiftStepCount = 10;           // Shift+. steps this many

}  // namespace

ViewerApp::ViewerApp(ViewerOptions options) : options_(std::move(options)) {
  WindowInput input;
  input.on_key = [this](int key, int action, int mods) { onKey(key, action, mods); };
  input.on_drag = [this](int button, double dx, double dy, int mods) { onDrag(button, dx, dy, mods); };
  input.on_scroll = [this](double steps) {
    if (view_.camera < 0) camera_.zoom(steps);
  };
  input.on_focus_lost = [this] {
    if (teleop_) teleop_->releaseAll();
  };
  input.on_display_lost = [this] {
    if (session_) finishSession();
  };
  window_ = std::make_unique<Window>(options_.width, options_.height, options_.title, std::move(input),
                                     options_.vsync && options_.measure_seconds <= 0);
}

ViewerApp::~ViewerApp() = default;

std::optional<Pose> ViewerApp::findRobotBase() const {
  const Environment& env = session_->getEnvironment();
  const Scene& scene = env.getScene();
  const int robot = scene.findArticulation(env.getTaskDescription().robot_articulation);
  if (robot < 0) return std::nullopt;
  // The mobile base moves under a fixed root.
  const int base = scene.findLink(robot, "base_link");
  return base >= 0 ? scene.getLinkPose(base) : scene.getRootPose(robot);
}

void ViewerApp::aimAtRobot() {
  const std::optional<Pose> base = findRobotBase();
  if (base) {
    const Eigen::Vector3d x = base->orientation * Eigen::Vector3d::UnitX();
    camera_.aimAtRobot(base->position, std::atan2(x.y(), x.x()));
    followed_base_ = base->position;
  } else {
    camera_.aimAtRobot(Eigen::Vector3d::Zero(), 0);
    followed_base_.reset();
  }
}

void ViewerApp::followRobot() {
  const std::optional<Pose> base = findRobotBase();
  if (follow_ && base && followed_base_) camera_.translate(base->position - *followed_base_);
  followed_base_ = base ? std::optional<Eigen::Vector3d>(base->position) : std::nullopt;
}

void ViewerApp::stepOnce(const Eigen::VectorXd& teleop_action) {
  session_->step(teleop_action);
  ++totals_.steps;
}

void ViewerApp::takeSteps(double now) {
  const auto start = std::chrono::steady_clock::now();
  // The keys held now (zeros without teleoperation; a policy or a replay
  // ignores it).
  const Eigen::VectorXd held =
      teleop_ ? teleop_->calcAction()
              : Eigen::VectorXd::Zero(session_->getEnvironment().getControllerDescription().action_dim);
  while (!queued_steps_.empty()) {
    stepOnce(queued_steps_.front().size() ? queued_steps_.front() : held);
    queued_steps_.pop_front();
  }
  if (!paused_ && !session_->isOver()) {
    const uint32_t due = clock_->takeDueSteps(now);
    uint32_t taken = 0;
    for (; taken < due && !session_->isOver(); ++taken) stepOnce(held);
    clock_->countSteps(taken);
  }
  physics_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  if (session_->isOver()) {
    if (over_since_ < 0) over_since_ = now;
    if (session_->getMode() == SessionMode::Replay) reportReplay();
    // A policy's episodes follow one another (N and Backspace still work).
    if (session_->getMode() == SessionMode::Policy && !paused_ && now - over_since_ > kPolicyPauseSeconds) {
      session_->nextObject();
      clock_->restart(now);
    }
  } else {
    over_since_ = -1;
  }
}

void ViewerApp::reportReplay() {
  if (replay_reported_) return;
  replay_reported_ = true;
  const Session& s = *session_;
  std::cout << s.getTrajectoryName() << ": replayed to its last state (step " << s.getReplayLength()
            << "), ";
  if (s.isReplayExact()) {
    std::cout << "every state bit-identical to the recording\n";
  } else {
    std::cout << "DIFFERS from the recording at " << s.getReplayDivergence() << "\n";
    exit_status_ = 1;
  }
  std::cout << std::flush;
}

void ViewerApp::takeScreenshot() {
  std::filesystem::path path;
  do {
    char name[64];
    std::snprintf(name, sizeof(name), "manibench-view-%03d.png", screenshot_count_++);
    path = std::filesystem::path(options_.screenshot_dir) / name;
  } while (std::filesystem::exists(path));
  window_->requestScreenshot(path.string());
  wants_screenshot_ = true;
}

void ViewerApp::onKey(int key, int action, int mods) {
  const bool shift = (mods & GLFW_MOD_SHIFT) != 0;
  // Repeats step again (a held `.` steps on, and a tap within 20 ms of the
  // last is one more step, not a repeat to drop) and change the speed;
  // held motion keys stay held; nothing else repeats.
  if (action == GLFW_REPEAT) {
    if (key == GLFW_KEY_PERIOD) action = GLFW_PRESS;
    else if (key == GLFW_KEY_MINUS || key == GLFW_KEY_EQUAL) action = GLFW_PRESS;
    else return;
  }
  const bool pressed = action == GLFW_PRESS;
  if (teleop_ && session_->getMode() == SessionMode::Teleop && teleop_->handleKey(key, pressed, shift))
    return;
  if (!pressed) return;
  const bool replay = session_->getMode() == SessionMode::Replay;
  switch (key) {
    case GLFW_KEY_ESCAPE: window_->requestClose(); break;
    case GLFW_KEY_SPACE:
      paused_ = !paused_;
      clock_->restart(now_);
      break;
    case GLFW_KEY_PERIOD: {  // one step (Shift: ten), with the keys held now
      paused_ = true;
      const Eigen::VectorXd action = teleop_ ? teleop_->calcAction() : Eigen::VectorXd();
      for (int i = 0; i < (shift ? kShiftStepCount : 1); ++i) queued_steps_.push_back(action);
      break;
    }
    case GLFW_KEY_COMMA:  // replay: one state back
      if (replay) {
        paused_ = true;
        const uint32_t t = session_->getEnvironment().getElapsedSteps();
        session_->seek(t > 0 ? t - 1 : 0);
        replay_reported_ = false;
      }
      break;
    case GLFW_KEY_HOME:
      if (replay) {
        session_->seek(0);
        replay_reported_ = false;
      }
      break;
    case GLFW_KEY_END:
      if (replay) session_->seek(session_->getReplayLength());
      break;
    case GLFW_KEY_BACKSPACE:  // Shift: the episode is not recorded
      queued_steps_.clear();
      session_->restart(shift);
      replay_reported_ = false;
      clock_->restart(now_);
      break;
    case GLFW_KEY_N:
      queued_steps_.clear();
      session_->nextObject();
      replay_reported_ = false;
      clock_->restart(now_);
      break;
    case GLFW_KEY_C: {
      const int count = int(session_->getEnvironment().getObserver().getCameras().getCount());
      view_.camera = view_.camera + 1 >= count ? -1 : view_.camera + 1;
      break;
    }
    case GLFW_KEY_M: view_.masks = !view_.masks; break;
    case GLFW_KEY_P: view_.points = !view_.points; break;
    case GLFW_KEY_H: show_keymap_ = !show_keymap_; break;
    case GLFW_KEY_TAB: show_overlay_ = !show_overlay_; break;
    case GLFW_KEY_T: follow_ = !follow_; break;
    case GLFW_KEY_V:
      view_.camera = -1;
      aimAtRobot();
      break;
    case GLFW_KEY_F12: takeScreenshot(); break;
    default: break;
  }
}

void ViewerApp::onDrag(int button, double dx, double dy, int mods) {
  if (view_.camera >= 0) return;  // a task camera sits where the task put it
  int height = 0, width = 0;
  window_->getFramebufferSize(width, height);
  if (button == GLFW_MOUSE_BUTTON_LEFT && !(mods & GLFW_MOD_SHIFT))
    camera_.orbit(dx, dy);
  else
    camera_.pan(dx, dy, height);
}

void ViewerApp::finishMeasurement(double now) {
  if (options_.measure_seconds <= 0) return;
  if (totals_.start < 0) {
    if (now < kWarmUpSeconds) return;
    totals_ = Totals();
    totals_.start = now;
    totals_.cpu_start = cpuSeconds();
    return;
  }
  if (now - totals_.start < options_.measure_seconds) return;
  const double seconds = now - totals_.start;
  const double frames = double(std::max<uint64_t>(totals_.frames, 1));
  int width = 0, height = 0;
  window_->getFramebufferSize(width, height);
  std::cout << std::fixed << std::setprecision(1) << "measured " << totals_.frames << " frames (each a new scene image) in "
            << seconds << " s: " << double(totals_.frames) / seconds << " frames/s at " << width << "x"
            << height << " (" << (view_.points ? "point cloud" : view_.masks ? "masks" : "scene")
            << ", " << (view_.camera < 0 ? "free camera" : "task camera") << "); per frame: physics "
            << std::setprecision(2) << 1e3 * totals_.physics / frames << " ms, scene render "
            << 1e3 * totals_.render / frames << " ms, masks/points " << 1e3 * totals_.compose / frames
            << " ms, overlay and present " << 1e3 * totals_.present / frames << " ms, CPU (all threads) "
            << 1e3 * (cpuSeconds() - totals_.cpu_start) / frames << " ms; "
            << totals_.steps << " env steps (" << std::setprecision(2)
            << double(totals_.steps) * clock_->getStepSeconds() / seconds << "x real time)\n"
            << std::flush;
  std::cout.unsetf(std::ios::fixed);
  window_->requestClose();
}

int ViewerApp::run(Session& session, const ViewSettings& view) {
  session_ = &session;
  const Environment& env = session.getEnvironment();
  if (session.getMode() == SessionMode::Teleop) {
    try {
      teleop_ = std::make_unique<Teleop>(findTeleopLayout(env.getControllerDescription()));
    } catch (const InvalidArgument& e) {
      teleop_unavailable_ = e.what();
    }
  }
  const TaskDescription& task = env.getTaskDescription();
  clock_ = std::make_unique<StepClock>(double(task.frame_skip) / task.control_frequency, kMaxStepsPerFrame);
  view_ = view;
  paused_ = options_.paused;
  aimAtRobot();

  cli::StopSignals stop_signals;  // Ctrl-C closes the window as Esc does
  now_ = wallSeconds();
  clock_->restart(now_);
  while (!window_->shouldClose() && !cli::StopSignals::isRequested()) {
    if (wait_seconds_ > 0)
      window_->waitEvents(wait_seconds_);
    else
      window_->pollEvents();
    now_ = wallSeconds();
    takeSteps(now_);
    followRobot();
    if (options_.measure_seconds > 0) camera_.orbit(1, 0);
    drawFrame();
    const double end = wallSeconds();
    if (rate_window_start_ < 0 || end - rate_window_start_ >= 1.0) {
      if (rate_window_start_ >= 0) scene_rate_ = double(rate_window_frames_) / (end - rate_window_start_);
      rate_window_start_ = end;
      rate_window_frames_ = 0;
    }
    finishMeasurement(end);
  }
  if (cli::StopSignals::isRequested()) exit_status_ = 130;
  finishSession();
  return exit_status_;
}

void ViewerApp::drawFrame() {
  Session& session = *session_;
  int width = 0, height = 0;
  window_->getFramebufferSize(width, height);
  width = std::max(width, 16);
  height = std::max(height, 16);
  SceneKey key;
  key.episode = session.getEpisodeCount();
  key.step = session.getEnvironment().getElapsedSteps();
  key.camera = view_.camera;
  key.masks = view_.masks;
  key.points = view_.points;
  key.width = width;
  key.height = height;
  if (view_.camera < 0) {
    const Pose pose = camera_.calcPose();
    key.position = pose.position;
    key.orientation = pose.orientation.coeffs();
  }
  const bool changed = !(key == scene_key_);
  const std::vector<std::uint8_t>* rgba = nullptr;
  int image_width = 0, image_height = 0;
  if (changed) {
    window_->releaseContext();  // the renderer's EGL context goes current
    const ViewImage& image = composer_.compose(session.updEnvironment(), key.episode, view_, camera_, width, height);
    rgba = image.rgba;
    image_width = image.width;
    image_height = image.height;
    scene_key_ = key;
    ++rate_window_frames_;
    ++totals_.frames;
    totals_.render += composer_.getRenderSeconds();
    totals_.compose += composer_.getComposeSeconds();
  }
  const auto present_start = std::chrono::steady_clock::now();
  window_->beginFrame(rgba, image_width, image_height);
  if (show_overlay_) drawOverlay();
  if (show_keymap_) drawKeymap();
  if (session.getMode() == SessionMode::Replay) drawTimeline();
  window_->endFrame();
  if (wants_screenshot_ && !window_->getLastScreenshot().empty()) {
    std::cout << "wrote " << window_->getLastScreenshot() << "\n" << std::flush;
    wants_screenshot_ = false;
  }
  if (changed) {
    totals_.present += std::chrono::duration<double>(std::chrono::steady_clock::now() - present_start).count();
    totals_.physics += physics_seconds_;
  }
  // Nothing new: wait for input, or until the next step is due (at most
  // 1/30 s, for the overlay's clock), instead of drawing the same again.
  const bool running = !paused_ && !session.isOver();
  const double until_step = running ? clock_->getNextStepTime() - wallSeconds() : 1.0;
  wait_seconds_ = changed || !queued_steps_.empty() ? 0 : std::clamp(until_step, 0.0, 1.0 / 30);
}

void ViewerApp::finishSession() {
  Session& session = *session_;
  session.close();
  if (session.getRecordPath().empty()) return;
  const std::size_t n = session.getRecordedCount();
  if (n == 0)
    std::cout << "recorded nothing (no episode had a step): no file " << session.getRecordPath() << "\n";
  else
    std::cout << "recorded " << n << " episode(s) to " << session.getRecordPath() << "\n";
  std::cout << std::flush;
}

}  // namespace manibench::viewer
