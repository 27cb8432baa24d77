// Conversion of a demonstration file (another observation mode, or another
// controller: convert_controller.cpp) in worker processes (WorkerPool).
// Each worker builds its own environments (and EGL context) after the
// fork, then converts one trajectory at a time, handed out from a queue,
// into a part file of its own per trajectory, and says over its channel
// which it finished. The parent then copies the parts into the output in
// the input's order. A worker that dies costs only the trajectory it was
// converting: that one is handed out again, to a worker started in its
// place, and named with the death's cause when it kills a worker twice.

#include <manibench/demos.hpp>
#include <manibench/wire_format.hpp>
#include <manibench/worker_pool.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <map>

namespace manibench {
namespace {

// What a worker tells the parent: that it is set up (or why it cannot be),
// then one frame per trajectory: the kind, the input index, why.
enum Report : uint8_t { kReady = 0, kConverted = 1, kFailed = 2, kFatal = 3, kDropped = 4 };

// How many workers a trajectory may take down before it is named, not
// handed out again: once is a worker's bad luck (a kill, the OOM killer),
// twice is the trajectory.
constexpr int kDeathsPerTrajectory = 2;

void sendReport(int fd, Report kind, std::size_t index, const std::string& why) {
  wire::Writer w;
  w.u8(kind).u64(index).str(why);
  wire::sendFrame(fd, w);
}

std::string getPartPath(const std::string& parts_dir, std::size_t index) {
  return parts_dir + "/traj_" + std::to_string(index) + ".h5";
}

int runConversionWorker(const PluginRegistry& registry, const std::string& in_path, const std::string& parts_dir,
                        const std::vector<std::string>& overrides, const std::optional<ControllerConversion>& plan,
                        const std::vector<std::string>& names, const DemoFileInfo& out_info, bool keep_failed,
                        int fd) {
  std::unique_ptr<DemoReader> reader;
  std::unique_ptr<Environment> env, layer;
  TrackingSpeeds speeds;
  try {
    reader = std::make_unique<DemoReader>(in_path);
    // Another controller: the layer's environment and the target's;
    // otherwise one environment renders the recorded states.
    env = makeDemoEnvironment(registry, reader->getInfo(), plan ? plan->target_overrides : overrides);
    if (plan) layer = makeDemoEnvironment(registry, reader->getInfo(), plan->source_overrides);
    speeds = readTrackingSpeeds(env->getOptions());
  } catch (const std::exception& e) {
    sendReport(fd, kFatal, 0, e.what());
    return 1;
  }
  sendReport(fd, kReady, 0, "");
  std::string request;
  while (wire::receiveFrame(fd, request)) {
    wire::Reader in(request);
    const std::size_t index = in.u64();
    try {
      const Trajectory recorded = reader->read(names.at(index));
      const Trajectory converted =
          !plan                       ? convertTrajectory(*env, recorded)
          : plan->method == "tracked" ? trackTrajectory(*layer, *env, recorded, speeds)
                                      : convertTrajectoryController(*layer, *env, recorded, plan->frame_skip);
      if (plan && plan->method == "tracked" && !converted.success && !keep_failed) {
        sendReport(fd, kDropped, index,
                   "no success in " + std::to_string(converted.steps) + " steps (largest tracking error " +
                       std::to_string(converted.tracking_error) + " m)");
        continue;
      }
      DemoWriter writer(getPartPath(parts_dir, index), out_info, 1);
      writer.append(converted);
      writer.close();
      sendReport(fd, kConverted, index, "");
    } catch (const std::exception& e) {
      sendReport(fd, kFailed, index, e.what());
    }
  }
  return 0;
}

}  // namespace

ConversionResult convertDemonstrations(const PluginRegistry& registry, const std::string& in_path,
                                       const std::string& out_path,
                                       const std::vector<std::string>& overrides,
                                       const std::vector<std::string>& selected, unsigned workers,
                                       const DemoFileInfo& out_info_base, const ConversionHooks& hooks,
                                       bool keep_failed) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  if (workers < 1 || workers > 256) throw DemoError("the number of workers must be 1 to 256");
  std::vector<std::string> names;
  DemoFileInfo out_info = out_info_base;
  std::optional<ControllerConversion> plan;
  {
    // Read what is needed and close the file before forking: HDF5's handles
    // do not cross a fork.
    const DemoReader reader(in_path);
    // The output's configuration is the input's with the overrides: what
    // its replays build.
    plan = planControllerConversion(registry, reader.getInfo(), overrides);
    const ConfigNode config = calcDemoConfig(registry, reader.getInfo(), plan ? plan->target_overrides : overrides);
    out_info.config = formatConfig(config);
    out_info.observation_mode = calcEnvironmentOptions(config).observation.mode;
    out_info.controller = plan ? plan->target : reader.getInfo().controller;
    out_info.converted_from = in_path;
    out_info.conversion = plan ? plan->method : "observations";
    const std::vector<std::string>& all = reader.getTrajectoryNames();
    names = selected.empty() ? all : selected;
    for (const std::string& name : names)
      if (std::find(all.begin(), all.end(), name) == all.end())
        throw DemoError("'" + in_path + "' has no trajectory " + name);
  }
  workers = unsigned(std::min<std::size_t>(workers, std::max<std::size_t>(1, names.size())));

  // The parts: one file per converted trajectory, in a folder beside the
  // output, so that what a killed worker finished stays readable.
  const std::string parts_dir = out_path + ".parts";
  std::error_code ignored;
  std::filesystem::remove_all(parts_dir, ignored);
  if (!std::filesystem::create_directories(parts_dir, ignored) && !std::filesystem::is_directory(parts_dir))
    throw DemoError("cannot create '" + parts_dir + "' for the converted parts: " + ignored.message());
  struct RemoveParts {
    std::string dir;
    ~RemoveParts() {
      std::error_code e;
      std::filesystem::remove_all(dir, e);
    }
  } remove_parts{parts_dir};

  ConversionResult result;
  std::map<std::size_t, std::string> errors, dropped, redone;
  std::vector<bool> converted(names.size(), false);
  std::map<std::size_t, int> deaths;
  std::deque<std::size_t> queue;
  for (std::size_t i = 0; i < names.size(); ++i) queue.push_back(i);
  struct Worker {
    bool ready = false;
    int64_t index = -1;  // the trajectory it converts, -1 when idle
  };
  std::vector<Worker> state(workers);
  std::string fatal;
  WorkerPool pool(workers, [&](std::size_t, int fd) {
    return runConversionWorker(registry, in_path, parts_dir, overrides, plan, names, out_info, keep_failed, fd);
  });
  const auto startWorker = [&](std::size_t k) {
    try {
      pool.start(k);
    } catch (const std::runtime_error& e) {
      throw DemoError(e.what());
    }
    state[k] = Worker();
  };
  for (unsigned k = 0; k < workers; ++k) startWorker(k);

  // The next trajectory for worker k, or its end when none is left.
  const auto dispatch = [&](std::size_t k) {
    if (queue.empty() || result.interrupted) {
      pool.stop(k, false);
      return;
    }
    state[k].index = int64_t(queue.front());
    queue.pop_front();
    wire::Writer w;
    w.u64(uint64_t(state[k].index));
    pool.send(k, w);  // a worker gone already: its end comes through poll
  };
  std::size_t finished = 0;
  const auto on_frame = [&](std::size_t k, const std::string& payload) {
    wire::Reader in(payload);
    const uint8_t kind = in.u8();
    const std::size_t index = in.u64();
    const std::string why = in.str();
    if (kind == kFatal) {
      if (fatal.empty()) fatal = why;
      return;
    }
    if (kind == kReady) {
      state[k].ready = true;
      dispatch(k);
      return;
    }
    if (state[k].index < 0 || std::size_t(state[k].index) != index)
      throw DemoError("a conversion worker reported trajectory " + std::to_string(index) + " it was not converting");
    state[k].index = -1;
    ++finished;
    if (kind == kConverted)
      converted[index] = true;
    else if (kind == kDropped)
      dropped[index] = why;
    else
      errors[index] = why;
    if (hooks.on_progress) hooks.on_progress(finished, names.size(), elapsed());
    dispatch(k);
  };
  const auto on_end = [&](std::size_t k, int status) {
    if (!state[k].ready) {
      // It could not set up: the others may; none is started in its place.
      if (fatal.empty()) fatal = "a conversion worker " + describeExit(status) + " while setting up";
      return;
    }
    if (state[k].index >= 0) {
      const std::size_t index = std::size_t(state[k].index);
      state[k].index = -1;
      const std::string why = "the worker converting it was " + describeExit(status);
      if (++deaths[index] < kDeathsPerTrajectory) {
        queue.push_front(index);
        redone[index] = why;
      } else {
        ++finished;
        errors[index] = why + ", twice";
        if (hooks.on_progress) hooks.on_progress(finished, names.size(), elapsed());
      }
    }
    if (!queue.empty() && !result.interrupted) {
      startWorker(k);
      ++result.worker_restarts;
    }
  };
  for (;;) {
    if (hooks.should_stop && hooks.should_stop() && !result.interrupted) {
      result.interrupted = true;
      pool.stopAll();
    }
    try {
      if (!pool.poll(200, on_frame, on_end)) break;
    } catch (const std::runtime_error& e) {
      if (dynamic_cast<const DemoError*>(&e)) throw;
      throw DemoError(e.what());
    }
  }

  const std::size_t done = std::size_t(std::count(converted.begin(), converted.end(), true));
  if (done == 0 && !fatal.empty()) throw DemoError("converting '" + in_path + "': " + fatal);
  // The parts, merged in the input's order.
  {
    DemoWriter writer(out_path, out_info, done);
    for (std::size_t index = 0; index < names.size(); ++index) {
      if (!converted[index]) continue;
      try {
        const DemoReader part(getPartPath(parts_dir, index));
        writer.append(part.read("traj_0"));
        ++result.converted;
      } catch (const DemoError& e) {
        errors[index] = e.what();
      }
    }
    writer.close();
  }
  // What is neither converted, dropped nor failed was never finished: named.
  const std::string unfinished = result.interrupted ? "the run was interrupted before it was converted"
                                 : fatal.empty()    ? "no worker was left to convert it"
                                                    : "no worker could set up: " + fatal;
  for (std::size_t index = 0; index < names.size(); ++index)
    if (!converted[index] && !dropped.count(index) && !errors.count(index)) errors[index] = unfinished;
  for (const auto& [index, why] : errors) result.failed.push_back(names[index] + ": " + why);
  for (const auto& [index, why] : dropped) result.dropped.push_back(names[index] + ": " + why);
  for (const auto& [index, why] : redone)
    if (converted[index] || dropped.count(index))
      result.redone.push_back(names[index] + ": " + why + "; converted again by another worker");
  result.seconds = elapsed();
  return result;
}

}  // namespace manibench
