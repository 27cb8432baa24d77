#include "step_block_bindings.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <manibench/error.hpp>

#include "step_block.hpp"

#include <cstring>
#include <string>
#include <vector>

namespace manibench::python {

namespace py = pybind11;
namespace mb = manibench;

// make_vec's shared block (step_block.hpp) as the package uses it: the
// parent posts and waits and reads the scalars; numpy views of the
// observation fields come from `memory` and field_offset().
void bindStepBlock(py::module_& m) {
  m.attr("SERVE_TO_PIPE") = int(ServeExit::ToPipe);
  m.attr("SERVE_AUTO_RESET") = int(ServeExit::AutoReset);
  m.attr("SERVE_EPISODE_ENDED") = int(ServeExit::EpisodeEnded);
  auto layout = [](std::size_t slots, std::size_t action_dim, std::size_t conditions,
                   std::vector<std::size_t> field_bytes) {
    StepBlockLayout l;
    l.slot_count = slots;
    l.action_dim = action_dim;
    l.condition_count = conditions;
    l.field_bytes = std::move(field_bytes);
    return l;
  };
  py::class_<StepBlock>(m, "StepBlock", py::buffer_protocol())
      .def_static(
          "create",
          [layout](std::size_t slots, std::size_t action_dim, std::size_t conditions,
                   std::vector<std::size_t> field_bytes) {
            return StepBlock::create(layout(slots, action_dim, conditions, std::move(field_bytes)));
          },
          py::arg("slots"), py::arg("action_dim"), py::arg("conditions"), py::arg("field_bytes"))
      .def_static(
          "attach",
          [layout](const std::string& name, std::size_t slots, std::size_t action_dim,
                   std::size_t conditions, std::vector<std::size_t> field_bytes) {
            return StepBlock::attach(name,
                                     layout(slots, action_dim, conditions, std::move(field_bytes)));
          },
          py::arg("name"), py::arg("slots"), py::arg("action_dim"), py::arg("conditions"),
          py::arg("field_bytes"))
      .def_property_readonly("name", &StepBlock::getName)
      .def("unlink_name", &StepBlock::unlinkName)
      .def_buffer([](StepBlock& b) {
        return py::buffer_info(b.updData(), 1, py::format_descriptor<uint8_t>::format(), 1,
                               {py::ssize_t(b.getSize())}, {py::ssize_t(1)});
      })
      .def("field_offset", &StepBlock::getFieldOffset, py::arg("slot"), py::arg("field"))
      .def(
          "post_step",
          [](StepBlock& b, py::array_t<double, py::array::c_style | py::array::forcecast> actions) {
            const StepBlockLayout& l = b.getLayout();
            if (actions.ndim() != 2 || std::size_t(actions.shape(0)) != l.slot_count ||
                std::size_t(actions.shape(1)) != l.action_dim)
              throw mb::InvalidArgument("post_step: actions must be (" +
                                          std::to_string(l.slot_count) + ", " +
                                          std::to_string(l.action_dim) + ")");
            b.post(StepCommand::Step, actions.data());
          },
          py::arg("actions"))
      .def("post_to_pipe", [](StepBlock& b) { b.post(StepCommand::ToPipe, nullptr); })
      .def(
          "wait_all",
          [](StepBlock& b, double timeout) {
            py::gil_scoped_release release;
            return b.waitAll(timeout);
          },
          py::arg("timeout"), "Waits for every slot; returns those not done in `timeout` s.")
      .def(
          "results",
          [](StepBlock& b) {
            // (rewards, terminated, truncated, success, elapsed_steps,
            //  flags, values, on_pipe, point_count) over the slots.
            const StepBlockLayout& l = b.getLayout();
            const py::ssize_t n = py::ssize_t(l.slot_count), c = py::ssize_t(l.condition_count);
            py::array_t<double> rewards(n), values({n, c});
            auto bools = [](std::vector<py::ssize_t> shape) {
              return py::array(py::dtype("bool"), std::move(shape));
            };
            py::array terminated = bools({n}), truncated = bools({n}), success = bools({n}),
                      on_pipe = bools({n}), flags = bools({n, c});
            py::array_t<int64_t> elapsed(n), points(n);
            for (py::ssize_t s = 0; s < n; ++s) {
              const StepSlotHeader& h = b.updHeader(std::size_t(s));
              rewards.mutable_at(s) = h.reward;
              static_cast<bool*>(terminated.mutable_data())[s] = h.terminated;
              static_cast<bool*>(truncated.mutable_data())[s] = h.truncated;
              static_cast<bool*>(success.mutable_data())[s] = h.success;
              static_cast<bool*>(on_pipe.mutable_data())[s] =
                  h.place == uint32_t(StepResultPlace::OnPipe);
              elapsed.mutable_at(s) = h.elapsed_steps;
              points.mutable_at(s) = h.point_count;
              bool* f = static_cast<bool*>(flags.mutable_data()) + s * c;
              const uint8_t* src = b.updFlags(std::size_t(s));
              for (py::ssize_t k = 0; k < c; ++k) f[k] = src[k] != 0;
              if (c > 0)
                std::memcpy(values.mutable_data() + s * c, b.updValues(std::size_t(s)),
                            sizeof(double) * std::size_t(c));
            }
            return py::make_tuple(rewards, terminated, truncated, success, elapsed, flags, values,
                                  on_pipe, points);
          })
      .def(
          "finish_on_pipe",
          [](StepBlock& b, std::size_t slot) { b.finish(slot, StepResultPlace::OnPipe); },
          py::arg("slot"), "Worker: the taken Step's result went through the pipe.")
      .def(
          "set_needs_reset",
          [](StepBlock& b, std::size_t slot, bool value) { b.updHeader(slot).needs_reset = value; },
          py::arg("slot"), py::arg("value"));
}

}  // namespace manibench::python
