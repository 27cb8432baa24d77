// The kit's version, apart from the ABI's (abi.h) and the SDK's: the kit is
// source code compiled into each plugin, so a change to it never affects a
// plugin already built. A minor version adds, a major one changes or
// removes (sdk/kit/README.md has the history).
#pragma once

#define MANIBENCH_KIT_VERSION_MAJOR 2
#define MANIBENCH_KIT_VERSION_MINOR 3
