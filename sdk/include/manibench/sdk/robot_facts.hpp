// What a task needs from a robot's YAML facts (assets/robots/<robot>.yaml,
// docs/robot.md): the actuated joints in DoF order, the initial
// configuration with the task's lift height, and the head cameras at the
// task's mount height as a `cameras:` configuration layer. Every mobile
// Panda family reads the same file the same way.
#pragma once

#include <manibench/sdk/common.hpp>

#include <yaml-cpp/yaml.h>

#include <sstream>
#include <string>
#include <vector>

namespace manibench::sdk {

struct RobotFacts {
  std::vector<std::string> joints;  // actuated, DoF order
  Eigen::VectorXd initial;          // base x, y, yaw, lift, then every arm and its fingers
  std::string camera_config;        // YAML: `cameras:` with the robot's head cameras
};

// Reads `yaml_path` for the task `task_key` (its key in `lift_height` and
// `cameras.mount_height`; others get the defaults). Throws Error naming the
// file and what is wrong with it.
inline RobotFacts readRobotFacts(const std::string& yaml_path, const std::string& task_key) {
  YAML::Node facts;
  try {
    facts = YAML::LoadFile(yaml_path);
  } catch (const YAML::Exception& e) {
    throw Error("cannot read the robot facts " + yaml_path + " (set task.robot_dir): " + e.what(), MB_NOT_FOUND);
  }
  RobotFacts out;
  try {
    out.joints = facts["joints"].as<std::vector<std::string>>();
    const YAML::Node init = facts["initial_configuration"];
    std::vector<double> q = init["base"].as<std::vector<double>>();
    const YAML::Node lift = facts["lift_height"][task_key];
    q.push_back(lift ? lift.as<double>() : init["lift"].as<double>());
    for (std::size_t arm = 0; arm < facts["arms"].size(); ++arm) {
      for (double x : init["arm"].as<std::vector<double>>()) q.push_back(x);
      for (double x : init["fingers"].as<std::vector<double>>()) q.push_back(x);
    }
    if (q.size() != out.joints.size())
      throw Error(yaml_path + ": the initial configuration has " + std::to_string(q.size()) + " values for " +
                      std::to_string(out.joints.size()) + " joints",
                  MB_INVALID_ARGUMENT);
    out.initial = Eigen::Map<const Eigen::VectorXd>(q.data(), Eigen::Index(q.size()));
    const YAML::Node cams = facts["cameras"];
    const YAML::Node heights = cams["mount_height"];
    const double mount_z = heights[task_key] ? heights[task_key].as<double>() : heights["default"].as<double>();
    std::ostringstream yaml;
    yaml << "cameras:\n";
    for (const YAML::Node& m : cams["mounts"]) {
      const auto xyz = m["xyz"].as<std::vector<double>>();
      const auto rpy = m["rpy"].as<std::vector<double>>();
      yaml << "  - name: " << m["name"].as<std::string>() << "\n    articulation: robot\n    link: "
           << m["parent_link"].as<std::string>() << "\n    pose: {position: [" << xyz.at(0) << ", " << xyz.at(1)
           << ", " << mount_z << "], rpy: [" << rpy.at(0) << ", " << rpy.at(1) << ", " << rpy.at(2)
           << "]}\n    width: " << cams["width"].as<int>() << "\n    height: " << cams["height"].as<int>()
           << "\n    fovy: " << cams["fovy"].as<double>() << "\n    near: " << cams["near"].as<double>()
           << "\n    far: " << cams["far"].as<double>() << "\n";
    }
    out.camera_config = yaml.str();
  } catch (const YAML::Exception& e) {
    throw Error(yaml_path + ": not the robot facts a task expects (" + e.what() + ")", MB_INVALID_ARGUMENT);
  } catch (const std::out_of_range&) {
    throw Error(yaml_path + ": a camera mount needs xyz and rpy of 3 values", MB_INVALID_ARGUMENT);
  }
  return out;
}

}  // namespace manibench::sdk
