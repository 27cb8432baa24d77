// Conversion of a demonstration file (another observation mode, or another
// controller: convert_controller.cpp) in worker processes
// (WorkerPool): worker k converts trajectories k, k + W, ... into a part
// file of its own (its own environment and EGL context, created after the
// fork), telling the parent over its channel which ones it finished; the
// parent then copies the parts into the output in the input's order. A
// worker that dies costs only the trajectories it had not finished.

#include <manibench/demos.hpp>
#include <manibench/wire_format.hpp>
#include <manibench/worker_pool.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>

namespace manibench {
namespace {

// What a worker tells the parent, one frame per trajectory (and one when it
// cannot set up): the kind, the input index, why.
enum Report : uint8_t { kConverted = 0, kFailed = 1, kFatal = 2, kDropped = 3 };

void sendReport(int fd, Report kind, std::size_t index, const std::string& why) {
  wire::Writer w;
  w.u8(kind).u64(index).str(why);
  wire::sendFrame(fd, w);
}

int runConversionWorker(const PluginRegistry& registry, const std::string& in_path, const std::string& part_path,
                        const std::vector<std::string>& overrides, const std::optional<ControllerConversion>& plan,
                        const std::vector<std::string>& names, const std::vector<std::size_t>& mine,
                        const DemoFileInfo& out_info, bool keep_failed, int fd) {
  int status = 0;
  try {
    const DemoReader reader(in_path);
    // Another controller: the layer's environment and the target's;
    // otherwise one environment renders the recorded states.
    const std::unique_ptr<Environment> env =
        makeDemoEnvironment(registry, reader.getInfo(), plan ? plan->target_overrides : overrides);
    const std::unique_ptr<Environment> layer =
        plan ? makeDemoEnvironment(registry, reader.getInfo(), plan->source_overrides) : nullptr;
    const TrackingSpeeds speeds = readTrackingSpeeds(env->getOptions());
    DemoWriter writer(part_path, out_info, mine.size());
    for (std::size_t index : mine) {
      try {
        const Trajectory recorded = reader.read(names[index]);
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
        writer.append(converted);
        sendReport(fd, kConverted, index, "");
      } catch (const std::exception& e) {
        sendReport(fd, kFailed, index, e.what());
      }
    }
    writer.close();
  } catch (const std::exception& e) {
    sendReport(fd, kFatal, 0, e.what());
    status = 1;
  }
  return status;
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

  struct Part {
    std::string path, fatal;
    std::vector<std::size_t> done;  // input indices, in the order written to the part
  };
  std::vector<Part> children(workers);
  for (unsigned k = 0; k < workers; ++k) children[k].path = out_path + ".part" + std::to_string(k);
  ConversionResult result;
  std::map<std::size_t, std::string> errors, dropped;
  // Worker k converts trajectories k, k + W, ...; one that dies is not
  // replaced: what it had not finished is not converted.
  WorkerPool pool(workers, [&](std::size_t k, int fd) {
    std::vector<std::size_t> mine;
    for (std::size_t i = k; i < names.size(); i += workers) mine.push_back(i);
    return runConversionWorker(registry, in_path, children[k].path, overrides, plan, names, mine, out_info,
                               keep_failed, fd);
  });
  for (unsigned k = 0; k < workers; ++k) {
    try {
      pool.start(k);
    } catch (const std::runtime_error& e) {
      throw DemoError(e.what());
    }
  }

  std::size_t finished = 0;
  const auto on_frame = [&](std::size_t k, const std::string& payload) {
    wire::Reader in(payload);
    const uint8_t kind = in.u8();
    const std::size_t index = in.u64();
    const std::string why = in.str();
    if (kind == kFatal) {
      children[k].fatal = why;
      return;
    }
    ++finished;
    if (kind == kConverted)
      children[k].done.push_back(index);
    else if (kind == kDropped)
      dropped[index] = why;
    else
      errors[index] = why;
    if (hooks.on_progress) hooks.on_progress(finished, names.size(), elapsed());
  };
  const auto on_end = [&](std::size_t k) { pool.stop(k, false); };
  for (;;) {
    if (hooks.should_stop && hooks.should_stop() && !result.interrupted) {
      result.interrupted = true;
      for (unsigned k = 0; k < workers; ++k) pool.kill(k);
    }
    try {
      if (!pool.poll(200, on_frame, on_end)) break;
    } catch (const std::runtime_error& e) {
      throw DemoError(e.what());
    }
  }

  // The parts, merged in the input's order: what each worker finished is in
  // its part in the order it reported.
  std::map<std::size_t, std::pair<std::size_t, std::size_t>> where;  // index -> (worker, position)
  for (std::size_t k = 0; k < children.size(); ++k)
    for (std::size_t j = 0; j < children[k].done.size(); ++j) where[children[k].done[j]] = {k, j};
  std::string fatal;
  for (const Part& c : children)
    if (!c.fatal.empty() && fatal.empty()) fatal = c.fatal;
  if (where.empty() && !fatal.empty()) {
    for (const Part& c : children) std::filesystem::remove(c.path);
    throw DemoError("converting '" + in_path + "': " + fatal);
  }
  {
    std::vector<std::unique_ptr<DemoReader>> parts(children.size());
    DemoWriter writer(out_path, out_info, where.size());
    for (const auto& [index, at] : where) {
      try {
        if (!parts[at.first]) parts[at.first] = std::make_unique<DemoReader>(children[at.first].path);
        writer.append(parts[at.first]->read("traj_" + std::to_string(at.second)));
        ++result.converted;
      } catch (const DemoError& e) {
        errors[index] = e.what();
      }
    }
    writer.close();
  }
  for (const Part& c : children) {
    std::filesystem::remove(c.path);
    std::filesystem::remove(getDemoJsonPath(c.path));
  }
  for (const auto& [index, why] : errors) result.failed.push_back(names[index] + ": " + why);
  for (const auto& [index, why] : dropped) result.dropped.push_back(names[index] + ": " + why);
  if (!fatal.empty()) result.failed.push_back("a worker could not set up: " + fatal);
  result.seconds = elapsed();
  return result;
}

}  // namespace manibench
