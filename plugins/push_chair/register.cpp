// Everything the push_chair plugin library registers, in one place.
#include "push_chair.hpp"

MANIBENCH_REGISTER_TASK(push_chair::PushChairTask, "PushChair-v0",
                        "dual-arm mobile Panda pushes a swivel chair to a target on the ground (ManiSkill v1)");
MANIBENCH_REGISTER_POLICY_FOR_CONTROLLER(push_chair::PushChairExpert, "push_chair_expert",
                                         "scripted expert for PushChair-v0 over mobile_panda_ee (privileged state)",
                                         "mobile_panda_ee");
MANIBENCH_PLUGIN_LIBRARY("manibench_push_chair", "0.1.0");
