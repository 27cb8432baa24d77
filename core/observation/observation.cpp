// Observation modes by name, and the checks of ObservationOptions.
#include <manibench/observation.hpp>

#include <iterator>
#include <set>
#include <stdexcept>

namespace manibench {

namespace {
// In enum order: the one place a mode's name is written.
constexpr const char* kModeNames[] = {"state", "pointcloud", "rgbd"};
constexpr std::size_t kModeCount = sizeof(kModeNames) / sizeof(kModeNames[0]);
static_assert(kModeCount == std::size_t(ObservationMode::Rgbd) + 1, "a name per mode");
}  // namespace

const char* toString(ObservationMode mode) { return kModeNames[std::size_t(mode)]; }

const std::vector<std::string>& getObservationModeNames() {
  static const std::vector<std::string> names(kModeNames, kModeNames + kModeCount);
  return names;
}

std::optional<ObservationMode> findObservationMode(const std::string& name) {
  for (std::size_t i = 0; i < kModeCount; ++i)
    if (name == kModeNames[i]) return ObservationMode(i);
  return std::nullopt;
}

namespace {
constexpr const char* kRgbDtypeNames[] = {"float32", "uint8"};
static_assert(std::size(kRgbDtypeNames) == std::size_t(RgbDtype::Uint8) + 1, "a name per dtype");
}  // namespace

const char* toString(RgbDtype dtype) { return kRgbDtypeNames[std::size_t(dtype)]; }

std::optional<RgbDtype> findRgbDtype(const std::string& name) {
  for (std::size_t i = 0; i < std::size(kRgbDtypeNames); ++i)
    if (name == kRgbDtypeNames[i]) return RgbDtype(i);
  return std::nullopt;
}

const std::vector<std::string>& getRgbDtypeNames() {
  static const std::vector<std::string> names(std::begin(kRgbDtypeNames), std::end(kRgbDtypeNames));
  return names;
}

void validateObservationOptions(const ObservationOptions& options) {
  if (isVisualMode(options.mode) && options.cameras.empty())
    throw InvalidArgument(std::string("observation mode '") + toString(options.mode) +
                                "' needs at least one camera, and the configuration's `cameras` "
                                "list is empty");
  std::set<std::string> camera_names;
  for (const CameraMount& camera : options.cameras) {
    const std::string where = camera.source.empty() ? "camera '" + camera.spec.name + "'" : camera.source;
    if (!camera_names.insert(camera.spec.name).second)
      throw InvalidArgument(where + ": duplicate camera name '" + camera.spec.name + "'");
    if (!camera.link.empty() && camera.articulation.empty())
      throw InvalidArgument(where + ": camera '" + camera.spec.name + "' names link '" +
                                  camera.link + "' but no articulation");
    if (camera.spec.width < 1 || camera.spec.height < 1)
      throw InvalidArgument(where + ": camera '" + camera.spec.name + "' has an empty image");
  }
  if (options.mode == ObservationMode::Rgbd)
    for (const CameraMount& camera : options.cameras) {
      const CameraSpec& first = options.cameras.front().spec;
      if (camera.spec.width != first.width || camera.spec.height != first.height)
        throw InvalidArgument(
            "observation mode 'rgbd' stacks the cameras' images, so they must be of one size: "
            "camera '" + first.name + "' is " + std::to_string(first.width) + "x" +
            std::to_string(first.height) + ", camera '" + camera.spec.name + "' is " +
            std::to_string(camera.spec.width) + "x" + std::to_string(camera.spec.height));
    }
  if (options.pointcloud.masked_total > options.pointcloud.total)
    throw InvalidArgument("point cloud sampling: masked_total exceeds total");
}

}  // namespace manibench
