// The StepBlock's Python class (manibench._core.StepBlock) and the
// serve_steps exit codes, bound into the module (module.cpp).
#pragma once

#include <pybind11/pybind11.h>

namespace manibench::python {

void bindStepBlock(pybind11::module_& m);

}  // namespace manibench::python
