#!/usr/bin/env bash
# bench/gpu_bundle.sh [BUILD_DIR]: packs what the GPU machine lacks for
# `bench/gpu_table9.sh --bundle` (docs/learning.md, "CUDA"). Runs here, on
# the Debian machine, after a normal build (default build/: manibench,
# manibench_all_plugins and the learning module built). The GPU machine has
# PyTorch (its libtorch), a compiler, CMake and NVIDIA's EGL, and none of
# Debian's development packages; this writes .gpu-bundle/ at the checkout's
# root (ignored through .git/info/exclude, to carry with the tree):
#
#   prebuilt.tar.xz  a prefix, unpacked by enter.sh (default /tmp/manibench-prebuilt):
#     bin/manibench, lib/manibench/plugins/*.so, share/manibench/robots and objects
#                    the host and the task, controller and example plugins: what
#                    `demos generate`, `demos convert` and `eval` run (not
#                    manibench-train, the learning runtime or torch_policy,
#                    which link Debian's libtorch: bench/gpu/CMakeLists.txt
#                    builds them there against PyTorch's, into this prefix)
#     static/*.a     core's layers and apps' manibench_cli, which
#                    manibench_learning_data and manibench-train link
#     link.cmake     the link line of a program on those (bin/manibench's, as
#                    built here), in the bundle's terms
#     sys/lib        the shared libraries all of the above load, their closure
#                    (Simbody, assimp, urdfdom, FCL, HDF5, yaml-cpp, Boost's
#                    filesystem, GLVND's EGL, BLAS...), less glibc, libstdc++ and
#                    libgcc_s (the machine's own, newer: g++ 13) and Mesa's EGL
#                    vendor; nothing of libtorch's (nothing here links it);
#                    with GoogleTest's static libraries for the model tests
#     sys/include    the headers outside the tree that the learning sources
#                    include (computed with g++ -M over learning/src, train and
#                    policy with the build's flags: Eigen, Boost's subset,
#                    yaml-cpp, nlohmann), less those of glibc, the compiler and
#                    libtorch's (PyTorch brings its own); GoogleTest's
#   enter.sh         source it from the checkout's root: unpacks the prefix,
#                    sets LD_LIBRARY_PATH, PATH, MANIBENCH_PREBUILT and NVIDIA's
#                    EGL vendor file
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-$root/build}" && pwd)
out=$root/.gpu-bundle
exclude=$(git -C "$root" rev-parse --git-path info/exclude)
case $exclude in /*) ;; *) exclude=$root/$exclude ;; esac
mkdir -p "$(dirname "$exclude")"
grep -qx '/.gpu-bundle/' "$exclude" 2>/dev/null || echo '/.gpu-bundle/' >> "$exclude"
for f in bin/manibench apps/libmanibench_cli.a core/libmanibench_demos.a compile_commands.json; do
  [ -e "$build/$f" ] || { echo "gpu_bundle: $build/$f missing: build manibench, manibench_all_plugins and the learning module first" >&2; exit 1; }
done
stage=$(mktemp -d); trap 'rm -rf "$stage"' EXIT
p=$stage/prebuilt
mkdir -p "$p/bin" "$p/lib/manibench/plugins" "$p/share/manibench" "$p/static" "$p/sys/lib" "$p/sys/include"

# (a) The host, its plugins (not torch_policy, which is built there, nor
# python_policy: the machine's Python is another one) and the robots.
cp "$build/bin/manibench" "$p/bin/"
for so in "$build"/lib/manibench/plugins/*.so; do
  case $(basename "$so") in libmanibench_torch_policy.so|libmanibench_python_policy.so) ;; *) cp "$so" "$p/lib/manibench/plugins/" ;; esac
done
cp -rL "$root/assets/robots" "$p/share/manibench/robots"
cp -rL "$root/assets/objects" "$p/share/manibench/objects"

# (b) The static libraries, and bin/manibench's link line (manibench_cli +
# manibench::core: what manibench-train links beside the learning module)
# in the bundle's terms: static/NAME.a, sys/lib/SONAME, -lNAME for glibc's.
cp "$build/apps/libmanibench_cli.a" "$build"/core/libmanibench_*.a "$p/static/"
is_glibc() { case $1 in libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|libresolv.so*|libutil.so*|libanl.so*|libmvec.so*|ld-linux*|linux-vdso*) return 0 ;; *) return 1 ;; esac; }
is_kept_out() { is_glibc "$1" || case $1 in libstdc++.so*|libgcc_s.so*|libEGL_mesa*|libGLX_mesa*|libtorch*|libc10*) return 0 ;; *) return 1 ;; esac; }
soname() { objdump -p "$1" | awk '/SONAME/ {print $2}'; }
link=()
declare -A linked  # soname -> the file the link line named
read -ra words < <(ninja -C "$build" -t commands bin/manibench | tail -1)
after_out=0
for w in "${words[@]}"; do
  if [ $after_out = 0 ]; then [ "$w" = bin/manibench ] && after_out=1; continue; fi
  case $w in
    '&&') break ;;
    -Wl,-rpath,*) ;;
    *.o) ;;
    apps/*.a|core/*.a) link+=("static/$(basename "$w")") ;;
    */librt.a|*/libpthread.a|*/libdl.a) n=$(basename "$w" .a); link+=("-l${n#lib}") ;;
    -lpthread|-lrt|-ldl|-lm) link+=("$w") ;;
    -l*) w=$(realpath "$(g++ -print-file-name="lib${w#-l}.so")") ;&
    /*.so*)
      real=$(realpath "$w"); name=$(soname "$real"); name=${name:-$(basename "$real")}
      is_kept_out "$name" && { echo "gpu_bundle: bin/manibench links $name, which the bundle leaves out" >&2; exit 1; }
      link+=("sys/lib/$name"); linked[$name]=$real ;;
    *) echo "gpu_bundle: unexpected word in bin/manibench's link line: $w" >&2; exit 1 ;;
  esac
done
{
  echo "# Written by bench/gpu_bundle.sh from $build's bin/manibench link line"
  echo "# (manibench_cli + manibench::core), relative to this folder."
  printf 'set(MANIBENCH_PREBUILT_CORE_LINK\n'; printf '  "%s"\n' "${link[@]}"; printf ')\n'
  echo "set(MANIBENCH_PREBUILT_BUILT_WITH \"$(g++ --version | head -1)\")"
  echo "set(MANIBENCH_PREBUILT_COMMIT \"$(git -C "$root" rev-parse HEAD)\")"
} > "$p/link.cmake"

# (c) The shared-library closure of all of it, each library as the loader
# finds it (not the development link's target: Debian's libblas.so leads
# to the reference BLAS, libblas.so.3 to OpenBLAS), then what the link
# line names and the programs do not load.
{
  ldd "$p/bin/manibench" "$p"/lib/manibench/plugins/*.so 2>/dev/null
  for name in "${!linked[@]}"; do ldd "${linked[$name]}" 2>/dev/null; done
} | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}' | sort -u | while read -r name path; do
  is_kept_out "$name" || [ -e "$p/sys/lib/$name" ] || cp -L "$path" "$p/sys/lib/$name"
done
for name in "${!linked[@]}"; do [ -e "$p/sys/lib/$name" ] || cp -L "${linked[$name]}" "$p/sys/lib/$name"; done
# Every library they load resolves inside the bundle, but for those left out.
outside=$(LD_LIBRARY_PATH=$p/sys/lib ldd "$p/bin/manibench" "$p"/lib/manibench/plugins/*.so "$p"/sys/lib/*.so* 2>/dev/null |
  awk -v lib="$p/sys/lib/" '$2 == "=>" && index($3, lib) != 1 {print $1}' | sort -u |
  while read -r name; do is_kept_out "$name" || echo "$name"; done)
[ -z "$outside" ] || { echo "gpu_bundle: libraries not in the bundle: $outside" >&2; exit 1; }
# GoogleTest, for the model tests (bench/gpu/CMakeLists.txt).
for a in libgtest.a libgtest_main.a; do
  f=$(g++ -print-file-name=$a); [ -f "$f" ] && cp "$f" "$p/sys/lib/"
done

# (d) The headers: g++ -M over the learning sources with the build's flags;
# kept: outside the tree and owned by no package of glibc's, the compiler's
# or libtorch's header closure (what <torch/torch.h> and <torch/script.h>
# pull in: libtorch-dev, glog, gflags on Debian).
deps_of() {  # the compile command (JSON-free: one per line on stdin) -> the files it reads
  while IFS= read -r cmd; do
    eval "set -- $cmd"; args=()
    while [ $# -gt 0 ]; do case $1 in -o) shift ;; -c) ;; *) args+=("$1") ;; esac; shift; done
    "${args[@]}" -M | sed 's/\\$//' | tr ' ' '\n' | grep '^/' | xargs -r realpath -s || true
  done
}
commands=$(python3 - "$build/compile_commands.json" "$root" <<'PY'
import json, sys
root = sys.argv[2] + "/learning/"
for e in json.load(open(sys.argv[1])):
    f = e["file"]
    if f.startswith(root) and "/tests/" not in f:
        print(e["command"])
PY
)
first=$(head -1 <<<"$commands")
torch_probe=$stage/torch_probe.cpp
printf '#include <torch/torch.h>\n#include <torch/script.h>\n' > "$torch_probe"
torch_cmd=$(sed -E "s# -c [^ ]+# -c $torch_probe#; s# -o [^ ]+##" <<<"$first")
(cd "$build" && deps_of <<<"$commands") | grep -v "^$root/" | sort -u > "$stage/deps.txt"
(cd "$build" && deps_of <<<"$torch_cmd") | sort -u > "$stage/torch_deps.txt"
owner() { xargs -r dpkg -S 2>/dev/null | awk -F': ' '{split($1, a, ", "); for (i in a) print a[i] "\t" $2}'; }
skip=$( (owner < "$stage/torch_deps.txt" | cut -f1; printf '%s\n' libc6-dev linux-libc-dev) | sed 's/:amd64$//' | sort -u)
owner < "$stage/deps.txt" | sed 's/:amd64\t/\t/' | while IFS=$'\t' read -r pkg file; do
  case $pkg in libstdc++*-dev|libgcc*-dev) continue ;; esac
  grep -qx "$pkg" <<<"$skip" && continue
  case $file in /usr/include/*) ;; *) echo "gpu_bundle: header outside /usr/include: $file ($pkg)" >&2; exit 1 ;; esac
  mkdir -p "$p/sys/include/$(dirname "${file#/usr/include/}")"
  cp -L --preserve=timestamps "$file" "$p/sys/include/${file#/usr/include/}"
done
unowned=$(owner < "$stage/deps.txt" | cut -f2 | sort -u | comm -23 "$stage/deps.txt" - | tr '\n' ' ')
[ -z "$unowned" ] || echo "gpu_bundle: note: headers no package owns, left out: $unowned" >&2
[ -d /usr/include/gtest ] && cp -r /usr/include/gtest "$p/sys/include/"

# (e) enter.sh.
cat > "$p/README" <<EOT
manibench prebuilt prefix from bench/gpu_bundle.sh, commit $(git -C "$root" rev-parse --short HEAD), $(date -u +%F)
EOT
rm -rf "$out"; mkdir -p "$out"
tar -C "$stage" -cf - prebuilt | xz -9e -T0 > "$out/prebuilt.tar.xz"
cat > "$out/enter.sh" <<'EOT'
# Written by bench/gpu_bundle.sh: `source .gpu-bundle/enter.sh` on the GPU
# machine (any folder). Unpacks the prebuilt prefix into $MANIBENCH_PREBUILT
# (default /tmp/manibench-prebuilt) unless that bundle is already there,
# puts its libraries and bin/ first, and points GLVND's EGL at NVIDIA's
# vendor library where there is one (rendering on the GPU).
_mb_bundle=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
export MANIBENCH_PREBUILT=${MANIBENCH_PREBUILT:-/tmp/manibench-prebuilt}
if ! cmp -s "$_mb_bundle/stamp" "$MANIBENCH_PREBUILT/.stamp" 2>/dev/null; then
  rm -rf "$MANIBENCH_PREBUILT" && mkdir -p "$MANIBENCH_PREBUILT" &&
    tar -C "$MANIBENCH_PREBUILT" --strip-components=1 -xJf "$_mb_bundle/prebuilt.tar.xz" &&
    cp "$_mb_bundle/stamp" "$MANIBENCH_PREBUILT/.stamp"
fi
# The toolchain and Python keep the machine's own libraries: run them with
# LD_LIBRARY_PATH=$MANIBENCH_HOST_LD_LIBRARY_PATH (the bundle's libz, libgmp
# or libssl are Debian 12's, older than what a newer compiler may need).
[ -n "${MANIBENCH_HOST_LD_LIBRARY_PATH+set}" ] || export MANIBENCH_HOST_LD_LIBRARY_PATH=${LD_LIBRARY_PATH-}
export LD_LIBRARY_PATH=$MANIBENCH_PREBUILT/sys/lib${MANIBENCH_HOST_LD_LIBRARY_PATH:+:$MANIBENCH_HOST_LD_LIBRARY_PATH}
for _mb_d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib; do [ -d "$_mb_d" ] && LD_LIBRARY_PATH=$LD_LIBRARY_PATH:$_mb_d; done
for _mb_j in /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json /usr/share/glvnd/egl_vendor.d/10_nvidia.json; do
  [ -f "$_mb_j" ] && { export __EGL_VENDOR_LIBRARY_FILENAMES=$_mb_j; break; }
done
export PATH=$MANIBENCH_PREBUILT/bin:$PATH
unset _mb_bundle _mb_d _mb_j
EOT
sha256sum "$out/prebuilt.tar.xz" | cut -d' ' -f1 > "$out/stamp"
tree_kb=$(git -C "$root" ls-files -z | (cd "$root" && xargs -0 du -k --apparent-size 2>/dev/null) | awk '{s += $1} END {print s}')
bundle_kb=$(du -k --apparent-size -s "$out" | cut -f1)
echo "gpu_bundle: .gpu-bundle holds $((bundle_kb / 1024)).$(( (bundle_kb % 1024) * 10 / 1024 )) MiB" \
  "($(find "$p/sys/lib" -name '*.so*' | wc -l) shared libraries, $(find "$p/sys/include" -type f | wc -l) headers," \
  "$(ls "$p/static" | wc -l) static libraries); with the tracked tree ($((tree_kb / 1024)) MiB): $(( (bundle_kb + tree_kb) / 1024 )) MiB of the 64 MiB carry limit"
echo "gpu_bundle: carry \".gpu-bundle\"; on the GPU machine: bench/gpu_table9.sh --bundle --out \$OUT"
