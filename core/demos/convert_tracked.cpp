// Tracked conversion (`demos convert --controller`, where the file's
// controller is no layer over the target): the recording is replayed in its
// own controller beside the target's environment, and at each step the
// target's action is made, segment by segment by name, to follow the
// recorded robot in closed loop. docs/demonstrations.md, "Another
// controller".
#include <manibench/demos.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>

namespace manibench {
namespace {

Eigen::Isometry3d toIsometry(const Pose& p) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = p.orientation.normalized().toRotationMatrix();
  x.translation() = p.position;
  return x;
}

Eigen::Vector3d calcRotationVector(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.axis() * aa.angle();
}

// The mobile Panda's frames the tracking reads: base_link (the base's pose),
// body_link (base_link raised by the lift: the frame the end-effector
// velocities are in) and each arm's TCP.
struct RobotFrames {
  int base = -1, body = -1;
  std::map<std::string, int> tcp;  // by side
};

RobotFrames findFrames(const Environment& env) {
  const Scene& scene = env.getScene();
  const int robot = scene.findArticulation(env.getTaskDescription().robot_articulation);
  RobotFrames frames;
  frames.base = scene.findLink(robot, "base_link");
  frames.body = scene.findLink(robot, "body_link");
  for (const char* side : {"right", "left"})
    if (const int tcp = scene.findLink(robot, std::string(side) + "_panda_tcp"); tcp >= 0) frames.tcp[side] = tcp;
  if (robot < 0 || frames.base < 0 || frames.body < 0 || frames.tcp.empty())
    throw DemoError("tracked conversion needs the mobile Panda robot (base_link, body_link, <side>_panda_tcp)");
  return frames;
}

// The share of the base's drift corrected per step, measured on the 10
// procedural PushChair trajectories (docs/demonstrations.md): with half,
// 2 still succeeded, with a tenth 8, with none 6; the cabinets' rates are
// the same with either.
constexpr double kBaseCorrection = 0.1;

const sdk::Segment* findSegment(const std::vector<sdk::Segment>& segments, const std::string& name) {
  for (const sdk::Segment& s : segments)
    if (s.name == name) return &s;
  return nullptr;
}

// The largest distance between the two robots' TCPs (m).
double calcTcpDistance(const Environment& a, const Environment& b, const RobotFrames& frames) {
  double largest = 0;
  for (const auto& [side, link] : frames.tcp)
    largest = std::max(largest, (a.getScene().getLinkPose(link).position - b.getScene().getLinkPose(link).position).norm());
  return largest;
}

}  // namespace

TrackingSpeeds readTrackingSpeeds(const EnvironmentOptions& target) {
  TrackingSpeeds speeds;
  if (target.controller_config.empty()) return speeds;
  const ConfigNode config = parseConfig(target.controller_config, "the target controller's configuration");
  for (auto [key, value] : {std::pair{"ee_linear_max", &speeds.linear}, std::pair{"ee_angular_max", &speeds.angular},
                            std::pair{"base_max_velocity", &speeds.base}})
    if (const ConfigNode* node = config.find(key))
      if (const std::optional<double> number = calcNumber(*node)) *value = *number;
  return speeds;
}

Trajectory trackTrajectory(Environment& source, Environment& target, const Trajectory& trajectory,
                           const TrackingSpeeds& speeds) {
  startControllerConversion(source, target, trajectory);
  const RobotFrames frames = findFrames(target);
  const std::vector<sdk::Segment>& recorded_segments = source.getControllerDescription().action_segments;
  const std::vector<sdk::Segment>& segments = target.getControllerDescription().action_segments;
  const double dt = double(target.getTaskDescription().frame_skip) / target.getTaskDescription().control_frequency;
  TrajectoryRecorder recorder(target);
  recorder.onReset(trajectory.object_id, trajectory.level, trajectory.seed);
  double tracking_error = 0;
  for (uint32_t k = 0; k < trajectory.steps; ++k) {
    const Eigen::VectorXd recorded = trajectory.getAction(k).cwiseMax(-1.0).cwiseMin(1.0);
    const Scene& now = target.getScene();
    // The base's drift from the recording, before the step, in the robot's
    // own frame: a tenth of it corrected per step on top of the recorded
    // base action.
    const Eigen::Isometry3d base = toIsometry(now.getLinkPose(frames.base));
    const Eigen::Isometry3d recorded_base = toIsometry(source.getScene().getLinkPose(frames.base));
    const Eigen::Vector3d base_error = base.linear().transpose() * (recorded_base.translation() - base.translation());
    const double yaw_error = calcRotationVector(recorded_base.linear() * base.linear().transpose()).z();
    const Eigen::Isometry3d body = toIsometry(now.getLinkPose(frames.body));
    const double lift_error = (base.inverse() * toIsometry(source.getScene().getLinkPose(frames.body))).translation().z() -
                              (base.inverse() * body).translation().z();
    // The recording's next state: where each TCP is to be, relative to the
    // body (the base is tracked on its own, and carries the arm).
    source.step(trajectory.getAction(k));
    const Eigen::Isometry3d next_body = toIsometry(source.getScene().getLinkPose(frames.body));
    Eigen::VectorXd action = Eigen::VectorXd::Zero(target.getControllerDescription().action_dim);
    for (const sdk::Segment& s : segments) {
      const std::string& name = s.name;
      const std::size_t underscore = name.find('_');
      const std::string side = name.substr(0, underscore), part = name.substr(underscore + 1);
      if (const sdk::Segment* same = findSegment(recorded_segments, name); same && same->size == s.size) {
        action.segment(s.offset, s.size) = recorded.segment(same->offset, s.size);
        const double correction = kBaseCorrection / dt;
        if (name == "base_forward") action[s.offset] += correction * base_error.x() / speeds.base;
        if (name == "base_left") action[s.offset] += correction * base_error.y() / speeds.base;
        if (name == "base_yaw") action[s.offset] += correction * yaw_error / speeds.yaw;
        if (name == "lift") action[s.offset] += correction * lift_error / speeds.lift;
      } else if ((part == "ee_linear" || part == "ee_angular") && s.size == 3 && frames.tcp.count(side)) {
        const int tcp = frames.tcp.at(side);
        const Eigen::Isometry3d want = next_body.inverse() * toIsometry(source.getScene().getLinkPose(tcp));
        const Eigen::Isometry3d have = body.inverse() * toIsometry(now.getLinkPose(tcp));
        if (part == "ee_linear")
          action.segment<3>(s.offset) = (want.translation() - have.translation()) / (dt * speeds.linear);
        else
          action.segment<3>(s.offset) =
              calcRotationVector(want.linear() * have.linear().transpose()) / (dt * speeds.angular);
      } else {
        throw DemoError("tracking into '" + target.getControllerDescription().name + "': its action segment '" +
                        name + "' is neither the recording's controller's nor an end-effector velocity");
      }
    }
    const StepResult result = target.step(action.cwiseMax(-1.0).cwiseMin(1.0));
    recorder.onStep(action.cwiseMax(-1.0).cwiseMin(1.0), result);
    tracking_error = std::max(tracking_error, calcTcpDistance(target, source, frames));
    if (result.isDone()) break;
  }
  Trajectory tracked = recorder.take();
  tracked.tracking_error = tracking_error;
  return tracked;
}

}  // namespace manibench
