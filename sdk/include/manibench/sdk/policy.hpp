// Writing a policy: derive from sdk::Policy, construct from
// (const sdk::Config&, const sdk::PolicyContext&) or (const sdk::PolicyContext&),
// and register it:
//   MANIBENCH_REGISTER_POLICY(MyPolicy, "my_policy", "summary");
#pragma once

#include <manibench/sdk/common.hpp>
#include <manibench/sdk/registry.hpp>

#include <cstdint>
#include <memory>
#include <new>
#include <string>
#include <type_traits>
#include <vector>

namespace manibench::sdk {

// SDK 1.x's name for a layout's segment, kept for policies written
// against it: one type now (segment.hpp).
using SegmentInfo [[deprecated("use sdk::Segment")]] = Segment;

// A vector's layout as the host describes it.
struct Layout {
  uint32_t dim = 0;
  std::vector<Segment> segments;

  const Segment* find(const std::string& name) const {
    for (const Segment& s : segments)
      if (s.name == name) return &s;
    return nullptr;
  }
  const Segment& get(const std::string& name) const {
    if (const Segment* s = find(name)) return *s;
    throw Error("no segment named '" + name + "' in this layout",
                MB_INVALID_ARGUMENT);
  }
  static Layout fromC(uint32_t dim, uint32_t count, const mb_segment* segments) {
    Layout out;
    out.dim = dim;
    for (uint32_t i = 0; i < count; ++i) out.segments.push_back(Segment::fromC(segments[i]));
    return out;
  }
};

struct PolicyContext {
  std::string task_name;
  std::string observation_mode;
  Layout observation;
  Layout action;
};

using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixXu8 = Eigen::Matrix<std::uint8_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// One observation, viewed in place (valid during act() only). The visual
// parts are empty (zero rows) in the modes that lack them and when the
// host is older than ABI 1.1.
struct Observation {
  Eigen::Map<const Eigen::VectorXd> state;
  uint32_t step;
  const mb_observation* raw;  // for fields newer than this SDK's helpers
  uint32_t mask_count = 0;    // the task's segmentation masks

  // "pointcloud": one row per point (world frame; supplement D.1 sampling,
  // zero points pad it to a fixed size): xyz in m, rgb in [0, 1], and
  // mask_count columns of 0 or 1.
  Eigen::Map<const RowMatrixXf> points_xyz{nullptr, 0, 3};
  Eigen::Map<const RowMatrixXf> points_rgb{nullptr, 0, 3};
  Eigen::Map<const RowMatrixXu8> points_mask{nullptr, 0, 0};

  // "rgbd": one row per pixel (row * image_width + col, row 0 on top), the
  // cameras stacked along the columns as ManiSkill stacks channels: rgb
  // 3 per camera (camera c in columns 3c..3c+2), depth 1 per camera (m
  // along the optical axis, 0 where nothing was hit), masks mask_count per
  // camera (camera c's mask m in column c * mask_count + m).
  uint32_t camera_count = 0, image_height = 0, image_width = 0;
  Eigen::Map<const RowMatrixXf> image_rgb{nullptr, 0, 0};
  Eigen::Map<const RowMatrixXf> image_depth{nullptr, 0, 0};
  Eigen::Map<const RowMatrixXu8> image_masks{nullptr, 0, 0};

  explicit Observation(const mb_observation& o)
      : state(o.state, o.state_dim), step(o.step), raw(&o) {
    if (!MB_HAS_FIELD(mb_observation, image_masks, o.struct_size)) return;
    mask_count = o.mask_count;
    const Eigen::Index n = o.point_count, k = o.mask_count;
    if (n > 0 && o.points_xyz && o.points_rgb) {
      new (&points_xyz) Eigen::Map<const RowMatrixXf>(o.points_xyz, n, 3);
      new (&points_rgb) Eigen::Map<const RowMatrixXf>(o.points_rgb, n, 3);
      if (o.points_mask) new (&points_mask) Eigen::Map<const RowMatrixXu8>(o.points_mask, n, k);
    }
    const Eigen::Index pixels = Eigen::Index(o.image_height) * o.image_width;
    const Eigen::Index c = o.camera_count;
    if (pixels > 0 && c > 0 && o.image_rgb && o.image_depth) {
      camera_count = o.camera_count;
      image_height = o.image_height;
      image_width = o.image_width;
      new (&image_rgb) Eigen::Map<const RowMatrixXf>(o.image_rgb, pixels, 3 * c);
      new (&image_depth) Eigen::Map<const RowMatrixXf>(o.image_depth, pixels, c);
      if (o.image_masks)
        new (&image_masks) Eigen::Map<const RowMatrixXu8>(o.image_masks, pixels, k * c);
    }
  }

  // A named segment of the state vector.
  Eigen::Map<const Eigen::VectorXd> segment(const Segment& s) const {
    return Eigen::Map<const Eigen::VectorXd>(state.data() + s.offset, s.size);
  }
  // Color channel `channel` (0 r, 1 g, 2 b) of camera `camera` at (row, col).
  float rgbAt(uint32_t camera, uint32_t row, uint32_t col, uint32_t channel) const {
    return image_rgb(Eigen::Index(row) * image_width + col, 3 * Eigen::Index(camera) + channel);
  }
  float depthAt(uint32_t camera, uint32_t row, uint32_t col) const {
    return image_depth(Eigen::Index(row) * image_width + col, camera);
  }
  bool maskAt(uint32_t camera, uint32_t row, uint32_t col, uint32_t mask) const {
    return image_masks(Eigen::Index(row) * image_width + col,
                       Eigen::Index(camera) * mask_count + mask) != 0;
  }
};

// The episode a policy starts (ABI 1.5's mb_episode_info); strings empty
// where the host does not know them.
struct EpisodeInfo {
  std::string task_name;
  std::string object_id;
  uint64_t seed = 0;
};

class Policy {
 public:
  virtual ~Policy() = default;
  virtual void reset(uint64_t seed) {}
  // Called at each episode's start by a 1.5 host instead of reset(seed);
  // override it to learn the episode's object (one agent per object).
  virtual void resetEpisode(const EpisodeInfo& episode) { reset(episode.seed); }
  // Returns the action (the controller's action size, see PolicyContext).
  // Values outside [-1, 1] are clipped by the host; NaN, infinity or a wrong
  // size fail the episode with the step and index.
  virtual Eigen::VectorXd act(const Observation& observation) = 0;
};

namespace detail {

inline PolicyContext toContext(const mb_policy_context* c) {
  if (c == nullptr) throw Error("no policy context", MB_INVALID_ARGUMENT);
  PolicyContext out;
  out.task_name = c->task_name ? c->task_name : "";
  out.observation_mode = c->observation_mode ? c->observation_mode : "";
  out.observation = Layout::fromC(c->observation_dim, c->observation_segment_count,
                                  c->observation_segments);
  out.action = Layout::fromC(c->action_dim, c->action_segment_count, c->action_segments);
  return out;
}

inline Policy* asPolicy(mb_policy* p) { return reinterpret_cast<Policy*>(p); }

template <class T>
struct PolicyTrampolines {
  static mb_status create(const char* config_yaml, const mb_policy_context* context,
                          mb_policy** out, mb_error* err) {
    return guard(err, [&] {
      *out = nullptr;
      const PolicyContext ctx = toContext(context);
      std::unique_ptr<Policy> policy;
      if constexpr (std::is_constructible_v<T, const Config&, const PolicyContext&>)
        policy = std::make_unique<T>(Config(config_yaml), ctx);
      else
        policy = std::make_unique<T>(ctx);
      *out = reinterpret_cast<mb_policy*>(policy.release());
    });
  }
  static void destroy(mb_policy* p) noexcept {
    try {
      delete asPolicy(p);
    } catch (...) {
    }
  }
  static mb_status reset(mb_policy* p, uint64_t seed, mb_error* err) {
    return guard(err, [&] { asPolicy(p)->reset(seed); });
  }
  static mb_status resetEpisode(mb_policy* p, const mb_episode_info* episode, mb_error* err) {
    return guard(err, [&] {
      if (episode == nullptr) throw Error("no episode", MB_INVALID_ARGUMENT);
      EpisodeInfo info;
      if (MB_HAS_FIELD(mb_episode_info, seed, episode->struct_size)) {
        info.task_name = episode->task_name ? episode->task_name : "";
        info.object_id = episode->object_id ? episode->object_id : "";
        info.seed = episode->seed;
      }
      asPolicy(p)->resetEpisode(info);
    });
  }
  static mb_status act(mb_policy* p, const mb_observation* obs, double* out_action,
                       uint32_t action_dim, mb_error* err) {
    return guard(err, [&] {
      if (obs == nullptr) throw Error("no observation", MB_INVALID_ARGUMENT);
      const Observation o(*obs);
      const Eigen::VectorXd action = asPolicy(p)->act(o);
      if (action.size() != Eigen::Index(action_dim))
        throw Error("act() returned " + std::to_string(action.size()) +
                        " values, but the action has " + std::to_string(action_dim),
                    MB_INVALID_ARGUMENT);
      std::copy(action.data(), action.data() + action_dim, out_action);
    });
  }
};

template <class T>
bool registerPolicy(const char* name, const char* summary, const char* controller = nullptr) {
  static_assert(std::is_base_of_v<Policy, T>, "a policy derives from manibench::sdk::Policy");
  auto* d = newDescriptor<mb_policy_descriptor>(MB_KIND_POLICY, name, summary);
  d->controller = controller;  // ABI 1.4
  d->create = &PolicyTrampolines<T>::create;
  d->destroy = &PolicyTrampolines<T>::destroy;
  d->reset = &PolicyTrampolines<T>::reset;
  d->act = &PolicyTrampolines<T>::act;
  d->reset_episode = &PolicyTrampolines<T>::resetEpisode;
  return true;
}

}  // namespace detail
}  // namespace manibench::sdk

#define MANIBENCH_REGISTER_POLICY(Class, name, summary)                  \
  static const bool MANIBENCH_SDK_CONCAT(manibench_registered_policy_,   \
                                         __COUNTER__) =                  \
      ::manibench::sdk::detail::registerPolicy<Class>(name, summary)

// A policy whose actions are for one controller (ABI 1.4): the host runs it
// on `controller` when the user names none, and refuses another one.
#define MANIBENCH_REGISTER_POLICY_FOR_CONTROLLER(Class, name, summary, controller) \
  static const bool MANIBENCH_SDK_CONCAT(manibench_registered_policy_,   \
                                         __COUNTER__) =                  \
      ::manibench::sdk::detail::registerPolicy<Class>(name, summary, controller)
