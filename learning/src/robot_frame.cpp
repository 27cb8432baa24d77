#include <manibench/learning/robot_frame.hpp>

#include <yaml-cpp/yaml.h>

#include <sstream>

namespace manibench::learning {

namespace {

using Kind = RobotFrameInputs::Kind;

const char* toString(Kind kind) {
  switch (kind) {
    case Kind::Points: return "points";
    case Kind::Vectors: return "vectors";
    case Kind::PlanarVector: return "planar_vector";
    case Kind::Pose: return "pose";
  }
  return "?";
}

Kind parseKind(const std::string& name) {
  for (Kind k : {Kind::Points, Kind::Vectors, Kind::PlanarVector, Kind::Pose})
    if (name == toString(k)) return k;
  throw LearningError("unknown robot-frame input kind '" + name + "'");
}

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

const SpecSegment* findSegment(const ObservationSpec& spec, const std::string& name) {
  for (const SpecSegment& s : spec.state_segments)
    if (s.name == name) return &s;
  return nullptr;
}

}  // namespace

int64_t RobotFrameInputs::calcDim() const {
  int64_t n = 0;
  for (const Entry& e : entries) n += e.size;
  return n;
}

std::string RobotFrameInputs::describe() const {
  std::ostringstream out;
  out << entries.size() << " segments, " << calcDim() << " values:";
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const Entry& e = entries[i];
    out << (i ? ", " : " ") << e.segment << " (";
    if (e.kind == Kind::Points || e.kind == Kind::Vectors)
      out << e.size / 3 << " " << (e.kind == Kind::Points ? "point" : "vector") << (e.size > 3 ? "s" : "");
    else
      out << toString(e.kind);
    out << ")";
  }
  return out.str();
}

void RobotFrameInputs::writeYaml(YAML::Node node) const {
  if (!isEnabled()) return;
  node["base_position"] = base_position;
  node["base_yaw"] = base_yaw;
  for (const Entry& e : entries) {
    YAML::Node n;
    n["segment"] = e.segment;
    n["kind"] = toString(e.kind);
    n["offset"] = e.offset;
    n["size"] = e.size;
    node["entries"].push_back(n);
  }
}

RobotFrameInputs RobotFrameInputs::readYaml(const YAML::Node& node) {
  RobotFrameInputs r;
  if (!node || !node["entries"]) return r;
  r.base_position = node["base_position"].as<uint32_t>();
  r.base_yaw = node["base_yaw"].as<uint32_t>();
  for (const YAML::Node& n : node["entries"])
    r.entries.push_back({n["segment"].as<std::string>(), parseKind(n["kind"].as<std::string>()),
                         n["offset"].as<uint32_t>(), n["size"].as<uint32_t>()});
  return r;
}

RobotFrameInputs planRobotFrameInputs(const ObservationSpec& spec) {
  const SpecSegment* position = findSegment(spec, "base_position");
  const SpecSegment* yaw = findSegment(spec, "base_yaw");
  if (position == nullptr || position->size != 2 || yaw == nullptr || yaw->size != 1)
    throw LearningError("--robot-frame needs the segments base_position (2 values) and base_yaw (1) in the " +
                        spec.mode + " observation of " + spec.task + "; its layout is " + spec.describe());
  RobotFrameInputs r;
  r.base_position = position->offset;
  r.base_yaw = yaw->offset;
  for (const SpecSegment& s : spec.state_segments) {
    if (s.name == "base_position") continue;
    const bool world = s.description.find("world") != std::string::npos;
    if (endsWith(s.name, "_pose") && s.size == 7)
      r.entries.push_back({s.name, Kind::Pose, s.offset, s.size});
    else if (world && s.size == 2)
      r.entries.push_back({s.name, Kind::PlanarVector, s.offset, s.size});
    else if (world && s.size > 0 && s.size % 3 == 0)
      r.entries.push_back({s.name, s.description.find("(m)") != std::string::npos ? Kind::Points : Kind::Vectors,
                           s.offset, s.size});
  }
  if (r.entries.empty())
    throw LearningError("--robot-frame found nothing in the world's frame to re-express in " + spec.task +
                        "'s layout (" + spec.describe() + ")");
  return r;
}

torch::Tensor calcRobotFrameFeatures(const RobotFrameInputs& inputs, const torch::Tensor& state) {
  const torch::Tensor s = state.to(torch::kFloat32);
  const torch::Tensor bx = s.select(1, inputs.base_position), by = s.select(1, inputs.base_position + 1);
  const torch::Tensor yaw = s.select(1, inputs.base_yaw);
  const torch::Tensor c = torch::cos(yaw), n = torch::sin(yaw);
  std::vector<torch::Tensor> out;
  // The world vector (x, y) in the base's frame: turned by -yaw.
  auto turn = [&](const torch::Tensor& x, const torch::Tensor& y) {
    out.push_back(c * x + n * y);
    out.push_back(c * y - n * x);
  };
  auto point = [&](int64_t at) {
    turn(s.select(1, at) - bx, s.select(1, at + 1) - by);
    out.push_back(s.select(1, at + 2));
  };
  auto vector = [&](int64_t at) {
    turn(s.select(1, at), s.select(1, at + 1));
    out.push_back(s.select(1, at + 2));
  };
  for (const RobotFrameInputs::Entry& e : inputs.entries) {
    const int64_t at = e.offset;
    switch (e.kind) {
      case Kind::Points:
        for (uint32_t k = 0; k < e.size; k += 3) point(at + k);
        break;
      case Kind::Vectors:
        for (uint32_t k = 0; k < e.size; k += 3) vector(at + k);
        break;
      case Kind::PlanarVector: turn(s.select(1, at), s.select(1, at + 1)); break;
      case Kind::Pose: {
        point(at);
        // (cos(-yaw/2), 0, 0, sin(-yaw/2)) * q, sign chosen so that w >= 0.
        const torch::Tensor aw = torch::cos(yaw / 2), az = -torch::sin(yaw / 2);
        const torch::Tensor qw = s.select(1, at + 3), qx = s.select(1, at + 4), qy = s.select(1, at + 5),
                            qz = s.select(1, at + 6);
        const torch::Tensor w = aw * qw - az * qz;
        const torch::Tensor sign = torch::where(w < 0, -torch::ones_like(w), torch::ones_like(w));
        out.push_back(sign * w);
        out.push_back(sign * (aw * qx - az * qy));
        out.push_back(sign * (aw * qy + az * qx));
        out.push_back(sign * (aw * qz + az * qw));
        break;
      }
    }
  }
  return torch::stack(out, 1);
}

}  // namespace manibench::learning
