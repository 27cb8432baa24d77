// Writing a policy: derive from sdk::Policy, construct from
// (const sdk::Config&, const sdk::PolicyContext&) or (const sdk::PolicyContext&),
// and register it:
//   MANIBENCH_REGISTER_POLICY(MyPolicy, "my_policy", "summary");
#pragma once

#include <manibench/sdk/common.hpp>
#include <manibench/sdk/registry.hpp>

#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace manibench::sdk {

struct SegmentInfo {
  std::string name;
  uint32_t offset = 0;
  uint32_t size = 0;
};

// A vector's layout as the host describes it.
struct Layout {
  uint32_t dim = 0;
  std::vector<SegmentInfo> segments;

  const SegmentInfo* find(const std::string& name) const {
    for (const SegmentInfo& s : segments)
      if (s.name == name) return &s;
    return nullptr;
  }
  const SegmentInfo& get(const std::string& name) const {
    if (const SegmentInfo* s = find(name)) return *s;
    throw Error("no segment named '" + name + "' in this layout",
                MB_INVALID_ARGUMENT);
  }
  static Layout fromC(uint32_t dim, uint32_t count, const mb_segment* segments) {
    Layout out;
    out.dim = dim;
    for (uint32_t i = 0; i < count; ++i)
      out.segments.push_back({segments[i].name ? segments[i].name : "",
                              segments[i].offset, segments[i].size});
    return out;
  }
};

struct PolicyContext {
  std::string task_name;
  std::string observation_mode;
  Layout observation;
  Layout action;
};

struct Observation {
  Eigen::Map<const Eigen::VectorXd> state;
  uint32_t step;
  const mb_observation* raw;  // for fields newer than this SDK's helpers

  // A named segment of the state vector.
  Eigen::Map<const Eigen::VectorXd> segment(const SegmentInfo& s) const {
    return Eigen::Map<const Eigen::VectorXd>(state.data() + s.offset, s.size);
  }
};

class Policy {
 public:
  virtual ~Policy() = default;
  virtual void reset(uint64_t seed) {}
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
  static mb_status act(mb_policy* p, const mb_observation* obs, double* out_action,
                       uint32_t action_dim, mb_error* err) {
    return guard(err, [&] {
      if (obs == nullptr) throw Error("no observation", MB_INVALID_ARGUMENT);
      const Observation o{Eigen::Map<const Eigen::VectorXd>(obs->state, obs->state_dim),
                          obs->step, obs};
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
bool registerPolicy(const char* name, const char* summary) {
  static_assert(std::is_base_of_v<Policy, T>, "a policy derives from manibench::sdk::Policy");
  auto* d = newDescriptor<mb_policy_descriptor>(MB_KIND_POLICY, name, summary);
  d->create = &PolicyTrampolines<T>::create;
  d->destroy = &PolicyTrampolines<T>::destroy;
  d->reset = &PolicyTrampolines<T>::reset;
  d->act = &PolicyTrampolines<T>::act;
  return true;
}

}  // namespace detail
}  // namespace manibench::sdk

#define MANIBENCH_REGISTER_POLICY(Class, name, summary)                  \
  static const bool MANIBENCH_SDK_CONCAT(manibench_registered_policy_,   \
                                         __COUNTER__) =                  \
      ::manibench::sdk::detail::registerPolicy<Class>(name, summary)
