// manibench render: the cameras' images, masks and point clouds of a task
// after a reset, as files; optionally an episode as a video.
#include <manibench/environment.hpp>
#include <manibench/episode.hpp>
#include <manibench/pointcloud.hpp>
#include <manibench/renderer.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli.hpp"
#include "image_io.hpp"
#include "video.hpp"

namespace manibench::cli {
namespace {

const std::string kRenderUsageText = R"(usage: manibench render TASK --out DIR [options]

Resets TASK, renders its cameras (the configuration's `cameras`), each at
its own size (they may differ, in either --obs mode), and writes into DIR,
per camera:
  CAMERA_color.png        8-bit RGB
  CAMERA_depth.png        16-bit gray: millimetres along the optical axis,
                          0 where nothing was hit
  CAMERA_mask_MASK.png    8-bit gray: 255 where the task's mask MASK is seen
and for all cameras together (binary PLY: x y z, red green blue, one
mask_MASK property per mask):
  pointcloud_full.ply     every pixel that hit something, world frame
  pointcloud.ply          the supplement D.1 sample (with --obs pointcloud,
                          exactly the observation the policy gets)
With --video, also runs one episode of --policy and records it from a
third-person camera to an MP4 file (needs the `ffmpeg` program); the policy
observes the --obs mode, so with rgbd its cameras must be of one size.

Options:
  --out DIR               output folder (created if missing)
  --seed S                episode seed (default 0)
  --object ID             object id (default: drawn from the split by the seed)
  --split train|test      split to draw the object from (default train)
  --obs pointcloud|rgbd   what the --video policy observes; pointcloud also
                          makes pointcloud.ply that observation (default rgbd)
  --video FILE.mp4        record an episode (needs --policy)
)" + std::string(kPolicyUsage) + R"(                          the policy acting in the recorded episode
  --video-size WxH        video frame size (default 640x480)
  --controller NAME       override the task's default controller (default: the
                          one the policy names)
  --config FILE, --set KEY=VALUE   configuration layers, as for run
)";
const char* const kRenderUsage = kRenderUsageText.c_str();

std::string fileName(const std::string& name) {
  std::string out = name;
  std::replace_if(out.begin(), out.end(), [](char c) { return c == '/' || c == ' '; }, '_');
  return out;
}

void writeCamera(const std::filesystem::path& dir, const CameraImages& image, const Environment& env) {
  const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
  std::vector<std::uint8_t> rgb(3 * pixels);
  for (std::size_t p = 0; p < pixels; ++p)
    for (std::size_t c = 0; c < 3; ++c) rgb[3 * p + c] = image.rgba[4 * p + c];
  const std::string base = (dir / fileName(image.camera)).string();
  writePng8(base + "_color.png", image.width, image.height, 3, rgb);
  std::vector<std::uint16_t> depth(pixels);
  for (std::size_t p = 0; p < pixels; ++p)
    depth[p] = std::uint16_t(std::clamp(std::lround(image.depth[p] * 1000.0f), 0L, 65535L));
  writePng16(base + "_depth.png", image.width, image.height, depth);
  const std::vector<std::string>& masks = env.getTaskDescription().masks;
  for (std::size_t m = 0; m < masks.size(); ++m) {
    std::vector<std::uint8_t> mask(pixels);
    for (std::size_t p = 0; p < pixels; ++p)
      mask[p] = ((env.getObserver().getMasks().calcPixelMasks(image, p) >> m) & 1u) ? 255 : 0;
    writePng8(base + "_mask_" + fileName(masks[m]) + ".png", image.width, image.height, 1, mask);
  }
}

void recordVideo(const PluginRegistry& registry, Environment& env, const PolicyChoice& choice,
                 const std::string& object, uint64_t seed, const std::string& path, int width, int height) {
  PolicyInstance policy(registry, choice.name, choice.config, env.calcPolicyLayout());
  EpisodeVideo video(env, path, width, height);
  // A frame of every state a policy sees, then of the last one.
  EpisodeHooks hooks;
  hooks.on_phase = [&](EpisodePhase phase, uint32_t) {
    if (phase == EpisodePhase::PolicyReset) video.aimAtRobot();
    if (phase == EpisodePhase::PolicyAct) video.record();
  };
  runEpisode(env, policy, object, seed, hooks);
  video.record();
  video.close();
  std::cout << "wrote " << path << ": " << video.getFrameCount() << " frames, "
            << env.getElapsedSteps() << " steps of policy " << choice.name << "\n";
}

}  // namespace

int commandRender(int argc, char** argv) {
  const Arguments args = parseArguments(
      argc, argv, 2,
      {"out", "seed", "object", "split", "obs", "video", "policy", "policy-config", "video-size", "controller",
       "config", "set"},
      {},
      kRenderUsage);
  if (args.help) {
    std::cout << kRenderUsage;
    return 0;
  }
  if (args.positional.size() != 1) throw UsageError("render needs exactly one TASK", kRenderUsage);
  if (!args.options.count("out")) throw UsageError("render needs --out DIR", kRenderUsage);
  const ObservationMode mode =
      parseObservationMode(args, kRenderUsage, {ObservationMode::PointCloud, ObservationMode::Rgbd})
          .value_or(ObservationMode::Rgbd);
  const std::string split = parseSplit(args, "train", kRenderUsage);
  const uint64_t seed = parseSeed(valueOr(args, "seed", "0"), kRenderUsage);
  const std::string video = valueOr(args, "video", "");
  if (!video.empty() && !args.options.count("policy"))
    throw UsageError("--video needs --policy NAME|PATH.so|PATH.py", kRenderUsage);
  const auto [video_width, video_height] = parseVideoSize(args, kRenderUsage);

  // The environment's own observation mode: the files come from
  // renderCameras() (each camera at its own size) and fusePointCloud(), so
  // only pointcloud.ply of --obs pointcloud (the observation itself) and a
  // --video episode (its policy sees MODE) need MODE's observation. Else
  // the environment observes the state: rgbd's stacking, which needs
  // cameras of one size, is not built for images it would not give out,
  // and nothing is rendered twice.
  const ObservationMode env_mode =
      mode == ObservationMode::PointCloud || !video.empty() ? mode : ObservationMode::State;

  PluginRegistry registry;
  loadPlugins(registry);
  ConfigSources sources = getConfigSources(args, env_mode);
  // The --video policy, resolved (and its controller configured) before
  // anything is built.
  std::optional<PolicyChoice> policy;
  if (!video.empty()) {
    policy = choosePolicy(registry, args, kRenderUsage);
    applyPolicyController(registry, policy->name, args, sources, kRenderUsage);
  }
  const std::unique_ptr<Environment> env =
      makeEnvironment(registry, args.positional[0], sources, /*stop_on_success=*/true);
  const std::string object = args.options.count("object")
                                 ? args.options.at("object")
                                 : chooseObject(env->listObjects(split), seed, split);
  env->reset(object, seed);

  const std::filesystem::path dir(args.options.at("out"));
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw std::runtime_error("cannot create " + dir.string() + ": " + error.message());
  // Renders every camera at the reset state (in pointcloud mode the
  // observation already did, with the same images) and hands them out.
  VisualObserver& observer = env->updObserver();
  const std::vector<CameraImages>& images = observer.renderCameras();
  for (const CameraImages& image : images) writeCamera(dir, image, *env);
  PointCloud full;
  observer.fusePointCloud(images, images.size(), full);
  const std::vector<std::string>& masks = env->getTaskDescription().masks;
  writePly((dir / "pointcloud_full.ply").string(), full, masks);
  const PointCloud sample = mode == ObservationMode::PointCloud ? env->getVisualObservation().points
                                                : samplePointCloud(full, env->getOptions().observation.pointcloud, seed);
  writePly((dir / "pointcloud.ply").string(), sample, masks);
  std::cout << "task " << args.positional[0] << ", object " << object << ", seed " << seed << ": "
            << images.size() << " camera" << (images.size() == 1 ? "" : "s") << ", "
            << full.size() << " points (" << sample.size() << " sampled), "
            << observer.updRenderer().getTriangleCount() << " triangles; "
            << observer.updRenderer().getDeviceInfo().gl_renderer << "\nwrote " << dir.string() << "\n";
  if (!video.empty())
    recordVideo(registry, *env, *policy, object, seed, video, video_width, video_height);
  return 0;
}

}  // namespace manibench::cli
