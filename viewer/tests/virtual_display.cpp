#include "virtual_display.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace manibench::viewer::testing {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string makeTempPath(const std::string& what) {
  std::string path = "/tmp/manibench_viewer_" + what + "_XXXXXX";
  const int fd = mkstemp(path.data());
  if (fd < 0) throw std::runtime_error("mkstemp failed");
  close(fd);
  return path;
}

[[noreturn]] void execWith(const std::vector<std::string>& argv, const std::string& display) {
  setenv("DISPLAY", display.c_str(), 1);
  std::vector<char*> words;
  std::vector<std::string> copies = argv;
  for (std::string& w : copies) words.push_back(w.data());
  words.push_back(nullptr);
  execvp(words[0], words.data());
  _exit(127);
}

}  // namespace

VirtualDisplay::VirtualDisplay() {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    close(fds[0]);
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, 1);
    dup2(null, 2);
    const std::string fd = std::to_string(fds[1]);
    execlp("Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1600x900x24", "-nolisten", "tcp",
           "-noreset", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(fds[1]);
  // Xvfb writes its display number once it accepts connections.
  std::string number;
  const Clock::time_point start = Clock::now();
  pollfd p{fds[0], POLLIN, 0};
  while (secondsSince(start) < 30 && poll(&p, 1, 30000) > 0) {
    char c = 0;
    if (read(fds[0], &c, 1) != 1 || c == '\n') break;
    number += c;
  }
  close(fds[0]);
  if (number.empty()) {
    ::kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    throw std::runtime_error("Xvfb did not start (Debian's xvfb; scripts/install-deps installs it)");
  }
  name_ = ":" + number;
}

VirtualDisplay::~VirtualDisplay() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGTERM);
  waitpid(pid_, nullptr, 0);
}

std::string runXdotool(const VirtualDisplay& display, const std::vector<std::string>& args) {
  const std::string out_path = makeTempPath("xdotool");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    const int out = open(out_path.c_str(), O_WRONLY | O_TRUNC | O_CREAT, 0600);
    dup2(out, 1);
    std::vector<std::string> argv = {"xdotool"};
    argv.insert(argv.end(), args.begin(), args.end());
    execWith(argv, display.getName());
  }
  int status = 0;
  waitpid(pid, &status, 0);
  const std::string out = readFile(out_path);
  std::remove(out_path.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string command = "xdotool";
    for (const std::string& a : args) command += " " + a;
    throw std::runtime_error(command + " failed (status " + std::to_string(status) + ")");
  }
  return out;
}

ViewerProcess::ViewerProcess(const VirtualDisplay& display, const std::vector<std::string>& args)
    : out_path_(makeTempPath("out")), err_path_(makeTempPath("err")) {
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    const int out = open(out_path_.c_str(), O_WRONLY | O_TRUNC | O_CREAT, 0600);
    const int err = open(err_path_.c_str(), O_WRONLY | O_TRUNC | O_CREAT, 0600);
    dup2(out, 1);
    dup2(err, 2);
    std::vector<std::string> argv = {MANIBENCH_TEST_CLI, "view"};
    argv.insert(argv.end(), args.begin(), args.end());
    execWith(argv, display.getName());
  }
}

ViewerProcess::~ViewerProcess() {
  if (status_ < 0 && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  std::remove(out_path_.c_str());
  std::remove(err_path_.c_str());
}

bool ViewerProcess::waitForOutput(const std::string& text, double seconds) {
  const Clock::time_point start = Clock::now();
  while (secondsSince(start) < seconds) {
    if (getOut().find(text) != std::string::npos) return true;
    int status = 0;
    if (status_ < 0 && waitpid(pid_, &status, WNOHANG) == pid_) status_ = status;
    if (status_ >= 0) return getOut().find(text) != std::string::npos;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

std::string ViewerProcess::focusWindow(const VirtualDisplay& display) {
  std::string id = runXdotool(display, {"search", "--name", "^manibench view"});
  id = id.substr(0, id.find('\n'));
  if (id.empty()) throw std::runtime_error("no viewer window on " + display.getName());
  runXdotool(display, {"windowfocus", id});
  runXdotool(display, {"mousemove", "--window", id, "640", "360"});
  return id;
}

int ViewerProcess::wait(double seconds) {
  const Clock::time_point start = Clock::now();
  while (status_ < 0) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      status_ = status;
      break;
    }
    if (secondsSince(start) > seconds) {
      ::kill(pid_, SIGKILL);
      waitpid(pid_, &status, 0);
      status_ = status;
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return WIFEXITED(status_) ? WEXITSTATUS(status_) : 128 + WTERMSIG(status_);
}

void ViewerProcess::kill(int signal) { ::kill(pid_, signal); }
std::string ViewerProcess::getOut() const { return readFile(out_path_); }
std::string ViewerProcess::getErr() const { return readFile(err_path_); }

}  // namespace manibench::viewer::testing
