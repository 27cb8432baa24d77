// What the overlay shows (Dear ImGui): the episode (task, object, seed,
// step, reward, every success condition with its value), the mode, real
// time or slower, the view and its mask colours, the recording; the keymap;
// in replays, the timeline.
#include <imgui.h>

#include <cstdio>
#include <string>

#include "viewer_app.hpp"

namespace manibench::viewer {
namespace {

constexpr ImGuiWindowFlags kPanel = ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoSavedSettings |
                                    ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav;
const ImVec4 kGreen(0.45f, 0.9f, 0.45f, 1), kRed(1, 0.4f, 0.35f, 1), kYellow(1, 0.85f, 0.3f, 1),
    kGrey(0.65f, 0.65f, 0.65f, 1);

ImVec4 toImColor(const std::array<std::uint8_t, 3>& c) {
  return ImVec4(c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f, 1);
}

const char* describeMode(SessionMode mode) {
  switch (mode) {
    case SessionMode::Teleop: return "teleoperation";
    case SessionMode::Policy: return "policy";
    case SessionMode::Replay: return "replay";
  }
  return "?";
}

}  // namespace

void ViewerApp::drawOverlay() {
  const Session& s = *session_;
  const Environment& env = s.getEnvironment();
  const TaskDescription& task = env.getTaskDescription();
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.65f);
  ImGui::Begin("episode", nullptr, kPanel);
  ImGui::Text("%s", env.getEnvironmentId().c_str());
  ImGui::Text("object %s   seed %llu", env.getObjectId().c_str(), static_cast<unsigned long long>(env.getSeed()));
  if (s.getMode() == SessionMode::Policy)
    ImGui::Text("%s %s, controller %s", describeMode(s.getMode()), s.getPolicyName().c_str(),
                env.getControllerDescription().name.c_str());
  else if (s.getMode() == SessionMode::Replay)
    ImGui::Text("replay of %s, controller %s", s.getTrajectoryName().c_str(),
                env.getControllerDescription().name.c_str());
  else
    ImGui::Text("%s, controller %s", describeMode(s.getMode()), env.getControllerDescription().name.c_str());
  ImGui::Separator();

  ImGui::Text("step %u / %u   reward %.4f   return %.3f", env.getElapsedSteps(), task.max_episode_steps,
              s.getLastStep().reward, s.getReturn());
  const StepResult& last = s.getLastStep();
  if (ImGui::BeginTable("conditions", 3, ImGuiTableFlags_SizingFixedFit)) {
    for (std::size_t i = 0; i < task.success_conditions.size(); ++i) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(task.success_conditions[i].c_str());
      ImGui::TableNextColumn();
      if (i < last.flags.size())
        ImGui::TextColored(last.flags[i] ? kGreen : kRed, "%s", last.flags[i] ? "yes" : "no");
      else
        ImGui::TextColored(kGrey, "-");
      ImGui::TableNextColumn();
      if (i < last.values.size()) ImGui::Text("%.4g", last.values[i]);
    }
    ImGui::EndTable();
  }
  switch (s.getStatus()) {
    case EpisodeStatus::Running:
      if (paused_) ImGui::TextColored(kYellow, "paused (Space runs, . steps)");
      break;
    case EpisodeStatus::Success: ImGui::TextColored(kGreen, "episode over: success (Backspace, N)"); break;
    case EpisodeStatus::TimeLimit: ImGui::TextColored(kYellow, "episode over: time limit (Backspace, N)"); break;
    case EpisodeStatus::Failed:
      ImGui::PushTextWrapPos(560);
      ImGui::TextColored(kRed, "episode failed: %s", s.getFailure().c_str());
      ImGui::PopTextWrapPos();
      break;
  }
  if (!paused_ && !s.isOver()) {
    const double factor = clock_->getRealTimeFactor();
    if (factor <= 0)
      ImGui::TextColored(kGrey, "physics: measuring");
    else if (factor < 0.95)
      ImGui::TextColored(kRed, "physics %.2fx real time: slower than real time", factor);
    else
      ImGui::Text("physics %.2fx real time", factor);
  }
  ImGui::Text("%.1f scene frames/s (last drawn in %.1f ms)", scene_rate_, 1e3 * composer_.getRenderSeconds());
  ImGui::Separator();

  const CameraRig& rig = env.getObserver().getCameras();
  ImGui::Text("view: %s%s%s%s", view_.camera < 0 ? "free camera" : ("camera " + rig.getMount(std::size_t(view_.camera)).spec.name).c_str(),
              view_.masks ? ", masks" : "", view_.points ? ", point cloud" : "",
              follow_ && view_.camera < 0 ? " (following the robot)" : "");
  if (view_.masks)
    for (std::size_t m = 0; m < task.masks.size(); ++m) {
      ImGui::ColorButton(task.masks[m].c_str(), toImColor(ViewComposer::getMaskColor(m)),
                         ImGuiColorEditFlags_NoTooltip, ImVec2(12, 12));
      ImGui::SameLine();
      ImGui::TextUnformatted(task.masks[m].c_str());
    }
  if (view_.points) ImGui::Text("%zu points (supplement D.1 sample)", composer_.getPointCloud().size());

  if (teleop_) {
    ImGui::Separator();
    const TeleopLayout& layout = teleop_->getLayout();
    std::string arms;
    for (std::size_t a = 0; a < layout.arms.size(); ++a) {
      const bool selected = teleop_->getSelectedArm() < 0 || std::size_t(teleop_->getSelectedArm()) == a;
      arms += (a ? "   " : "") + layout.arms[a].side + (selected ? "*" : "") + " gripper " +
              (teleop_->isGripperOpen(a) ? "open" : "closed");
    }
    ImGui::Text("%s", arms.c_str());
    ImGui::Text("speed %.0f %%%s", 100 * teleop_->getSpeed(), teleop_->isRotating() ? ", rotating" : "");
  } else if (!teleop_unavailable_.empty()) {
    ImGui::Separator();
    ImGui::PushTextWrapPos(560);
    ImGui::TextColored(kYellow, "no teleoperation: %s", teleop_unavailable_.c_str());
    ImGui::PopTextWrapPos();
  }
  if (!s.getRecordPath().empty()) {
    ImGui::Separator();
    ImGui::TextColored(kRed, "recording to %s: %zu episode(s) written", s.getRecordPath().c_str(),
                       s.getRecordedCount());
  }
  ImGui::End();
}

void ViewerApp::drawKeymap() {
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(size.x - 8, 8), ImGuiCond_Always, ImVec2(1, 0));
  ImGui::SetNextWindowBgAlpha(0.55f);
  ImGui::Begin("keys (H hides)", nullptr, kPanel);
  const bool replay = session_->getMode() == SessionMode::Replay;
  std::vector<KeyBinding> keys = {
      {"Space", replay ? "play / pause" : "run / pause"},
      {".  Shift+.", "one step / ten steps"},
  };
  if (replay) {
    keys.push_back({",  Home  End", "step back / first / last state"});
    keys.push_back({"Backspace  N", "from the start / next trajectory"});
  } else {
    keys.push_back({"Backspace  N", "restart / next object"});
    if (!session_->getRecordPath().empty()) keys.push_back({"Shift+Backspace", "restart, not recording this one"});
  }
  keys.insert(keys.end(), {{"C", "next camera (free, task cameras)"},
                           {"M  P", "masks / point cloud"},
                           {"mouse", "drag: orbit, Shift/right drag: pan, wheel: zoom"},
                           {"V  T", "view the robot / follow it"},
                           {"F12", "screenshot"},
                           {"Tab  Esc", "overlay / quit"}});
  if (teleop_) {
    const std::vector<KeyBinding> drive = teleop_->describeKeys();
    keys.insert(keys.end(), drive.begin(), drive.end());
  }
  if (ImGui::BeginTable("keys", 2, ImGuiTableFlags_SizingFixedFit)) {
    for (const KeyBinding& k : keys) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextColored(kYellow, "%s", k.keys.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(k.what.c_str());
    }
    ImGui::EndTable();
  }
  ImGui::End();
}

void ViewerApp::drawTimeline() {
  Session& s = *session_;
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(size.x / 2, size.y - 8), ImGuiCond_Always, ImVec2(0.5f, 1));
  ImGui::SetNextWindowSize(ImVec2(size.x * 0.7f, 0), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.65f);
  ImGui::Begin("timeline", nullptr,
               ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoNav);
  if (ImGui::Button(paused_ ? "play" : "pause")) {
    paused_ = !paused_;
    clock_->restart(now_);
  }
  ImGui::SameLine();
  int t = int(s.getEnvironment().getElapsedSteps());
  ImGui::SetNextItemWidth(-260);
  if (ImGui::SliderInt("##step", &t, 0, int(s.getReplayLength()), "state %d")) {
    paused_ = true;
    s.seek(uint32_t(t));
    replay_reported_ = false;
  }
  ImGui::SameLine();
  ImGui::Text("%s (%zu in the file)", s.getTrajectoryName().c_str(), s.getTrajectoryCount());
  if (s.isReplayExact())
    ImGui::TextColored(kGreen, "bit-identical to the recording so far");
  else
    ImGui::TextColored(kRed, "differs: %s", s.getReplayDivergence().c_str());
  ImGui::End();
}

}  // namespace manibench::viewer
