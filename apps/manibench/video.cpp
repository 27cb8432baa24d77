#include "video.hpp"

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace manibench::cli {
namespace {

std::string shellQuote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

VideoWriter::VideoWriter(const std::string& path, int width, int height, double fps) : path_(path) {
  if (std::system("command -v ffmpeg >/dev/null 2>&1") != 0)
    throw std::runtime_error("--video needs the ffmpeg program (Debian package ffmpeg; "
                             "scripts/install-deps installs it)");
  // A dead ffmpeg must give a write error here, not kill this process.
  std::signal(SIGPIPE, SIG_IGN);
  const std::string command =
      "ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgb24 -s " + std::to_string(width) + "x" +
      std::to_string(height) + " -r " + std::to_string(fps) + " -i - -an -pix_fmt yuv420p " +
      shellQuote(path);
  pipe_ = popen(command.c_str(), "w");
  if (pipe_ == nullptr) throw std::runtime_error("cannot start ffmpeg: " + std::string(std::strerror(errno)));
}

VideoWriter::~VideoWriter() {
  if (pipe_) pclose(pipe_);
}

void VideoWriter::write(const CameraImages& image) {
  const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
  frame_.resize(3 * pixels);
  for (std::size_t p = 0; p < pixels; ++p)
    for (std::size_t c = 0; c < 3; ++c) frame_[3 * p + c] = image.rgba[4 * p + c];
  if (std::fwrite(frame_.data(), 1, frame_.size(), pipe_) != frame_.size())
    throw std::runtime_error("ffmpeg stopped taking frames for " + path_);
  ++frames_;
}

void VideoWriter::close() {
  const int status = pclose(pipe_);
  pipe_ = nullptr;
  if (status != 0)
    throw std::runtime_error("ffmpeg failed to write " + path_ + " (exit status " + std::to_string(status) +
                             ")");
}


EpisodeVideo::EpisodeVideo(Environment& env, const std::string& path, int width, int height)
    : env_(env),
      width_(width),
      height_(height),
      view_(calcThirdPersonView(env.getScene(), env.getTaskDescription().robot_articulation, width, height)),
      writer_(path, width, height,
              env.getTaskDescription().control_frequency / env.getTaskDescription().frame_skip) {}

void EpisodeVideo::aimAtRobot() {
  view_ = calcThirdPersonView(env_.getScene(), env_.getTaskDescription().robot_articulation, width_, height_);
}

void EpisodeVideo::record() {
  env_.updObserver().updRenderer().render(view_.camera, view_.pose, frame_);
  writer_.write(frame_);
}

}  // namespace manibench::cli
