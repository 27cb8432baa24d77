#!/usr/bin/env bash
# bench/gpu_bundle_check.sh [WORK]: `bench/gpu_table9.sh --bundle` here, on
# the CPU, as the bare GPU machine would run it (docs/learning.md, "CUDA"),
# after bench/gpu_bundle.sh: in a private mount namespace (unshare, an
# unprivileged user namespace, as tests/install/installed_checks.sh) where
# /usr/include holds only what that machine has without Debian's
# development packages (glibc's, the kernel's and the C++ library's
# headers, and libtorch's with what its CMake package asks for: glog,
# gflags, protobuf; Debian's 1.13 stands in for PyTorch's) and
# /usr/lib/x86_64-linux-gnu/cmake only libtorch's packages. So the learning
# module compiles against the bundle's headers and links its libraries, or
# fails here. Then a tiny pass end to end: 3 demonstrations generated and
# converted by the bundle's manibench, BC with PointNet + Transformer
# trained 4 iterations on the CPU, evaluated through torch_policy on 2
# episodes. What it cannot show: the machine's own glibc, g++ 13, CUDA and
# PyTorch 2.x (their headers and libraries are not these).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(realpath -m "${1:-/tmp/manibench-bundle-check}")
[ -f "$root/.gpu-bundle/enter.sh" ] || { echo "no .gpu-bundle: run bench/gpu_bundle.sh first" >&2; exit 2; }
if [ "${MANIBENCH_BUNDLE_CHECK_INSIDE:-}" != 1 ]; then
  rm -rf "$work/run" "$work/out"; mkdir -p "$work"  # build/ and prebuilt/ stay: a rerun builds what changed
  cxx=$(g++ -dumpversion | cut -d. -f1)
  # What stays in /usr/include: these packages' files, as links into the real
  # folder (bound at $work/usr-include before the tmpfs covers it).
  for pkg in libc6-dev linux-libc-dev "libstdc++-$cxx-dev" libtorch-dev libgoogle-glog-dev libgflags-dev libprotobuf-dev; do
    dpkg -L "$pkg" 2>/dev/null | grep '^/usr/include/' || true
  done | sort -u > "$work/kept.txt"
  exec unshare --map-root-user --mount bash -c "
    set -e
    mkdir -p '$work/usr-include' '$work/usr-cmake'
    mount --bind /usr/include '$work/usr-include'
    mount --bind /usr/lib/x86_64-linux-gnu/cmake '$work/usr-cmake'
    mount -t tmpfs none /usr/include
    mount -t tmpfs none /usr/lib/x86_64-linux-gnu/cmake
    while read -r f; do
      if [ -d \"$work/usr-include/\${f#/usr/include/}\" ] && [ ! -L \"$work/usr-include/\${f#/usr/include/}\" ]; then mkdir -p \"\$f\";
      else mkdir -p \"\$(dirname \"\$f\")\"; ln -sfn \"$work/usr-include/\${f#/usr/include/}\" \"\$f\"; fi
    done < '$work/kept.txt'
    for d in Torch Caffe2 ATen gflags glog; do [ -e '$work/usr-cmake/'\$d ] && ln -s '$work/usr-cmake/'\$d /usr/lib/x86_64-linux-gnu/cmake/\$d; done
    [ ! -e /usr/include/eigen3 ] && [ ! -e /usr/include/yaml-cpp ] && [ ! -e /usr/include/boost ] && [ ! -e /usr/lib/x86_64-linux-gnu/cmake/yaml-cpp ]
    echo \"bundle check: /usr/include holds \$(find /usr/include -type l | wc -l) files of glibc, linux, libstdc++ and libtorch; no Eigen, Boost, yaml-cpp, nlohmann\"
    MANIBENCH_BUNDLE_CHECK_INSIDE=1 exec bash '$0' '$work'"
fi
export MANIBENCH_PREBUILT=$work/prebuilt BUILD_DIR=$work/build PYTHON=/usr/bin/python3  # Debian's, with python3-torch
"$root/bench/gpu_table9.sh" --bundle --device cpu --iterations 4 --per-object 3 --eval-episodes 2 \
  --work "$work/run" --out "$work/out"
