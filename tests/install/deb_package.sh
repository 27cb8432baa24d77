#!/usr/bin/env bash
# The Debian package of `make package`: cpack builds the .deb from the build
# tree; its control file lists dependencies computed by dpkg-shlibdeps; it
# holds the Python package in Debian's place; unpacked with dpkg -x into a
# temporary root, its /usr passes installed_checks.sh with the source and
# build trees hidden, as the relocated install does.
#   deb_package.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$(realpath "$1") source=$(realpath "$2")
fail() { echo "FAIL: $*" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

(cd "$work" && cpack -G DEB --config "$build/CPackConfig.cmake" -B "$work/package") >"$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log"; fail "cpack -G DEB"; }
debs=("$work"/package/manibench_*_amd64.deb)
[[ -f "${debs[0]}" ]] || { cat "$work/cpack.log"; fail "no manibench_<version>_amd64.deb"; }
deb=${debs[0]}
echo "package: $(basename "$deb"), $(du -h "$deb" | cut -f1)"

info=$(dpkg-deb -I "$deb")
depends=$(grep -E "^ Depends:" <<<"$info") || fail "no Depends in dpkg-deb -I:"$'\n'"$info"
echo "$depends"
# From dpkg-shlibdeps (libraries the binaries link), and the interpreter.
for package in libsimbody libyaml-cpp libassimp libhdf5 libegl1 libc6 libstdc++6 python3 python3-numpy; do
  grep -q "$package" <<<"$depends" || fail "Depends lacks $package"
done

dpkg -x "$deb" "$work/root"
contents=$(dpkg-deb -c "$deb")
for path in ./usr/bin/manibench ./usr/share/manibench/robots/mobile_panda_dual.urdf \
            ./usr/lib/python3/dist-packages/manibench/__init__.py ./usr/include/manibench/sdk.hpp \
            ./usr/lib/cmake/manibench/manibenchConfig.cmake; do
  grep -qF " $path" <<<"$contents" || fail "the package lacks $path"
done

bash "$source/tests/install/installed_checks.sh" --hide "$source" --hide "$build" "$work/root/usr" "$work"
echo "deb package: OK"
