// manibench._core: the C++ side of the Python package. It owns the
// process's plugin registry and wraps Environment with numpy observations;
// the gymnasium conventions (spaces, seeds, info dicts, terminated vs
// truncated) live in the pure-Python package over it (python/manibench).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <manibench/config.hpp>
#include <manibench/environment.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/plugin_registry.hpp>
#include <manibench/renderer.hpp>
#include <manibench/task_name.hpp>

#include "step_block.hpp"
#include "step_block_bindings.hpp"

#include <unistd.h>

#include <atomic>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace py = pybind11;
namespace mb = manibench;
using manibench::python::bindStepBlock;
using manibench::python::ServeExit;
using manibench::python::StepBlock;
using manibench::python::StepBlockLayout;
using manibench::python::StepCommand;
using manibench::python::StepResultPlace;
using manibench::python::StepSlotHeader;

namespace {

// One registry per process, loaded from the search path on first use, as
// the CLI loads it (libraries are never unloaded: descriptors point into
// them, so it lives as long as the process).
mb::PluginRegistry& updRegistry() {
  static mb::PluginRegistry* registry = [] {
    auto* r = new mb::PluginRegistry();
    r->loadSearchPath();
    return r;
  }();
  return *registry;
}

// Whether this process has made a renderer (an EGL context): a visual
// observation or render() ran. make_vec forks its workers only while this
// is false (an EGL context does not survive fork).
std::atomic<bool> g_rendered{false};

mb::ConfigSources makeSources(const std::vector<std::string>& files,
                              const std::vector<std::string>& overrides) {
  mb::ConfigSources sources;
  sources.files = files;
  sources.overrides = overrides;
  return sources;
}

// A new numpy array of `shape` filled from `data`: the one copy an
// observation makes on its way to Python.
template <typename T>
py::array_t<T> copyArray(const T* data, std::vector<py::ssize_t> shape) {
  py::array_t<T> out(shape);
  if (out.size() > 0) std::memcpy(out.mutable_data(), data, sizeof(T) * std::size_t(out.size()));
  return out;
}

// 0/1 bytes as a numpy bool array (same bytes, one copy).
py::array copyMasks(const std::vector<std::uint8_t>& bytes, std::vector<py::ssize_t> shape) {
  py::array out(py::dtype("bool"), shape);
  if (!bytes.empty()) std::memcpy(out.mutable_data(), bytes.data(), bytes.size());
  return out;
}

py::list toSegments(const std::vector<mb::sdk::Segment>& segments) {
  py::list out;
  for (const mb::sdk::Segment& s : segments)
    out.append(py::dict(py::arg("name") = s.name, py::arg("offset") = s.offset,
                        py::arg("size") = s.size, py::arg("description") = s.description));
  return out;
}

// The state vector (and the visual modes' agent vector) as a new numpy
// array: float64 as the environment computes it, or rounded to float32
// (make()'s dtypes="compact").
py::array copyVector(const Eigen::VectorXd& v, bool float32) {
  if (!float32) return copyArray(v.data(), {py::ssize_t(v.size())});
  py::array_t<float> out(py::ssize_t(v.size()));
  float* dst = out.mutable_data();
  for (Eigen::Index i = 0; i < v.size(); ++i) dst[i] = float(v[i]);
  return std::move(out);
}

// The observation's arrays in the environment's mode: the shape, dtype
// and bounds of each, as the package's spaces are built from them.
py::dict describeObservation(const mb::Environment& env, bool float32) {
  const mb::TaskDescription& task = env.getTaskDescription();
  const mb::ObservationOptions& o = env.getOptions().observation;
  const double inf = std::numeric_limits<double>::infinity();
  auto field = [&](std::vector<py::ssize_t> shape, const char* dtype, double low, double high) {
    return py::dict(py::arg("shape") = py::tuple(py::cast(shape)), py::arg("dtype") = dtype,
                    py::arg("low") = low, py::arg("high") = high);
  };
  const char* vector = float32 ? "float32" : "float64";
  py::dict fields;
  const py::ssize_t masks = py::ssize_t(task.masks.size());
  switch (o.mode) {
    case mb::ObservationMode::State:
      fields["state"] = field({py::ssize_t(task.observation_dim)}, vector, -inf, inf);
      break;
    case mb::ObservationMode::PointCloud: {
      // Without padding the cloud may be smaller: total is its maximum.
      const py::ssize_t n = o.pointcloud.total;
      fields["xyz"] = field({n, 3}, "float32", -inf, inf);
      fields["rgb"] = field({n, 3}, "float32", 0, 1);
      fields["seg"] = field({n, masks}, "bool", 0, 1);
      fields["agent"] = field({py::ssize_t(task.agent_state_dim)}, vector, -inf, inf);
      break;
    }
    case mb::ObservationMode::Rgbd: {
      const py::ssize_t c = py::ssize_t(o.cameras.size());
      const py::ssize_t h = c ? o.cameras.front().spec.height : 0;
      const py::ssize_t w = c ? o.cameras.front().spec.width : 0;
      if (o.rgb_dtype == mb::RgbDtype::Uint8)
        fields["rgb"] = field({h, w, 3 * c}, "uint8", 0, 255);
      else
        fields["rgb"] = field({h, w, 3 * c}, "float32", 0, 1);
      fields["depth"] = field({h, w, c}, "float32", 0, inf);
      fields["seg"] = field({h, w, masks * c}, "bool", 0, 1);
      fields["agent"] = field({py::ssize_t(task.agent_state_dim)}, vector, -inf, inf);
      break;
    }
  }
  return fields;
}

// An environment as the CLI configures it (apps/manibench/cli.cpp
// makeEnvironment), with numpy in and out. With `float32_vectors` the state
// and agent vectors come out as float32 (actions of either dtype go in).
class PyEnvironment {
 public:
  PyEnvironment(const std::string& environment_id, const std::vector<std::string>& config_files,
                const std::vector<std::string>& overrides, bool stop_on_success,
                bool float32_vectors)
      : config_(mb::loadTaskConfig(updRegistry(), environment_id,
                                   makeSources(config_files, overrides))),
        float32_(float32_vectors) {
    mb::EnvironmentOptions options = mb::calcEnvironmentOptions(config_);
    options.stop_on_success = stop_on_success;
    try {
      env_ = std::make_unique<mb::Environment>(updRegistry(), environment_id, options);
    } catch (const mb::PluginCallError& e) {
      throw mb::PluginCallError(mb::annotatePluginError(config_, e.what()), e.status());
    }
  }

  mb::Environment& upd() {
    if (!env_) throw std::logic_error("the environment is closed");
    return *env_;
  }
  const mb::Environment& get() const {
    if (!env_) throw std::logic_error("the environment is closed");
    return *env_;
  }

  void close() { env_.reset(); }
  bool isClosed() const { return !env_; }

  void reset(const std::string& object_id, uint64_t seed) {
    mb::Environment& env = upd();
    if (mb::isVisualMode(env.getObservationMode())) g_rendered = true;
    py::gil_scoped_release release;
    env.reset(object_id, seed);
  }

  // (reward, terminated, truncated, success, flags, values): the step's
  // StepResult, which decides terminated and truncated.
  py::tuple step(py::array_t<double, py::array::c_style | py::array::forcecast> action) {
    mb::Environment& env = upd();
    if (action.ndim() != 1)
      throw mb::InvalidArgument("the action must be a 1-d array, got " +
                                  std::to_string(action.ndim()) + " dimensions");
    const Eigen::Map<const Eigen::VectorXd> view(action.data(), action.shape(0));
    action_ = view;
    mb::StepResult r;
    {
      py::gil_scoped_release release;
      r = env.step(action_);
    }
    py::list flags, values;
    for (uint8_t f : r.flags) flags.append(bool(f));
    for (double v : r.values) values.append(v);
    return py::make_tuple(r.reward, r.terminated, r.truncated, r.success, flags, values);
  }

  // The current observation: the state vector, or a dict of arrays in the
  // visual modes. Each array is a fresh copy of the environment's buffers.
  py::object getObservation() const {
    const mb::Environment& env = get();
    py::array vector = copyVector(env.getObservation(), float32_);
    const mb::VisualObservation& v = env.getVisualObservation();
    if (v.mode == mb::ObservationMode::State) return std::move(vector);
    py::dict out;
    const py::ssize_t k = v.mask_count;
    if (v.mode == mb::ObservationMode::PointCloud) {
      const py::ssize_t n = py::ssize_t(v.points.size());
      out["xyz"] = copyArray(v.points.xyz.data(), {n, 3});
      out["rgb"] = copyArray(v.points.rgb.data(), {n, 3});
      out["seg"] = copyMasks(v.points.masks, {n, k});
    } else {
      const py::ssize_t h = v.height, w = v.width, c = v.camera_count;
      if (v.rgb_bytes.empty())
        out["rgb"] = copyArray(v.rgb.data(), {h, w, 3 * c});
      else
        out["rgb"] = copyArray(v.rgb_bytes.data(), {h, w, 3 * c});
      out["depth"] = copyArray(v.depth.data(), {h, w, c});
      out["seg"] = copyMasks(v.masks, {h, w, k * c});
    }
    out["agent"] = std::move(vector);
    return std::move(out);
  }

  // A third-person RGB image (height x width x 3, uint8) of the current
  // state: the CLI's videos' view (calcThirdPersonView), framed on the
  // robot and the task's objects where they are now.
  py::array_t<std::uint8_t> render(int width, int height) {
    mb::Environment& env = upd();
    if (width <= 0 || height <= 0)
      throw mb::InvalidArgument("render size must be positive, got " + std::to_string(width) +
                                  "x" + std::to_string(height));
    const mb::ThirdPersonView view =
        mb::calcThirdPersonView(env.getScene(), env.getTaskDescription().robot_articulation, width, height);
    g_rendered = true;
    {
      py::gil_scoped_release release;
      env.updObserver().updRenderer().render(view.camera, view.pose, frame_);
    }
    py::array_t<std::uint8_t> out({py::ssize_t(height), py::ssize_t(width), py::ssize_t(3)});
    std::uint8_t* dst = out.mutable_data();
    const std::size_t pixels = std::size_t(width) * std::size_t(height);
    for (std::size_t p = 0; p < pixels; ++p)
      for (int ch = 0; ch < 3; ++ch) dst[3 * p + ch] = frame_.rgba[4 * p + ch];
    return out;
  }

  // make_vec's worker loop (python/manibench/vector.py): takes the
  // parent's Step commands from `slot` of `block` and answers each in the
  // block (the scalars, flags and values, the observation's fields in
  // describeObservation's order), without Python, until the parent posts
  // ToPipe or a Step arrives for an episode that ended (the next-step
  // auto-reset, which the package does) or, with `same_step`, a Step ends
  // the episode (the package resets at once and answers on the pipe). An
  // exception of a step leaves the loop as it would leave step(): the
  // package sends it through the pipe. Terminated and truncated are the
  // step's (StepResult).
  ServeExit serveSteps(StepBlock& block, std::size_t slot, double spin_wait, int parent_pid,
                       bool same_step) {
    mb::Environment& env = upd();
    const StepBlockLayout& layout = block.getLayout();
    if (slot >= layout.slot_count) throw std::out_of_range("no slot " + std::to_string(slot));
    if (layout.action_dim != std::size_t(env.getControllerDescription().action_dim) ||
        layout.condition_count != env.getTaskDescription().success_conditions.size())
      throw mb::InvalidArgument("serve_steps: the block's layout is not this environment's");
    StepSlotHeader& header = block.updHeader(slot);
    py::gil_scoped_release release;
    for (;;) {
      const StepCommand command = block.waitCommand(slot, spin_wait, parent_pid);
      if (command != StepCommand::Step) return ServeExit::ToPipe;
      if (header.needs_reset) return ServeExit::AutoReset;
      action_ = Eigen::Map<const Eigen::VectorXd>(block.updAction(slot), Eigen::Index(layout.action_dim));
      last_step_ = env.step(action_);
      const mb::StepResult& r = last_step_;
      header.reward = r.reward;
      header.success = r.success;
      header.terminated = r.terminated;
      header.truncated = r.truncated;
      header.elapsed_steps = int64_t(env.getElapsedSteps());
      header.needs_reset = header.terminated || header.truncated;
      std::memcpy(block.updFlags(slot), r.flags.data(), r.flags.size());
      std::memcpy(block.updValues(slot), r.values.data(), r.values.size() * sizeof(double));
      if (same_step && header.needs_reset) return ServeExit::EpisodeEnded;
      writeObservation(block, slot);
      block.finish(slot, StepResultPlace::InBlock);
    }
  }

  // (reward, terminated, truncated, success, flags, values) of
  // serve_steps' last step, as step() returns them.
  py::tuple getLastStep() const {
    py::list flags, values;
    for (uint8_t f : last_step_.flags) flags.append(bool(f));
    for (double v : last_step_.values) values.append(v);
    return py::make_tuple(last_step_.reward, last_step_.terminated, last_step_.truncated,
                          last_step_.success, flags, values);
  }

  py::bytes saveState() {
    const std::vector<uint8_t> blob = upd().saveState();
    return py::bytes(reinterpret_cast<const char*>(blob.data()), blob.size());
  }

  void restoreState(const py::bytes& blob) {
    mb::Environment& env = upd();
    const std::string text = blob;
    const std::vector<uint8_t> bytes(text.begin(), text.end());
    if (mb::isVisualMode(env.getObservationMode())) g_rendered = true;
    py::gil_scoped_release release;
    env.restoreState(bytes);
  }

  // Everything the package needs to describe the environment.
  py::dict describe() const {
    const mb::Environment& env = get();
    const mb::TaskDescription& task = env.getTaskDescription();
    const mb::ControllerDescription& controller = env.getControllerDescription();
    const mb::ObservationOptions& o = env.getOptions().observation;
    py::list cameras;
    for (const mb::CameraMount& c : o.cameras)
      cameras.append(py::dict(py::arg("name") = c.spec.name, py::arg("width") = c.spec.width,
                              py::arg("height") = c.spec.height,
                              py::arg("mount") = c.articulation.empty()
                                                     ? std::string("world")
                                                     : c.articulation + (c.link.empty() ? "" : ":" + c.link)));
    py::dict d;
    d["environment_id"] = env.getEnvironmentId();
    d["task"] = task.name;
    d["library"] =
        updRegistry().getLibraries()[updRegistry().getEntry(mb::PluginKind::Task, task.name).library].path;
    d["control_frequency"] = task.control_frequency;
    d["frame_skip"] = task.frame_skip;
    d["max_episode_steps"] = task.max_episode_steps;
    d["obs_mode"] = mb::toString(o.mode);
    d["observation_dim"] = task.observation_dim;
    d["observation_segments"] = toSegments(task.observation_segments);
    d["agent_state_dim"] = task.agent_state_dim;
    d["observation"] = describeObservation(env, float32_);
    d["controller"] = controller.name;
    d["action_dim"] = controller.action_dim;
    d["action_segments"] = toSegments(controller.action_segments);
    d["success_conditions"] = task.success_conditions;
    d["masks"] = task.masks;
    d["fixed_objects"] = env.getFixedObjects();
    d["cameras"] = cameras;
    return d;
  }

  std::vector<std::string> listObjects(const std::string& split) const {
    if (split != "train" && split != "test")
      throw mb::InvalidArgument("split must be 'train' or 'test', got '" + split + "'");
    return get().listObjects(split);
  }

  // The object `manibench run --seed SEED --split SPLIT` draws
  // (apps/manibench/cli.cpp chooseObject), so that both run one episode.
  std::string chooseObject(const std::string& split, uint64_t seed) const {
    const std::vector<std::string> objects = listObjects(split);
    if (objects.empty()) throw std::runtime_error("the " + split + " split has no objects");
    std::mt19937_64 rng(seed);
    return objects[rng() % objects.size()];
  }

 private:
  // The observation into the slot's fields (getObservation's arrays, in
  // its order: the state vector last in the visual modes).
  void writeObservation(StepBlock& block, std::size_t slot) {
    const mb::Environment& env = get();
    const std::vector<std::size_t>& bytes = block.getLayout().field_bytes;
    std::size_t field = 0;
    auto put = [&](const void* data, std::size_t size) {
      if (field >= bytes.size() || size > bytes[field])
        throw std::logic_error("serve_steps: observation field " + std::to_string(field) +
                               " does not fit the block");
      std::memcpy(block.updField(slot, field++), data, size);
    };
    const Eigen::VectorXd& state = env.getObservation();
    const mb::VisualObservation& v = env.getVisualObservation();
    if (v.mode == mb::ObservationMode::PointCloud) {
      block.updHeader(slot).point_count = uint32_t(v.points.size());
      put(v.points.xyz.data(), v.points.xyz.size() * sizeof(float));
      put(v.points.rgb.data(), v.points.rgb.size() * sizeof(float));
      put(v.points.masks.data(), v.points.masks.size());
    } else if (v.mode == mb::ObservationMode::Rgbd) {
      if (v.rgb_bytes.empty())
        put(v.rgb.data(), v.rgb.size() * sizeof(float));
      else
        put(v.rgb_bytes.data(), v.rgb_bytes.size());
      put(v.depth.data(), v.depth.size() * sizeof(float));
      put(v.masks.data(), v.masks.size());
    }
    if (!float32_) {
      put(state.data(), std::size_t(state.size()) * sizeof(double));
      return;
    }
    vector32_.resize(std::size_t(state.size()));
    for (Eigen::Index i = 0; i < state.size(); ++i) vector32_[std::size_t(i)] = float(state[i]);
    put(vector32_.data(), vector32_.size() * sizeof(float));
  }

  mb::ConfigNode config_;
  bool float32_;  // state and agent vectors as float32
  std::vector<float> vector32_;  // writeObservation's float32 vector
  mb::StepResult last_step_;     // serve_steps' last step
  std::unique_ptr<mb::Environment> env_;
  Eigen::VectorXd action_;
  mb::CameraImages frame_;
};

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "manibench's C++ core: environments over the plugin registry (use the manibench package)";

  // Exceptions carry the C++ message under classes that say what went
  // wrong, mapped onto manibench::Error's (manibench/error.hpp): every
  // mb::Error is a manibench.Error, the user-input ones (InvalidArgument,
  // ConfigError, InvalidAction) also ValueErrors; other std::exceptions
  // keep pybind11's mapping. The classes are made here with type() so that
  // those can be ValueErrors too;
  // they live as long as the process (never decref'd: no destructor runs
  // after the interpreter is gone).
  const py::object make_type = py::reinterpret_borrow<py::object>(reinterpret_cast<PyObject*>(&PyType_Type));
  auto make_error = [&](const char* name, py::tuple bases, const char* doc) {
    py::object type = make_type(name, bases, py::dict(py::arg("__module__") = "manibench",
                                                      py::arg("__doc__") = doc));
    m.attr(name) = type;
    return type.release().ptr();
  };
  static PyObject* error = make_error("Error", py::make_tuple(py::handle(PyExc_RuntimeError)),
                                      "Base of manibench's errors.");
  const py::handle base(error);
  static PyObject* plugin_error = make_error(
      "PluginError", py::make_tuple(base), "A plugin could not be loaded or a name is unknown.");
  static PyObject* plugin_call_error = make_error(
      "PluginCallError", py::make_tuple(base), "A plugin call failed (the plugin's message).");
  static PyObject* episode_failure = make_error(
      "EpisodeFailure", py::make_tuple(base), "Physics diverged or rendering failed in a reset or step.");
  static PyObject* config_error =
      make_error("ConfigError", py::make_tuple(base, py::handle(PyExc_ValueError)),
                 "Bad configuration: unreadable file, unknown key, wrong type, out of range.");
  static PyObject* invalid_action =
      make_error("InvalidAction", py::make_tuple(base, py::handle(PyExc_ValueError)),
                 "An action of the wrong size, or with NaN or infinity.");
  static PyObject* invalid_argument =
      make_error("InvalidArgument", py::make_tuple(base, py::handle(PyExc_ValueError)),
                 "A bad value: an option, an argument, an object id, a state blob.");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const mb::ConfigError& e) {
      PyErr_SetString(config_error, e.what());
    } catch (const mb::InvalidAction& e) {
      PyErr_SetString(invalid_action, e.what());
    } catch (const mb::PluginCallError& e) {
      PyErr_SetString(plugin_call_error, e.what());
    } catch (const mb::PluginError& e) {
      PyErr_SetString(plugin_error, e.what());
    } catch (const mb::EpisodeFailure& e) {
      PyErr_SetString(episode_failure, e.what());
    } catch (const mb::InvalidArgument& e) {
      PyErr_SetString(invalid_argument, e.what());
    } catch (const mb::Error& e) {
      PyErr_SetString(error, e.what());
    }
  });

  m.def(
      "list_tasks", [] { return updRegistry().getNames(mb::PluginKind::Task); },
      "The registered task names.");
  m.def(
      "list_plugins",
      [] {
        const mb::PluginRegistry& r = updRegistry();
        py::list out;
        for (const mb::PluginEntry& e : r.getEntries())
          out.append(py::dict(py::arg("kind") = mb::toString(e.kind), py::arg("name") = e.name,
                              py::arg("summary") = e.summary,
                              py::arg("library") = r.getLibraries()[e.library].path));
        return out;
      },
      "Every registered plugin: kind, name, summary, library.");
  m.def(
      "list_load_failures",
      [] {
        py::list out;
        for (const mb::LoadFailure& f : updRegistry().getFailures())
          out.append(py::make_tuple(f.path, f.message));
        return out;
      },
      "(path, message) of every library the registry refused.");
  m.def("get_search_path", &mb::PluginRegistry::calcDefaultSearchPath,
        "The plugin directories searched, in order.");
  m.def("has_rendered", [] { return g_rendered.load(); },
        "Whether this process has made a renderer (an EGL context).");
  m.def("get_version", &mb::getManibenchVersion);

  py::class_<PyEnvironment>(m, "Environment")
      .def(py::init<const std::string&, const std::vector<std::string>&,
                    const std::vector<std::string>&, bool, bool>(),
           py::arg("environment_id"), py::arg("config_files"), py::arg("overrides"),
           py::arg("stop_on_success"), py::arg("float32_vectors") = false)
      .def("reset", &PyEnvironment::reset, py::arg("object_id"), py::arg("seed"))
      .def("step", &PyEnvironment::step, py::arg("action"))
      .def("get_observation", &PyEnvironment::getObservation)
      .def("render", &PyEnvironment::render, py::arg("width"), py::arg("height"))
      .def("save_state", &PyEnvironment::saveState)
      .def("restore_state", &PyEnvironment::restoreState, py::arg("blob"))
      .def("describe", &PyEnvironment::describe)
      .def("list_objects", &PyEnvironment::listObjects, py::arg("split"))
      .def("choose_object", &PyEnvironment::chooseObject, py::arg("split"), py::arg("seed"))
      .def_property_readonly("object_id", [](const PyEnvironment& e) { return e.get().getObjectId(); })
      .def_property_readonly("seed", [](const PyEnvironment& e) { return e.get().getSeed(); })
      .def_property_readonly("elapsed_steps",
                             [](const PyEnvironment& e) { return e.get().getElapsedSteps(); })
      .def_property_readonly("closed", &PyEnvironment::isClosed)
      .def("close", &PyEnvironment::close)
      .def(
          "serve_steps",
          [](PyEnvironment& e, StepBlock& block, std::size_t slot, double spin_wait, int parent_pid,
             bool same_step) { return int(e.serveSteps(block, slot, spin_wait, parent_pid, same_step)); },
          py::arg("block"), py::arg("slot"), py::arg("spin_wait"), py::arg("parent_pid"),
          py::arg("same_step") = false,
          "make_vec's worker loop: answers the block's steps until the parent posts ToPipe "
          "(returns SERVE_TO_PIPE), an ended episode gets a step (SERVE_AUTO_RESET) or, with "
          "same_step, a step ends the episode (SERVE_EPISODE_ENDED).")
      .def("get_last_step", &PyEnvironment::getLastStep,
           "(reward, terminated, truncated, success, flags, values) of serve_steps' last step.");

  bindStepBlock(m);
}
