// Everything the turntable_family library registers, in one place.
#include "turntable.hpp"

MANIBENCH_REGISTER_TASK(turntable::TurntableTask, "Turntable-v0",
                        "a rod on a vertical hinge (3 lengths x 3 masses) turns to a heading and stops");
MANIBENCH_REGISTER_POLICY(turntable::TurntableExpert, "turntable_expert", "proportional control for Turntable-v0");
MANIBENCH_PLUGIN_LIBRARY("turntable_family", "1.0.0");
