// For the viewer's window tests: a virtual X display (Xvfb, started on a
// free display number), the viewer program running on it, and xdotool
// typing into it (XTEST: the events take the X server's real input path,
// as a keyboard's would).
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace manibench::viewer::testing {

class VirtualDisplay {
 public:
  // Starts `Xvfb -displayfd` (screen 1600x900, 24 bits); throws
  // std::runtime_error when it cannot (Xvfb missing: scripts/install-deps).
  VirtualDisplay();
  ~VirtualDisplay();
  VirtualDisplay(const VirtualDisplay&) = delete;
  VirtualDisplay& operator=(const VirtualDisplay&) = delete;
  const std::string& getName() const { return name_; }  // ":12"

 private:
  pid_t pid_ = -1;
  std::string name_;
};

// `xdotool args...` on `display`; returns its standard output (throws when
// it fails).
std::string runXdotool(const VirtualDisplay& display, const std::vector<std::string>& args);

// `manibench view args...` (the built CLI, which runs manibench-view) on
// `display`, its output in files.
class ViewerProcess {
 public:
  ViewerProcess(const VirtualDisplay& display, const std::vector<std::string>& args);
  ~ViewerProcess();  // kills it if still running
  ViewerProcess(const ViewerProcess&) = delete;
  ViewerProcess& operator=(const ViewerProcess&) = delete;

  // Waits until its standard output contains `text` (true) or it exits or
  // `seconds` pass (false).
  bool waitForOutput(const std::string& text, double seconds);
  // Its window (the first X window named "manibench view...") focused and
  // the pointer over it, so that keys go there; returns its id.
  std::string focusWindow(const VirtualDisplay& display);
  // Waits for the exit (killing it after `seconds`); the exit code, or 128 +
  // signal.
  int wait(double seconds);
  void kill(int signal);
  std::string getOut() const;
  std::string getErr() const;
  pid_t getPid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int status_ = -1;
  std::string out_path_, err_path_;
};

}  // namespace manibench::viewer::testing
