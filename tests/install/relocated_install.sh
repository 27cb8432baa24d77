#!/usr/bin/env bash
# A relocatable install: `cmake --install` into a temporary prefix, MOVE the
# tree, then run installed_checks.sh on the moved tree with the source and
# build trees hidden (a private mount namespace mounts an empty tmpfs over
# each), so that nothing compiled in can resolve. Also: no installed file
# names either tree.
#   relocated_install.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$(realpath "$1") source=$(realpath "$2")
fail() { echo "FAIL: $*" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/staged" >"$work/install.log" || { cat "$work/install.log"; fail "cmake --install"; }
mv "$work/staged" "$work/moved"
# Nothing installed points back (text or binary) at the trees it came from.
# Except, in a sanitized build (make sanitize), the binaries: GCC 12 writes
# the compiler's input path into ASan's global descriptors and UBSan's source
# locations without applying -ffile-prefix-map (a one-line .cpp compiled with
# -fsanitize=address or =undefined and the map keeps /abs/src/a.cpp), and CI
# compiles absolute paths. The plain build (make test) checks binaries too.
binary_files=(-a)
[[ "${MANIBENCH_SANITIZED_BUILD:-0}" == 1 ]] && binary_files=(-I)
if leaks=$(grep -rlF "${binary_files[@]}" -e "$source/" -e "$build/" "$work/moved"); then
  fail "installed files name the source or build tree:"$'\n'"$leaks"
fi
[[ -f "$work/moved/share/manibench/robots/mobile_panda_single.urdf" ]] || fail "robots not installed in share/manibench"

bash "$source/tests/install/installed_checks.sh" --hide "$source" --hide "$build" "$work/moved" "$work"
echo "relocated install: OK"
