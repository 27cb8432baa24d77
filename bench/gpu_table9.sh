#!/usr/bin/env bash
# bench/gpu_table9.sh: the GPU check of docs/learning.md ("CUDA"), on a
# machine with an NVIDIA GPU and PyTorch (its libtorch is what this builds
# against). Two modes:
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
#     and writes the curve (DIR/curve.csv: iteration, loss, success).
#
#   bench/gpu_table9.sh --model-only --deps DIR [--out DIR]
#     Where only PyTorch is there (no Eigen, Simbody, HDF5: no environment,
#     so no demonstrations or evaluation): builds the learning module's
#     model unit (bench/gpu/CMakeLists.txt) with yaml-cpp and GoogleTest
#     from DIR (include/, lib/: Debian's packages unpacked), runs its model
#     tests with their CUDA halves, times BC, TD3+BC and BCQ with PointNet +
#     Transformer on the GPU beside the CPU, and round-trips a CUDA-trained
#     checkpoint to the CPU.
#
# Both fit 10 minutes on an H200 with 16 cores (the model-only one: about 5).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
mode=full iterations=2000 demos="" out="$root/gpu-table9" deps=""
while [ $# -gt 0 ]; do
  case $1 in
    --model-only) mode=model ;;
    --iterations) iterations=$2; shift ;;
    --demos) demos=$(realpath "$2"); shift ;;
    --out) out=$2; shift ;;
    --deps) deps=$(realpath "$2"); shift ;;
    *) echo "usage: bench/gpu_table9.sh [--model-only --deps DIR] [--iterations N] [--demos FILE.h5] [--out DIR]" >&2; exit 2 ;;
  esac
  shift
done
mkdir -p "$out"; out=$(realpath "$out")
torch_prefix=$(python3 -c 'import torch; print(torch.utils.cmake_prefix_path)')
python3 -c 'import torch; print("PyTorch", torch.__version__, "CUDA", torch.version.cuda, "C++11 ABI", torch._C._GLIBCXX_USE_CXX11_ABI, "GPU:", torch.cuda.is_available() and torch.cuda.get_device_name(0))'
cores=$(nproc)
stamp() { date +%s.%N; }
since() { python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.1f} s')" "$1" "$(stamp)"; }

if [ "$mode" = model ]; then
  [ -n "$deps" ] || { echo "--model-only needs --deps DIR (yaml-cpp and GoogleTest: include/, lib/)" >&2; exit 2; }
  export LD_LIBRARY_PATH="$deps/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  build=${BUILD_DIR:-/tmp/manibench-build-model}  # not under --out: only logs go there
  t=$(stamp)
  cmake -S "$root/bench/gpu" -B "$build" -G Ninja -DCMAKE_PREFIX_PATH="$torch_prefix" \
    -DYAML_CPP_ROOT="$deps" -DGTEST_ROOT="$deps" > "$out/cmake.log" 2>&1 || { tail -30 "$out/cmake.log"; exit 1; }
  ninja -C "$build" -j "$cores" > "$out/build.log" 2>&1 || { grep -B2 -A12 'error' "$out/build.log" | head -80 || true; exit 1; }
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

# --- the whole path ---------------------------------------------------------------------
build=$root/build-gpu
t=$(stamp)
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$torch_prefix" \
  -DBUILD_TESTING=OFF > "$out/cmake.log" 2>&1 || { tail -30 "$out/cmake.log"; exit 1; }
ninja -C "$build" -j "$cores" manibench manibench-train manibench_all_plugins manibench_learning_bench \
  > "$out/build.log" 2>&1 || { grep -B2 -A12 'error' "$out/build.log" | head -80; exit 1; }
echo "built manibench against $torch_prefix in $(since "$t")"
mb=$build/bin/manibench
env_id=OpenCabinetDrawer_2000_link_0-v0
if [ -z "$demos" ]; then
  t=$(stamp)
  "$mb" demos generate $env_id --policy open_cabinet_expert --controller mobile_panda_ee --per-object 300 \
    --workers "$cores" --no-progress --out "$out/drawer300.h5"
  "$mb" demos convert "$out/drawer300.h5" --obs pointcloud --workers "$cores" --no-progress --out "$out/drawer300_pc.h5"
  demos=$out/drawer300_pc.h5
  echo "300 demonstrations generated and converted in $(since "$t")"
fi
run=$out/bc_pnt_cuda
rm -rf "$run"
t=$(stamp)
"$mb" train bc --net pn_transformer --demos "$demos" --device cuda --threads 4 --normalize-state \
  --iterations "$iterations" --log-every 50 --checkpoint-every "$iterations" --eval-every "$iterations" \
  --eval-episodes 25 --eval-workers "$cores" --no-progress --out "$run"
echo "trained and evaluated in $(since "$t")"
grep -q '^device: cpu$' "$run/policy.yaml" && echo "policy.yaml evaluates on the cpu"
cuda_its=$(tail -1 "$run/log.csv" | awk -F, '{print $NF}')
cpu_line=$("$build/bin/manibench_learning_bench" --net pn_transformer --batch 128 --threads "$cores" --seconds 20 --device cpu 2>/dev/null)
echo "BC PointNet + Transformer, batch 128: CUDA $cuda_its it/s (training, data included); CPU ($cores threads): $cpu_line"
# The curve: each log row's loss, and the success of the evaluations.
awk -F, 'NR == FNR { if (FNR > 1) success[$1] = $5; next }
         FNR == 1 { print "iteration,loss,success"; next }
         { print $1 "," $3 "," (($1 in success) ? success[$1] : "") }' "$run/eval.csv" "$run/log.csv" > "$out/curve.csv"
tail -3 "$out/curve.csv"
