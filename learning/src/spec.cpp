#include <manibench/learning/spec.hpp>

#include <yaml-cpp/yaml.h>

#include <sstream>

namespace manibench::learning {

namespace {

std::string describeSegments(uint32_t dim, const std::vector<SpecSegment>& segments) {
  std::ostringstream out;
  out << dim;
  if (!segments.empty()) {
    out << " [";
    for (std::size_t i = 0; i < segments.size(); ++i)
      out << (i ? ", " : "") << segments[i].name << " " << segments[i].size;
    out << "]";
  }
  return out.str();
}

void writeSegments(YAML::Node node, const std::vector<SpecSegment>& segments) {
  for (const SpecSegment& s : segments) {
    YAML::Node n;
    n["name"] = s.name;
    n["offset"] = s.offset;
    n["size"] = s.size;
    node.push_back(n);
  }
}

std::vector<SpecSegment> readSegments(const YAML::Node& node) {
  std::vector<SpecSegment> out;
  if (!node) return out;
  for (const YAML::Node& n : node)
    out.push_back({n["name"].as<std::string>(), n["offset"].as<uint32_t>(), n["size"].as<uint32_t>()});
  return out;
}

}  // namespace

std::string ObservationSpec::describe() const {
  std::ostringstream out;
  out << task << ", " << mode;
  if (isPointCloud()) out << " (" << point_count << " points, " << mask_count << " masks)";
  out << ", " << (mode == "state" ? "state " : "agent ") << describeSegments(state_dim, state_segments)
      << ", action " << describeSegments(action_dim, action_segments);
  if (!controller.empty()) out << ", controller " << controller;
  return out.str();
}

void ObservationSpec::checkSame(const ObservationSpec& other, const std::string& this_name,
                                const std::string& other_name) const {
  std::string field;
  if (task != other.task) field = "task";
  else if (mode != other.mode) field = "observation mode";
  else if (!controller.empty() && !other.controller.empty() && controller != other.controller)
    field = "controller";
  else if (state_dim != other.state_dim || state_segments != other.state_segments)
    field = mode == "state" ? "state layout" : "agent state layout";
  else if (action_dim != other.action_dim || action_segments != other.action_segments)
    field = "action layout";
  else if (isPointCloud() && point_count && other.point_count &&
           (point_count != other.point_count || mask_count != other.mask_count))
    field = "point cloud size or masks";
  if (field.empty()) return;
  throw LearningError("the " + field + " of " + this_name + " and " + other_name + " differ:\n  " +
                      this_name + ": " + describe() + "\n  " + other_name + ": " + other.describe());
}

void ObservationSpec::writeYaml(YAML::Node& node) const {
  node["task"] = task;
  node["mode"] = mode;
  node["controller"] = controller;
  node["state_dim"] = state_dim;
  writeSegments(node["state_segments"], state_segments);
  node["action_dim"] = action_dim;
  writeSegments(node["action_segments"], action_segments);
  node["point_count"] = point_count;
  node["mask_count"] = mask_count;
  node["mask_names"] = mask_names;
}

ObservationSpec ObservationSpec::readYaml(const YAML::Node& node) {
  ObservationSpec s;
  s.task = node["task"].as<std::string>();
  s.mode = node["mode"].as<std::string>();
  s.controller = node["controller"].as<std::string>("");
  s.state_dim = node["state_dim"].as<uint32_t>();
  s.state_segments = readSegments(node["state_segments"]);
  s.action_dim = node["action_dim"].as<uint32_t>();
  s.action_segments = readSegments(node["action_segments"]);
  s.point_count = node["point_count"].as<uint32_t>(0);
  s.mask_count = node["mask_count"].as<uint32_t>(0);
  if (node["mask_names"]) s.mask_names = node["mask_names"].as<std::vector<std::string>>();
  return s;
}

}  // namespace manibench::learning
