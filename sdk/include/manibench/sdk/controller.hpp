// Writing a controller: derive from sdk::Controller, construct from
// (const sdk::Config&, const sdk::ControllerContext&), register it:
//   MANIBENCH_REGISTER_CONTROLLER(MyController, "my_controller", "summary");
#pragma once

#include <algorithm>
#include <manibench/sdk/common.hpp>
#include <manibench/sdk/registry.hpp>
#include <manibench/sdk/scene_view.hpp>
#include <manibench/sdk/state.hpp>

#include <memory>
#include <string>
#include <vector>

namespace manibench::sdk {

struct JointInfo {
  std::string name;
  uint32_t type = MB_JOINT_REVOLUTE;
  uint32_t index = 0;  // in the articulation's joint vector
  double lower = 0, upper = 0, velocity_limit = 0, effort_limit = 0;
};

struct ControllerContext {
  mb_id articulation = -1;
  std::vector<JointInfo> joints;  // the driven joints, in action order
  double control_frequency = 100;
};

struct ControllerSpec {
  std::vector<Segment> action;  // normalized [-1, 1] action layout
  uint32_t flags = 0;           // MB_CONTROLLER_*
};

using DriveCommand = mb_drive_command;

class Controller {
 public:
  virtual ~Controller() = default;
  virtual ControllerSpec describe() const = 0;
  virtual void reset(const SceneView& scene) {}
  // One control step: `drives` has one entry per context joint.
  virtual void compute(const SceneView& scene,
                       Eigen::Map<const Eigen::VectorXd> action,
                       std::vector<DriveCommand>& drives) = 0;
};

// ABI 1.7: a controller whose compute ends in another controller's path
// (mobile_panda_ee ends in mobile_panda's filter and drives) derives from
// this too, and reports after each compute the base controller's action
// that computes the same drive commands, so that its demonstrations convert
// exactly into the base's actions (`demos convert --controller`).
class ControllerLayer {
 public:
  virtual ~ControllerLayer() = default;
  // The base controller's registered name.
  virtual std::string getBaseController() const = 0;
  // The base's normalized action of the last compute (its action size);
  // may throw Error(MB_UNSUPPORTED) before the first compute.
  virtual Eigen::VectorXd getBaseAction() const = 0;
};

namespace detail {

struct ControllerHandle {
  std::unique_ptr<Controller> controller;
  SegmentTable action;
  uint32_t flags;
  std::size_t joint_count;
  std::vector<DriveCommand> drives;
  const ControllerLayer* layer;  // null: no layer
  std::string base_controller;   // the layer's base, kept for get_info
  ControllerHandle(std::unique_ptr<Controller> c, const ControllerSpec& spec,
                   std::size_t joints)
      : controller(std::move(c)), action(spec.action), flags(spec.flags),
        joint_count(joints), drives(joints),
        layer(dynamic_cast<const ControllerLayer*>(controller.get())),
        base_controller(layer ? layer->getBaseController() : "") {}
};

inline ControllerHandle* asController(mb_controller* c) {
  return reinterpret_cast<ControllerHandle*>(c);
}

inline ControllerContext toContext(const mb_controller_context* c) {
  if (c == nullptr) throw Error("no controller context", MB_INVALID_ARGUMENT);
  ControllerContext out;
  out.articulation = c->articulation;
  out.control_frequency = c->control_frequency;
  for (uint32_t i = 0; i < c->joint_count; ++i) {
    const mb_joint_info& j = c->joints[i];
    out.joints.push_back({j.name ? j.name : "", j.type, j.index, j.lower,
                          j.upper, j.velocity_limit, j.effort_limit});
  }
  return out;
}

template <class T>
struct ControllerTrampolines {
  static mb_status create(const char* config_yaml,
                          const mb_controller_context* context,
                          mb_controller** out, mb_error* err) {
    return guard(err, [&] {
      *out = nullptr;
      const ControllerContext ctx = toContext(context);
      auto controller = std::make_unique<T>(Config(config_yaml), ctx);
      const ControllerSpec spec = controller->describe();
      *out = reinterpret_cast<mb_controller*>(
          new ControllerHandle(std::move(controller), spec, ctx.joints.size()));
    });
  }
  static void destroy(mb_controller* c) noexcept {
    try {
      delete asController(c);
    } catch (...) {
    }
  }
  static mb_status getInfo(mb_controller* c, mb_controller_info* out,
                           mb_error* err) {
    return guard(err, [&] {
      const ControllerHandle& h = *asController(c);
      mb_controller_info info{};
      info.struct_size = sizeof(mb_controller_info);
      info.action_dim = h.action.total();
      info.action_segment_count = h.action.count();
      info.action_segments = h.action.data();
      info.flags = h.flags;
      info.base_controller = h.layer ? h.base_controller.c_str() : nullptr;
      writeOutputStruct(out, info);
    });
  }
  static mb_status reset(mb_controller* c, const mb_scene_api* api,
                         mb_scene* scene, mb_error* err) {
    return guard(err, [&] {
      const SceneView view(api, scene);
      ControllerHandle& h = *asController(c);
      // An episode starts from the commands a new controller has, not from
      // what the last episode left: episodes must not depend on the ones
      // before them (and the saved state of a reset must not either).
      std::fill(h.drives.begin(), h.drives.end(), DriveCommand{});
      h.controller->reset(view);
    });
  }
  static mb_status compute(mb_controller* c, const mb_scene_api* api,
                           mb_scene* scene, const double* action,
                           uint32_t action_dim, mb_drive_command* out,
                           uint32_t joint_count, mb_error* err) {
    return guard(err, [&] {
      ControllerHandle& h = *asController(c);
      checkVectorSize("action", h.action.total(), action_dim);
      checkVectorSize("drive command buffer", h.joint_count, joint_count);
      const SceneView view(api, scene);
      h.controller->compute(view, Eigen::Map<const Eigen::VectorXd>(action, action_dim),
                            h.drives);
      checkVectorSize("drive commands", h.joint_count, h.drives.size());
      std::copy(h.drives.begin(), h.drives.end(), out);
    });
  }
  static mb_status getBaseAction(mb_controller* c, double* out, uint32_t dim,
                                 mb_error* err) {
    return guard(err, [&] {
      const ControllerHandle& h = *asController(c);
      if (h.layer == nullptr)
        throw Error("get_base_action: this controller is no layer over another",
                    MB_UNSUPPORTED);
      const Eigen::VectorXd action = h.layer->getBaseAction();
      checkVectorSize("base action", uint32_t(action.size()), dim);
      std::copy(action.data(), action.data() + action.size(), out);
    });
  }
  // ABI 1.2: the last drive commands (a controller may leave some as they
  // were), then the controller's Stateful part (state.hpp).
  static mb_status getState(mb_controller* c, uint8_t* out, uint64_t capacity,
                            uint64_t* out_size, mb_error* err) {
    const ControllerHandle& h = *asController(c);
    return saveState(
        *h.controller,
        [&](StateWriter& w) {
          w.write<uint64_t>(h.drives.size());
          w.writeBytes(h.drives.data(), h.drives.size() * sizeof(DriveCommand));
        },
        out, capacity, out_size, err);
  }
  static mb_status setState(mb_controller* c, const uint8_t* data, uint64_t size,
                            mb_error* err) {
    ControllerHandle& h = *asController(c);
    return restoreState(
        *h.controller,
        [&](StateReader& r) {
          if (r.read<uint64_t>() != h.drives.size())
            throw Error("set_state: drive commands for another number of joints",
                        MB_INVALID_ARGUMENT);
          r.readBytes(h.drives.data(), h.drives.size() * sizeof(DriveCommand));
        },
        data, size, err);
  }
};

template <class T>
bool registerController(const char* name, const char* summary) {
  static_assert(std::is_base_of_v<Controller, T>,
                "a controller derives from manibench::sdk::Controller");
  auto* d = newDescriptor<mb_controller_descriptor>(MB_KIND_CONTROLLER, name, summary);
  d->create = &ControllerTrampolines<T>::create;
  d->destroy = &ControllerTrampolines<T>::destroy;
  d->get_info = &ControllerTrampolines<T>::getInfo;
  d->reset = &ControllerTrampolines<T>::reset;
  d->compute = &ControllerTrampolines<T>::compute;
  d->get_state = &ControllerTrampolines<T>::getState;
  d->set_state = &ControllerTrampolines<T>::setState;
  d->get_base_action = &ControllerTrampolines<T>::getBaseAction;
  return true;
}

}  // namespace detail
}  // namespace manibench::sdk

#define MANIBENCH_REGISTER_CONTROLLER(Class, name, summary)                 \
  static const bool MANIBENCH_SDK_CONCAT(manibench_registered_controller_,  \
                                         __COUNTER__) =                     \
      ::manibench::sdk::detail::registerController<Class>(name, summary)
