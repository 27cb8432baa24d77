// Episode videos (render --video, demos replay --video): a third-person
// camera rendered through the environment's renderer and piped into ffmpeg.
#pragma once

#include <manibench/environment.hpp>
#include <manibench/renderer.hpp>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace manibench::cli {

// Pipes raw RGB frames into ffmpeg, which encodes them to `path`.
class VideoWriter {
 public:
  VideoWriter(const std::string& path, int width, int height, double fps);
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;
  void write(const CameraImages& image);
  void close();
  int getFrameCount() const { return frames_; }

 private:
  std::string path_;
  std::FILE* pipe_ = nullptr;
  std::vector<std::uint8_t> frame_;
  int frames_ = 0;
};

// One episode's video of `env` from a third-person camera at the task's
// control rate (frame_skip control steps per frame).
class EpisodeVideo {
 public:
  EpisodeVideo(Environment& env, const std::string& path, int width, int height);
  // From the front-right, above, framed on the robot and the task's
  // objects where the reset put them (calcThirdPersonView).
  void aimAtRobot();
  // A frame of the current state.
  void record();
  void close() { writer_.close(); }
  int getFrameCount() const { return writer_.getFrameCount(); }

 private:
  Environment& env_;
  int width_, height_;
  ThirdPersonView view_;  // the one third-person view (visual_observer.hpp)
  CameraImages frame_;
  VideoWriter writer_;
};

}  // namespace manibench::cli
