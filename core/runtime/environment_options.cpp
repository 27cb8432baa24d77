#include <manibench/environment_options.hpp>

#include <cmath>
#include <stdexcept>

namespace manibench {

void validateEnvironmentOptions(const EnvironmentOptions& options) {
  if (options.control_frequency &&
      !(std::isfinite(*options.control_frequency) && *options.control_frequency > 0))
    throw InvalidArgument("control frequency override must be a positive number of Hz, got " +
                                std::to_string(*options.control_frequency));
  if (options.frame_skip && *options.frame_skip == 0)
    throw InvalidArgument("frame skip override must be at least 1");
  if (options.max_episode_steps && *options.max_episode_steps == 0)
    throw InvalidArgument("episode length override must be at least 1 step");
  validateObservationOptions(options.observation);
}

}  // namespace manibench
