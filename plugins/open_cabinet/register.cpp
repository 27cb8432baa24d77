// Everything the open_cabinet plugin library registers, in one place.
#include "open_cabinet.hpp"

MANIBENCH_REGISTER_TASK(open_cabinet::OpenCabinetDoorTask, "OpenCabinetDoor-v0",
                        "mobile Panda opens a cabinet door by its handle (ManiSkill v1)");
MANIBENCH_REGISTER_TASK(open_cabinet::OpenCabinetDrawerTask, "OpenCabinetDrawer-v0",
                        "mobile Panda pulls a cabinet drawer open by its handle (ManiSkill v1)");
MANIBENCH_REGISTER_POLICY_FOR_CONTROLLER(open_cabinet::OpenCabinetExpert, "open_cabinet_expert",
                                         "scripted expert for OpenCabinetDoor/Drawer-v0 over mobile_panda_ee (privileged state)",
                                         "mobile_panda_ee");
MANIBENCH_PLUGIN_LIBRARY("manibench_open_cabinet", "0.1.0");
