// Observation-mode conversion of a demonstration file in forked workers:
// worker k converts trajectories k, k + W, ... into a part file of its own
// (its own environment and EGL context, created after the fork), telling
// the parent over a pipe which ones it finished; the parent then copies the
// parts into the output in the input's order. A worker that dies costs only
// the trajectories it had not finished.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <manibench/demos.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

namespace manibench {
namespace {

// One line per trajectory on the pipe: "ok INDEX" or "error INDEX WHY".
void sendLine(int fd, const std::string& line) {
  const std::string text = line + "\n";
  std::size_t sent = 0;
  while (sent < text.size()) {
    const ssize_t n = ::write(fd, text.data() + sent, text.size() - sent);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    sent += std::size_t(n);
  }
}

std::string oneLine(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

[[noreturn]] void runConversionWorker(const PluginRegistry& registry, const std::string& in_path,
                                      const std::string& part_path,
                                      const std::vector<std::string>& overrides,
                                      const std::vector<std::string>& names,
                                      const std::vector<std::size_t>& mine,
                                      const DemoFileInfo& out_info, int fd) {
  int status = 0;
  try {
    const DemoReader reader(in_path);
    const std::unique_ptr<Environment> env = makeDemoEnvironment(registry, reader.getInfo(), overrides);
    DemoWriter writer(part_path, out_info, mine.size());
    for (std::size_t index : mine) {
      try {
        const Trajectory converted = convertTrajectory(*env, reader.read(names[index]));
        writer.append(converted);
        sendLine(fd, "ok " + std::to_string(index));
      } catch (const std::exception& e) {
        sendLine(fd, "error " + std::to_string(index) + " " + oneLine(e.what()));
      }
    }
    writer.close();
  } catch (const std::exception& e) {
    sendLine(fd, "fatal " + oneLine(e.what()));
    status = 1;
  }
  std::fflush(nullptr);
  _exit(status);
}

}  // namespace

ConversionResult convertDemonstrations(const PluginRegistry& registry, const std::string& in_path,
                                       const std::string& out_path,
                                       const std::vector<std::string>& overrides,
                                       const std::vector<std::string>& selected, unsigned workers,
                                       const DemoFileInfo& out_info_base, const ConversionHooks& hooks) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  if (workers < 1 || workers > 256) throw DemoError("the number of workers must be 1 to 256");
  std::vector<std::string> names;
  DemoFileInfo out_info = out_info_base;
  {
    // Read what is needed and close the file before forking: HDF5's handles
    // do not cross a fork.
    const DemoReader reader(in_path);
    // The output's configuration is the input's with the overrides: what
    // its replays build.
    const ConfigNode config = calcDemoConfig(registry, reader.getInfo(), overrides);
    out_info.config = formatConfig(config);
    out_info.observation_mode = calcEnvironmentOptions(config).observation.mode;
    const std::vector<std::string>& all = reader.getTrajectoryNames();
    names = selected.empty() ? all : selected;
    for (const std::string& name : names)
      if (std::find(all.begin(), all.end(), name) == all.end())
        throw DemoError("'" + in_path + "' has no trajectory " + name);
  }
  workers = unsigned(std::min<std::size_t>(workers, std::max<std::size_t>(1, names.size())));

  struct Child {
    pid_t pid = -1;
    int fd = -1;
    std::string buffer, part, fatal;
    std::vector<std::size_t> done;  // input indices, in the order written to the part
  };
  std::vector<Child> children(workers);
  ConversionResult result;
  std::map<std::size_t, std::string> errors;
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  for (unsigned k = 0; k < workers; ++k) {
    Child& c = children[k];
    c.part = out_path + ".part" + std::to_string(k);
    std::vector<std::size_t> mine;
    for (std::size_t i = k; i < names.size(); i += workers) mine.push_back(i);
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) throw DemoError(std::string("cannot create a pipe: ") + std::strerror(errno));
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) throw DemoError(std::string("cannot fork a worker: ") + std::strerror(errno));
    if (pid == 0) {
      close(fds[0]);
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(1);
      signal(SIGINT, SIG_IGN);  // the parent decides
      runConversionWorker(registry, in_path, c.part, overrides, names, mine, out_info, fds[1]);
    }
    close(fds[1]);
    c.pid = pid;
    c.fd = fds[0];
  }

  std::size_t finished = 0;
  auto handleLine = [&](Child& c, const std::string& line) {
    std::istringstream in(line);
    std::string word;
    std::size_t index = 0;
    in >> word;
    if (word == "fatal") {
      c.fatal = line.substr(6);
      return;
    }
    in >> index;
    ++finished;
    if (word == "ok") {
      c.done.push_back(index);
    } else {
      std::string why;
      std::getline(in, why);
      errors[index] = why.empty() ? why : why.substr(1);
    }
    if (hooks.on_progress) hooks.on_progress(finished, names.size(), elapsed());
  };
  for (;;) {
    if (hooks.should_stop && hooks.should_stop() && !result.interrupted) {
      result.interrupted = true;
      for (Child& c : children)
        if (c.pid > 0) ::kill(c.pid, SIGKILL);
    }
    std::vector<pollfd> fds;
    std::vector<Child*> owners;
    for (Child& c : children)
      if (c.fd >= 0) {
        fds.push_back({c.fd, POLLIN, 0});
        owners.push_back(&c);
      }
    if (fds.empty()) break;
    if (poll(fds.data(), fds.size(), 200) < 0 && errno != EINTR)
      throw DemoError(std::string("poll failed: ") + std::strerror(errno));
    for (std::size_t k = 0; k < fds.size(); ++k) {
      if (!(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      Child& c = *owners[k];
      char chunk[4096];
      const ssize_t got = ::read(c.fd, chunk, sizeof(chunk));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        close(c.fd);
        c.fd = -1;
        int status = 0;
        while (waitpid(c.pid, &status, 0) < 0 && errno == EINTR) {
        }
        c.pid = -1;
        continue;
      }
      c.buffer.append(chunk, std::size_t(got));
      for (std::size_t end; (end = c.buffer.find('\n')) != std::string::npos;) {
        handleLine(c, c.buffer.substr(0, end));
        c.buffer.erase(0, end + 1);
      }
    }
  }

  // The parts, merged in the input's order: what each worker finished is in
  // its part in the order it reported.
  std::map<std::size_t, std::pair<std::size_t, std::size_t>> where;  // index -> (worker, position)
  for (std::size_t k = 0; k < children.size(); ++k)
    for (std::size_t j = 0; j < children[k].done.size(); ++j) where[children[k].done[j]] = {k, j};
  std::string fatal;
  for (const Child& c : children)
    if (!c.fatal.empty() && fatal.empty()) fatal = c.fatal;
  if (where.empty() && !fatal.empty()) {
    for (const Child& c : children) std::filesystem::remove(c.part);
    throw DemoError("converting '" + in_path + "': " + fatal);
  }
  {
    std::vector<std::unique_ptr<DemoReader>> parts(children.size());
    DemoWriter writer(out_path, out_info, where.size());
    for (const auto& [index, at] : where) {
      try {
        if (!parts[at.first]) parts[at.first] = std::make_unique<DemoReader>(children[at.first].part);
        writer.append(parts[at.first]->read("traj_" + std::to_string(at.second)));
        ++result.converted;
      } catch (const DemoError& e) {
        errors[index] = e.what();
      }
    }
    writer.close();
  }
  for (const Child& c : children) {
    std::filesystem::remove(c.part);
    std::filesystem::remove(getDemoJsonPath(c.part));
  }
  for (const auto& [index, why] : errors) result.failed.push_back(names[index] + ": " + why);
  if (!fatal.empty()) result.failed.push_back("a worker could not set up: " + fatal);
  result.seconds = elapsed();
  return result;
}

}  // namespace manibench
