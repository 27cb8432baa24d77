// The manibench plugin SDK: include this one header to write tasks,
// controllers and policies. See README.md, "Writing a plugin".
#pragma once

#include <manibench/abi.h>
#include <manibench/sdk/common.hpp>
#include <manibench/sdk/controller.hpp>
#include <manibench/sdk/data.hpp>
#include <manibench/sdk/policy.hpp>
#include <manibench/sdk/random.hpp>
#include <manibench/sdk/registry.hpp>
#include <manibench/sdk/scene_view.hpp>
#include <manibench/sdk/state.hpp>
#include <manibench/sdk/task.hpp>
