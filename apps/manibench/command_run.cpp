// manibench run: one episode of a policy, printed step count, return and
// success conditions.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <manibench/episode.hpp>
#include <memory>

#include "cli.hpp"
#include "video.hpp"

namespace manibench::cli {

namespace {

const std::string kRunUsageText = R"(usage: manibench run TASK --policy NAME|PATH.so|PATH.py [options]

TASK is a task name or a fixed-object id <Task>_<object>-v<N> such as
Reach_3-v0 or OpenCabinetDrawer_1000-v0 (the object is drawn from its own).

Options:
)" + std::string(kPolicyUsage) + R"(  --seed S                episode seed (default 0)
  --object ID             object id (default: drawn from the split by the seed)
  --split train|test      split to draw the object from (default train)
  --controller NAME       override the task's default controller (default: the
                          one the policy names, e.g. an expert's mobile_panda_ee)
  --obs MODE              observation mode: state (default), pointcloud or rgbd
  --no-early-stop         run to the time limit even after success
  --video FILE.mp4        record the episode from a third-person camera (any
                          --obs; needs the `ffmpeg` program): one frame per
                          state the policy saw, then the last (steps + 1)
  --video-size WxH        its frame size (default 640x480)
  --trace FILE.csv        one row per env step: the observation the policy
                          acted on (one column per value, named after its
                          segment: tcp_pose[2]), the action, the reward, each
                          success condition (0/1) and done; numbers exact
                          (%.17g)
  --config FILE           a YAML configuration layer; repeatable, later wins
  --set KEY=VALUE         one key, e.g. --set physics.accuracy=0.001; repeatable
)";
const char* const kRunUsage = kRunUsageText.c_str();

// Column names of a layout: segment[i] (segment alone when it has one value).
void appendColumns(std::vector<std::string>& columns, const std::string& prefix,
                   const std::vector<mb::sdk::Segment>& segments) {
  for (const mb::sdk::Segment& s : segments)
    for (uint32_t i = 0; i < s.size; ++i)
      columns.push_back(prefix + s.name + (s.size > 1 ? "[" + std::to_string(i) + "]" : ""));
}

// `run --trace`: the episode as CSV, written as it runs.
class TraceWriter {
 public:
  TraceWriter(const std::string& path, const mb::Environment& env) : out_(path) {
    if (!out_) throw std::runtime_error("cannot write the trace '" + path + "'");
    std::vector<std::string> columns = {"step"};
    appendColumns(columns, "obs.", env.calcPolicyLayout().observation_segments);
    appendColumns(columns, "action.", env.getControllerDescription().action_segments);
    columns.push_back("reward");
    for (const std::string& c : env.getTaskDescription().success_conditions) columns.push_back(c);
    columns.push_back("done");
    for (std::size_t i = 0; i < columns.size(); ++i) out_ << (i ? "," : "") << columns[i];
    out_ << "\n";
  }
  void onReset(const Eigen::VectorXd& observation) { observation_ = observation; }
  void onStep(uint32_t step, const Eigen::VectorXd& action, const mb::StepResult& result,
              const Eigen::VectorXd& next_observation) {
    char number[32];
    auto put = [&](double v) {
      std::snprintf(number, sizeof(number), "%.17g", v);
      out_ << "," << number;
    };
    out_ << step;
    for (Eigen::Index i = 0; i < observation_.size(); ++i) put(observation_[i]);
    for (Eigen::Index i = 0; i < action.size(); ++i) put(action[i]);
    put(result.reward);
    for (uint8_t flag : result.flags) out_ << "," << int(flag);
    out_ << "," << (result.isDone() ? 1 : 0) << "\n";
    observation_ = next_observation;
  }
  void close(const std::string& path) {
    out_.close();
    if (!out_) throw std::runtime_error("cannot write the trace '" + path + "'");
  }

 private:
  std::ofstream out_;
  Eigen::VectorXd observation_;
};

int runOne(mb::PluginRegistry& registry, const std::string& task_name, uint64_t seed, const std::string& object_arg,
           const std::string& split, const Arguments& args, bool stop_on_success, const std::string& trace_path,
           const std::string& video_path) {
  // The policy fails before anything is built.
  const PolicyChoice choice = choosePolicy(registry, args, kRunUsage);
  const std::string& policy_name = choice.name;
  mb::ConfigSources sources = getConfigSources(args, parseObservationMode(args, kRunUsage));
  applyPolicyController(registry, policy_name, args, sources, kRunUsage);
  const std::unique_ptr<mb::Environment> env_owner =
      makeEnvironment(registry, task_name, sources, stop_on_success);
  mb::Environment& env = *env_owner;
  const std::string object =
      object_arg.empty() ? chooseObject(env.listObjects(split), seed, split) : object_arg;
  env.reset(object, seed);
  mb::PolicyInstance policy(registry, policy_name, choice.config, env.calcPolicyLayout());
  std::cout << "task " << task_name << ", policy " << policy_name << ", controller "
            << env.getControllerDescription().name << "\n";
  // A policy's failure is named by where it happened, as the environment's
  // own errors are.
  mb::EpisodeHooks hooks;
  bool acting = false;
  // The video: a frame of every state the policy sees, then of the last one
  // (render --video, demos replay --video and Python's render() draw the
  // same third-person view: EpisodeVideo, calcThirdPersonView).
  std::unique_ptr<EpisodeVideo> video;
  if (!video_path.empty()) {
    const auto [width, height] = parseVideoSize(args, kRunUsage);
    video = std::make_unique<EpisodeVideo>(env, video_path, width, height);
  }
  hooks.on_phase = [&acting, &video](mb::EpisodePhase phase, uint32_t) {
    acting = phase == mb::EpisodePhase::PolicyAct;
    if (video && phase == mb::EpisodePhase::PolicyReset) video->aimAtRobot();
    if (video && acting) video->record();
  };
  std::unique_ptr<TraceWriter> trace;
  if (!trace_path.empty()) {
    trace = std::make_unique<TraceWriter>(trace_path, env);
    hooks.on_reset = [&] { trace->onReset(env.getObservation()); };
    hooks.on_transition = [&](const Eigen::VectorXd& action, const mb::StepResult& step) {
      trace->onStep(env.getElapsedSteps(), action, step, env.getObservation());
    };
  }
  try {
    printEpisode(mb::runEpisode(env, policy, object, seed, hooks));
    if (video) {
      video->record();
      video->close();
      std::cout << "wrote " << video_path << ": " << video->getFrameCount() << " frames, "
                << env.getElapsedSteps() << " steps\n";
    }
    if (trace) {
      trace->close(trace_path);
      std::cout << "wrote " << trace_path << "\n";
    }
  } catch (const mb::PluginCallError& e) {
    if (!acting) throw;
    throw mb::PluginCallError("task '" + env.getTaskDescription().name + "', object '" + object +
                                  "', seed " + std::to_string(seed) + ", step " +
                                  std::to_string(env.getElapsedSteps()) + ": " + e.what(),
                              e.status());
  }
  return 0;
}


}  // namespace

int commandRun(int argc, char** argv) {
  const Arguments args =
      parseArguments(argc, argv, 2,
                     {"policy", "policy-config", "seed", "object", "split", "controller", "obs", "config", "set",
                      "trace", "video", "video-size"},
                     {"no-early-stop"}, kRunUsage);
  if (args.help) {
    std::cout << kRunUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("run needs exactly one TASK", kRunUsage);
  if (!args.options.count("policy")) throw UsageError("run needs --policy NAME|PATH.so|PATH.py", kRunUsage);
  const std::string split = parseSplit(args, "train", kRunUsage);
  // A bad --obs or --video-size fails before the plugins load.
  parseObservationMode(args, kRunUsage);
  parseVideoSize(args, kRunUsage);
  const uint64_t seed = parseSeed(valueOr(args, "seed", "0"), kRunUsage);
  mb::PluginRegistry registry;
  loadPlugins(registry);
  return runOne(registry, args.positional[0], seed, valueOr(args, "object", ""), split, args,
                !args.options.count("no-early-stop"), valueOr(args, "trace", ""), valueOr(args, "video", ""));
}

}  // namespace manibench::cli
