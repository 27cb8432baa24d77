// Constants shared by the host and the plugins. No dependencies, so that
// the host may include it without the rest of the SDK.
#pragma once

namespace manibench::sdk {

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace manibench::sdk
