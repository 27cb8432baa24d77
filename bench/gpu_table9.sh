#!/usr/bin/env bash
# bench/gpu_table9.sh: the GPU check of docs/learning.md ("CUDA"), on a
# machine with an NVIDIA GPU and PyTorch (its libtorch is what this builds
# against). Three modes:
#
#   bench/gpu_table9.sh [--iterations N] [--demos FILE.h5] [--out DIR]
#     The whole path, where manibench builds (Debian's development packages,
#     scripts/install-deps): builds manibench against PyTorch's libtorch,
#     generates 300 drawer demonstrations and converts them to point clouds
#     (or reads FILE.h5, a converted file), trains BC with PointNet +
#     Transformer on CUDA for N iterations (default 2000), prints its
#     iterations/s beside the CPU's (the same network in
#     manibench_learning_bench), evaluates the checkpoint on the CPU through
#     torch_policy (policy.yaml says `device: cpu`: the device round trip)
#     and writes the curve (DIR/curve_bc.csv: iteration, loss, success).
#
#   bench/gpu_table9.sh --bundle [--iterations N] [--algorithms bc,td3bc,bcq] [--out DIR]
#     The same where only PyTorch is there, with .gpu-bundle/ carried (made
#     on the Debian machine by bench/gpu_bundle.sh: manibench, its plugins,
#     the core's static libraries, their shared libraries and headers):
#     sources .gpu-bundle/enter.sh, builds the learning module
#     (bench/gpu/CMakeLists.txt -DMANIBENCH_PREBUILT) against PyTorch's
#     libtorch into the bundle's prefix, then generates, converts, trains
#     each algorithm (default bc; N default 3000: 100 s at the 30 it/s BC
#     measured on the H200) and evaluates as above.
#
#   bench/gpu_table9.sh --model-only --deps DIR [--out DIR]
#     Where only PyTorch is there and nothing is carried but yaml-cpp and
#     GoogleTest (DIR: include/, lib/; .gpu-bundle's sys/ will do): builds the
#     learning module's model unit (bench/gpu/CMakeLists.txt), runs its model
#     tests with their CUDA halves, times BC, TD3+BC and BCQ with PointNet +
#     Transformer on the GPU beside the CPU, and round-trips a CUDA-trained
#     checkpoint to the CPU.
#
# Shared options: --device cuda|cpu (what trains; cpu checks the path on a
# machine without a GPU), --per-object N (demonstrations, default 300),
# --eval-episodes N (default 25), --work DIR (demonstrations and training
# directories, default /tmp/manibench-table9: large), --out DIR (what
# matters, in at most 8 files of at most 16 MiB: table9.log, results.csv,
# curve_ALG.csv, the build's logs; default gpu-table9/).
# Each fits one 10-minute command on an H200 with 16 cores (the model-only
# one: about 3 minutes).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
mode=full iterations="" demos="" out="$root/gpu-table9" deps="" algorithms=bc device=cuda
per_object=300 eval_episodes=25 work=/tmp/manibench-table9 python=${PYTHON:-python3}
usage="usage: bench/gpu_table9.sh [--bundle | --model-only --deps DIR] [--iterations N] [--algorithms bc,td3bc,bcq]
       [--device cuda|cpu] [--per-object N] [--eval-episodes N] [--demos FILE.h5] [--work DIR] [--out DIR]"
while [ $# -gt 0 ]; do
  case $1 in
    --model-only) mode=model ;;
    --bundle) mode=bundle ;;
    --iterations) iterations=$2; shift ;;
    --algorithms) algorithms=$2; shift ;;
    --device) device=$2; shift ;;
    --per-object) per_object=$2; shift ;;
    --eval-episodes) eval_episodes=$2; shift ;;
    --demos) demos=$(realpath "$2"); shift ;;
    --work) work=$2; shift ;;
    --out) out=$2; shift ;;
    --deps) deps=$(realpath "$2"); shift ;;
    *) echo "$usage" >&2; exit 2 ;;
  esac
  shift
done
[ -n "$iterations" ] || { [ $mode = bundle ] && iterations=3000 || iterations=2000; }
mkdir -p "$out" "$work"; out=$(realpath "$out") work=$(realpath "$work")
exec > >(tee "$out/table9.log") 2>&1
tee_pid=$!
trap 'exec >&- 2>&-; wait $tee_pid' EXIT  # the log is whole when the script returns
torch_prefix=$($python -c 'import torch; print(torch.utils.cmake_prefix_path)')
$python -c 'import torch; print("PyTorch", torch.__version__, "CUDA", torch.version.cuda, "C++11 ABI", torch._C._GLIBCXX_USE_CXX11_ABI, "GPU:", torch.cuda.is_available() and torch.cuda.get_device_name(0))'
cores=$(nproc)
stamp() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(stamp)" 'BEGIN { printf "%.1f s", b - a }'; }
build_failed() { grep -B2 -A12 'error' "$1" | head -80 || true; exit 1; }

if [ "$mode" = model ]; then
  [ -n "$deps" ] || { echo "--model-only needs --deps DIR (yaml-cpp and GoogleTest: include/, lib/)" >&2; exit 2; }
  export LD_LIBRARY_PATH="$deps/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  build=${BUILD_DIR:-/tmp/manibench-build-model}  # not under --out: only logs go there
  t=$(stamp)
  cmake -S "$root/bench/gpu" -B "$build" -G Ninja -DCMAKE_PREFIX_PATH="$torch_prefix" \
    -DYAML_CPP_ROOT="$deps" -DGTEST_ROOT="$deps" > "$out/cmake.log" 2>&1 || { tail -30 "$out/cmake.log"; exit 1; }
  ninja -C "$build" -j "$cores" > "$out/build.log" 2>&1 || build_failed "$out/build.log"
  echo "built the model unit against $torch_prefix in $(since "$t")"
  t=$(stamp)
  "$build/learning_networks_test" > "$out/tests.log" 2>&1 && echo "model tests passed in $(since "$t")" \
    || { grep -E 'FAILED|Failure|error' -A4 "$out/tests.log" | head -60 || true; echo "model tests FAILED"; }
  grep -E '^\[  (PASSED|FAILED|SKIPPED)' "$out/tests.log" || true
  bench=$build/manibench_learning_bench
  {
    "$bench" --net pn_transformer --batch 128 --threads "$cores" --seconds 20 --device cpu
    "$bench" --net pn_transformer --batch 128 --threads "$cores" --seconds 20 --device cuda --checkpoint "$build/bc_cuda.pt"
    "$bench" --algorithm td3bc --net pn_transformer --batch 64 --threads "$cores" --seconds 15 --device cuda
    "$bench" --algorithm bcq --net pn_transformer --batch 64 --threads "$cores" --seconds 15 --device cuda
  } 2>&1 | tee "$out/speed.txt"
  exit 0
fi

# --- building: manibench whole, or the learning module against the bundle -----------------
host() { "$@"; }  # the toolchain and Python, with the machine's own libraries
t=$(stamp)
if [ "$mode" = full ]; then
  build=$root/build-gpu
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$torch_prefix" \
    -DBUILD_TESTING=OFF > "$out/cmake.log" 2>&1 || { tail -30 "$out/cmake.log"; exit 1; }
  ninja -C "$build" -j "$cores" manibench manibench-train manibench_all_plugins manibench_learning_bench \
    > "$out/build.log" 2>&1 || build_failed "$out/build.log"
  mb=$build/bin/manibench bench=$build/bin/manibench_learning_bench
  echo "built manibench against $torch_prefix in $(since "$t")"
else
  [ -f "$root/.gpu-bundle/enter.sh" ] || { echo "--bundle needs .gpu-bundle/ (bench/gpu_bundle.sh, carried with the tree)" >&2; exit 2; }
  # The bundle's static libraries were compiled with the C++11 string ABI
  # (GCC's default): a libtorch without it cannot link them.
  [ "$($python -c 'import torch; print(int(torch._C._GLIBCXX_USE_CXX11_ABI))')" = 1 ] ||
    { echo "this PyTorch's libtorch uses the old C++ string ABI; the bundle's libraries need the C++11 one" >&2; exit 1; }
  # shellcheck source=/dev/null
  source "$root/.gpu-bundle/enter.sh"
  host() { LD_LIBRARY_PATH=$MANIBENCH_HOST_LD_LIBRARY_PATH "$@"; }
  mb=$MANIBENCH_PREBUILT/bin/manibench
  echo "bundle unpacked into $MANIBENCH_PREBUILT in $(since "$t"): $(grep -o 'commit.*' "$MANIBENCH_PREBUILT/README")"
  "$mb" list > "$out/list.txt" 2>&1 || { cat "$out/list.txt"; echo "the bundle's manibench does not run here (ldd: $(ldd "$mb" | grep -c 'not found') missing)"; exit 1; }
  t=$(stamp)
  build=${BUILD_DIR:-/tmp/manibench-build-bundle}
  host cmake -S "$root/bench/gpu" -B "$build" -G Ninja -DCMAKE_PREFIX_PATH="$torch_prefix" \
    -DMANIBENCH_PREBUILT="$MANIBENCH_PREBUILT" > "$out/cmake.log" 2>&1 || { tail -30 "$out/cmake.log"; exit 1; }
  host ninja -C "$build" -j "$cores" manibench-train manibench_learning_runtime manibench_torch_policy \
    manibench_learning_bench > "$out/build.log" 2>&1 || build_failed "$out/build.log"
  bench=$build/manibench_learning_bench
  echo "built the learning module against $torch_prefix and the bundle in $(since "$t")"
fi

# --- the demonstrations ---------------------------------------------------------------------
env_id=OpenCabinetDrawer_2000_link_0-v0
if [ -z "$demos" ]; then
  t=$(stamp)
  "$mb" demos generate $env_id --policy open_cabinet_expert --controller mobile_panda_ee --per-object "$per_object" \
    --workers "$cores" --no-progress --out "$work/drawer$per_object.h5"
  "$mb" demos convert "$work/drawer$per_object.h5" --obs pointcloud --workers "$cores" --no-progress \
    --out "$work/drawer${per_object}_pc.h5"
  demos=$work/drawer${per_object}_pc.h5
  echo "$per_object demonstrations generated and converted in $(since "$t")"
fi

# --- the trainings: on $device, evaluated on the CPU through torch_policy -------------------
echo "algorithm,network,device,iterations,iterations_per_second,eval_episodes,success_rate" > "$out/results.csv"
log_every=$((iterations < 50 ? iterations : 50))
threads=$([ "$device" = cuda ] && echo 4 || echo "$cores")
for alg in ${algorithms//,/ }; do
  run=$work/${alg}_pnt_$device
  rm -rf "$run"
  t=$(stamp)
  "$mb" train "$alg" --net pn_transformer --demos "$demos" --device "$device" --threads "$threads" --normalize-state \
    --iterations "$iterations" --log-every "$log_every" --checkpoint-every "$iterations" --eval-every "$iterations" \
    --eval-episodes "$eval_episodes" --eval-workers "$cores" --no-progress --out "$run"
  echo "$alg: trained and evaluated in $(since "$t")"
  grep -q '^device: cpu$' "$run/policy.yaml" && echo "$alg: policy.yaml evaluates on the cpu"
  its=$(tail -1 "$run/log.csv" | awk -F, '{print $NF}')
  success=$(tail -1 "$run/eval.csv" | awk -F, '{print $5}')
  echo "$alg,pn_transformer,$device,$iterations,$its,$eval_episodes,$success" >> "$out/results.csv"
  echo "$alg PointNet + Transformer: $its it/s on $device (training, data included); success $success on $eval_episodes episodes (CPU, torch_policy)"
  # The curve: each log row's loss, and the success of the evaluations.
  awk -F, 'NR == FNR { if (FNR > 1) success[$1] = $5; next }
           FNR == 1 { print "iteration,loss,success"; next }
           { print $1 "," $3 "," (($1 in success) ? success[$1] : "") }' "$run/eval.csv" "$run/log.csv" > "$out/curve_$alg.csv"
  tail -2 "$out/curve_$alg.csv"
done
if [ "$device" = cuda ]; then
  cpu_line=$("$bench" --net pn_transformer --batch 128 --threads "$cores" --seconds 15 --device cpu 2>/dev/null)
  echo "BC PointNet + Transformer, batch 128, on the CPU ($cores threads, no data): $cpu_line"
fi
cat "$out/results.csv"
