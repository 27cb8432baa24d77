// Everything the slider_family library registers, in one place.
#include "slider.hpp"

MANIBENCH_REGISTER_TASK(slider::SliderTask, "Slider-v0", "a block on a rail (3 lengths x 3 masses) stops at a target");
MANIBENCH_REGISTER_POLICY(slider::SliderExpert, "slider_expert", "proportional control for Slider-v0");
MANIBENCH_PLUGIN_LIBRARY("slider_family", "1.0.0");
