// The `python` policy: a policy written in Python, run by an interpreter
// embedded in the process that runs the episodes (an evaluation worker, a
// `manibench run`). Its configuration names the file:
//
//   file: path/to/solution.py   # defines the policy class
//   class: UserPolicy           # optional: the class to use (default:
//                               # UserPolicy, else the only class with act)
//   dtypes: compact             # optional: compact (float32 vectors and
//                               # uint8 rgbd rgb, as manibench.make's
//                               # default) or cpp (float64, float rgb)
//
// The class follows ManiSkill's evaluation kit (supplement B.5): act(obs)
// returns the action; reset() (or reset(seed)) is optional; __init__ takes
// nothing or one argument, a dict describing the task (task, obs_mode,
// observation_dim, action_dim, observation_segments, action_segments).
// Observations are numpy arrays as manibench.make returns them: the state
// vector, or dicts xyz/rgb/seg/agent (pointcloud), rgb/depth/seg/agent
// (rgbd). A Python exception is a plugin error whose message is the
// traceback, so the evaluation kit fails only that episode and shows it.
//
// A plugin like any other: it includes only the SDK (and pybind11).
#include <manibench/sdk.hpp>

#include <pybind11/embed.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <dlfcn.h>

#include <cmath>
#include <cstring>
#include <string>

namespace py = pybind11;
namespace sdk = manibench::sdk;

namespace {

// Starts the interpreter once per process and leaves it running (numpy
// cannot be initialized twice; the process ends with it). In a Python
// process (the manibench package) it already runs and is used as is.
void ensureInterpreter() {
  if (Py_IsInitialized()) return;
  // The host loaded this plugin, and with it libpython, privately
  // (RTLD_LOCAL); extension modules such as numpy's look the C API up in
  // the global scope, so make libpython's symbols global first.
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&Py_IsInitialized), &info) && info.dli_fname)
    dlopen(info.dli_fname, RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD);
  py::initialize_interpreter(false);  // the host keeps its signal handlers
  PyEval_SaveThread();                // every call below takes the GIL itself
}

// A Python exception as text: the traceback, then the exception.
std::string formatPythonError(py::error_already_set& e) {
  try {
    py::object format = py::module_::import("traceback").attr("format_exception");
    std::string text;
    for (py::handle line : format(e.type(), e.value(), e.trace())) text += line.cast<std::string>();
    while (!text.empty() && text.back() == '\n') text.pop_back();
    return text;
  } catch (...) {
    return e.what();
  }
}

template <typename T>
py::array_t<T> copyRows(const T* data, std::vector<py::ssize_t> shape) {
  py::array_t<T> out(shape);
  if (out.size() > 0) std::memcpy(out.mutable_data(), data, sizeof(T) * std::size_t(out.size()));
  return out;
}

py::array copyMasks(const std::uint8_t* data, std::vector<py::ssize_t> shape) {
  py::array out(py::dtype("bool"), shape);
  if (out.size() > 0) std::memcpy(out.mutable_data(), data, std::size_t(out.size()));
  return out;
}

py::list toSegments(const sdk::Layout& layout) {
  py::list out;
  for (const sdk::Segment& s : layout.segments)
    out.append(py::dict(py::arg("name") = s.name, py::arg("offset") = s.offset,
                        py::arg("size") = s.size));
  return out;
}

// The number of parameters `callable` takes (bound methods without self).
std::size_t countParameters(const py::object& callable) {
  py::object signature = py::module_::import("inspect").attr("signature")(callable);
  return py::len(signature.attr("parameters"));
}

class PythonPolicy : public sdk::Policy {
 public:
  PythonPolicy(const sdk::Config& config, const sdk::PolicyContext& context)
      : mode_(context.observation_mode), action_dim_(context.action.dim) {
    const std::string file = config.get<std::string>("file", "");
    const std::string dtypes = config.get<std::string>("dtypes", "compact");
    if (dtypes != "compact" && dtypes != "cpp")
      throw sdk::Error("the python policy's dtypes must be compact or cpp, got '" + dtypes + "'",
                       MB_INVALID_ARGUMENT);
    float32_ = dtypes == "compact";
    if (file.empty())
      throw sdk::Error("the python policy needs `file: path/to/solution.py` in its configuration",
                       MB_INVALID_ARGUMENT);
    const std::string class_name = config.get<std::string>("class", "");
    ensureInterpreter();
    py::gil_scoped_acquire gil;
    try {
      py::object util = py::module_::import("importlib.util");
      py::object spec = util.attr("spec_from_file_location")("manibench_user_policy", file);
      if (spec.is_none()) throw sdk::Error("cannot load '" + file + "' as Python", MB_INVALID_ARGUMENT);
      py::object module = util.attr("module_from_spec")(spec);
      // Importable by its name, as a script's own module would be.
      py::module_::import("sys").attr("modules")["manibench_user_policy"] = module;
      spec.attr("loader").attr("exec_module")(module);
      py::object cls = findClass(module, class_name, file);
      py::dict description;
      description["task"] = context.task_name;
      description["obs_mode"] = context.observation_mode;
      description["observation_dim"] = context.observation.dim;
      description["action_dim"] = context.action.dim;
      description["observation_segments"] = toSegments(context.observation);
      description["action_segments"] = toSegments(context.action);
      policy_ = countParameters(cls) == 0 ? cls() : cls(description);
      if (py::hasattr(policy_, "reset")) reset_parameters_ = countParameters(policy_.attr("reset"));
    } catch (py::error_already_set& e) {
      throw sdk::Error(file + ": " + formatPythonError(e), MB_ERROR);
    }
  }

  ~PythonPolicy() override {
    py::gil_scoped_acquire gil;
    policy_ = py::object();
  }

  void reset(uint64_t seed) override {
    py::gil_scoped_acquire gil;
    try {
      if (!py::hasattr(policy_, "reset")) return;
      if (reset_parameters_ == 0)
        policy_.attr("reset")();
      else
        policy_.attr("reset")(seed);
    } catch (py::error_already_set& e) {
      throw sdk::Error(formatPythonError(e), MB_ERROR);
    }
  }

  Eigen::VectorXd act(const sdk::Observation& o) override {
    py::gil_scoped_acquire gil;
    try {
      py::object result = policy_.attr("act")(makeObservation(o));
      py::array_t<double, py::array::c_style | py::array::forcecast> action =
          py::module_::import("numpy").attr("asarray")(result, "float64");
      if (action.ndim() != 1)
        throw sdk::Error("act() returned an array of " + std::to_string(action.ndim()) +
                             " dimensions; the action is a vector of " + std::to_string(action_dim_),
                         MB_INVALID_ARGUMENT);
      return Eigen::Map<const Eigen::VectorXd>(action.data(), action.shape(0));
    } catch (py::error_already_set& e) {
      throw sdk::Error(formatPythonError(e), MB_ERROR);
    }
  }

 private:
  static py::object findClass(const py::object& module, const std::string& name,
                              const std::string& file) {
    if (!name.empty()) {
      if (!py::hasattr(module, name.c_str()))
        throw sdk::Error(file + " defines no class '" + name + "'", MB_INVALID_ARGUMENT);
      return module.attr(name.c_str());
    }
    if (py::hasattr(module, "UserPolicy")) return module.attr("UserPolicy");
    py::object found;
    int count = 0;
    py::object isclass = py::module_::import("inspect").attr("isclass");
    for (auto item : module.attr("__dict__").cast<py::dict>()) {
      py::object value = py::reinterpret_borrow<py::object>(item.second);
      if (isclass(value).cast<bool>() && py::hasattr(value, "act") &&
          value.attr("__module__").cast<std::string>() == "manibench_user_policy") {
        found = value;
        ++count;
      }
    }
    if (count != 1)
      throw sdk::Error(file + " defines " + std::to_string(count) +
                           " classes with act(); name one with `class: NAME` (or call it UserPolicy)",
                       MB_INVALID_ARGUMENT);
    return found;
  }

  py::object makeObservation(const sdk::Observation& o) const {
    py::array state = copyRows(o.state.data(), {py::ssize_t(o.state.size())});
    if (float32_) state = state.attr("astype")("float32");
    if (mode_ == "pointcloud") {
      const py::ssize_t n = o.points_xyz.rows(), k = o.mask_count;
      py::dict out;
      out["xyz"] = copyRows(o.points_xyz.data(), {n, 3});
      out["rgb"] = copyRows(o.points_rgb.data(), {n, 3});
      out["seg"] = copyMasks(o.points_mask.data(), {n, k});
      out["agent"] = state;
      return std::move(out);
    }
    if (mode_ == "rgbd") {
      const py::ssize_t h = o.image_height, w = o.image_width, c = o.camera_count, k = o.mask_count;
      py::dict out;
      if (float32_) {  // the bytes back: the floats are byte / 255.0f exactly
        py::array_t<std::uint8_t> rgb({h, w, 3 * c});
        std::uint8_t* dst = rgb.mutable_data();
        for (py::ssize_t i = 0; i < rgb.size(); ++i)
          dst[i] = std::uint8_t(std::lround(o.image_rgb.data()[i] * 255.0f));
        out["rgb"] = rgb;
      } else {
        out["rgb"] = copyRows(o.image_rgb.data(), {h, w, 3 * c});
      }
      out["depth"] = copyRows(o.image_depth.data(), {h, w, c});
      out["seg"] = copyMasks(o.image_masks.data(), {h, w, k * c});
      out["agent"] = state;
      return std::move(out);
    }
    return std::move(state);
  }

  std::string mode_;
  bool float32_ = true;  // dtypes: compact
  uint32_t action_dim_ = 0;
  py::object policy_;
  std::size_t reset_parameters_ = 0;
};

}  // namespace

MANIBENCH_REGISTER_POLICY(PythonPolicy, "python",
                          "a Python policy class (config `file: solution.py`), embedded interpreter");
MANIBENCH_PLUGIN_LIBRARY("manibench_python_policy", "1.0.0");
