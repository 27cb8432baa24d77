// Everything the reach plugin library registers, in one place.
#include "reach.hpp"

MANIBENCH_REGISTER_TASK(reach::ReachTask, "Reach-v0",
                        "2-link arm moves its fingertip to a target point (example family)");
MANIBENCH_REGISTER_POLICY(reach::ReachExpert, "reach_expert",
                          "scripted expert for Reach-v0: analytic inverse kinematics");
MANIBENCH_PLUGIN_LIBRARY("manibench_reach", "0.1.0");
