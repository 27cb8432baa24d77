#!/usr/bin/env bash
# The checks an installed manibench must pass wherever its tree lies
# (relocated_install.sh: a moved `cmake --install` tree; deb_package.sh:
# the .deb unpacked with dpkg -x). Run with the source and build trees out
# of reach, so that a path compiled in cannot resolve.
#   installed_checks.sh [--hide DIR]... PREFIX WORK
# PREFIX: the installed tree (bin/, lib/, share/); WORK: a writable folder
# outside the hidden ones, where examples/hello_task is copied. Each --hide
# DIR (the source and build trees) gets an empty tmpfs mounted over it in a
# private mount namespace (unshare: an unprivileged user namespace) for the
# checks, so a path compiled in cannot resolve.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
hidden=()
while [[ "${1:-}" == --hide ]]; do hidden+=("$(realpath "$2")"); shift 2; done
prefix=$1 work=$2
if ((${#hidden[@]})); then
  here=$(dirname "$(realpath "$0")")
  cp -r "$here/../../examples/hello_task" "$work/hello_task"
  cp -r "$here/../../examples/turntable_family" "$work/turntable_family"
  cp "$0" "$work/installed_checks.sh"
  mounts=""
  # Deepest first: a build tree inside the source tree is covered before it.
  for dir in $(printf '%s\n' "${hidden[@]}" | awk '{ print length, $0 }' | sort -rn | cut -d' ' -f2-); do mounts+="mount -t tmpfs none '$dir' && [[ -z \"\$(ls -A '$dir')\" ]] && "; done
  exec unshare --map-root-user --mount bash -c "$mounts bash '$work/installed_checks.sh' '$prefix' '$work'"
fi
cli="$prefix/bin/manibench"
plugins=$(find "$prefix/lib" -type d -path '*/manibench/plugins')
[[ -n "$plugins" ]] || fail "no lib/.../manibench/plugins under $prefix"

# 1. The host finds its own plugins (and nothing else: no MANIBENCH_PLUGIN_PATH).
list=$(env -u MANIBENCH_PLUGIN_PATH -u MANIBENCH_DATA_DIR HOME="$work" "$cli" list)
grep -qF "  $plugins" <<<"$list" || fail "manibench list does not search $plugins:"$'\n'"$list"
for name in OpenCabinetDrawer-v0 PushChair-v0 MoveBucket-v0 open_cabinet_expert mobile_panda_ee; do
  grep -qE "^[a-z]+ +$name +.* $plugins/" <<<"$list" || fail "manibench list: no $name from $plugins:"$'\n'"$list"
done
echo "installed checks: manibench list OK ($plugins)"

# 2. A cabinet evaluation with the expert: the plugin reads the robot from
# the installed share/manibench, the expert chooses its controller.
env -u MANIBENCH_PLUGIN_PATH -u MANIBENCH_DATA_DIR HOME="$work" "$cli" eval OpenCabinetDrawer-v0 \
  --policy open_cabinet_expert --split train --objects 2000_link_0 --episodes-per-object 1 \
  --out "$work/eval" --no-progress >"$work/eval.log" 2>&1 || { cat "$work/eval.log"; fail "manibench eval"; }
summary="$work/eval/summary.csv"
[[ -f "$summary" ]] || fail "no $summary"
# object,episodes,successes,...: its one episode succeeded
awk -F, 'NR > 1 && $2 > 0 && $3 == $2 { ok = 1 } END { exit !ok }' "$summary" ||
  { cat "$work/eval.log" "$summary"; fail "the expert did not succeed"; }
echo "installed checks: eval OpenCabinetDrawer-v0 --policy open_cabinet_expert OK"

# 3. An out-of-tree plugin built against the installed CMake package, run
# by the installed host.
cmake -S "$work/hello_task" -B "$work/hello_build" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" >"$work/hello.log" 2>&1 &&
  cmake --build "$work/hello_build" >>"$work/hello.log" 2>&1 || { cat "$work/hello.log"; fail "hello_task build"; }
grep -q "^CMAKE_BUILD_TYPE:STRING=Release$" "$work/hello_build/CMakeCache.txt" ||
  fail "hello_task without a build type was not built Release (the package's default)"
run=$(MANIBENCH_PLUGIN_PATH="$work/hello_build" HOME="$work" "$cli" run HelloSlider-v0 --policy hello_expert --seed 3)
grep -qE "^  success +yes" <<<"$run" || fail "hello_task from $work/hello_build:"$'\n'"$run"
echo "installed checks: out-of-tree hello_task OK"

# 3b. The multi-file family template: built, its catalog test and its
# expert's evaluation through the installed host (ctest).
cmake -S "$work/turntable_family" -B "$work/turntable_build" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" >"$work/turntable.log" 2>&1 &&
  cmake --build "$work/turntable_build" >>"$work/turntable.log" 2>&1 &&
  (cd "$work/turntable_build" && HOME="$work" ctest --output-on-failure) >>"$work/turntable.log" 2>&1 ||
  { cat "$work/turntable.log"; fail "turntable_family build or tests"; }
echo "installed checks: out-of-tree turntable_family OK"

# 4. The Python package from Debian's interpreter: a cabinet environment
# resets and steps (its plugins and robot found from the module's place).
# Under make sanitize the interpreter preloads the ASan runtime
# (MANIBENCH_PYTHON_PRELOAD, set by tests/CMakeLists.txt; empty otherwise).
site=$(find "$prefix/lib" -maxdepth 3 -type d -name dist-packages | head -n 1)
[[ -n "$site" && -f "$site/manibench/__init__.py" ]] || fail "no dist-packages/manibench under $prefix/lib"
env -u MANIBENCH_PLUGIN_PATH -u MANIBENCH_DATA_DIR HOME="$work" PYTHONPATH="$site" PYTHONDONTWRITEBYTECODE=1 \
  LD_PRELOAD="${MANIBENCH_PYTHON_PRELOAD:-}" /usr/bin/python3 - "$prefix" <<'PY' || fail "import manibench from /usr/bin/python3"
import os, sys
import manibench
prefix = os.path.realpath(sys.argv[1])
assert os.path.realpath(manibench.__file__).startswith(prefix), manibench.__file__
tasks = manibench.list_tasks()
assert "OpenCabinetDrawer-v0" in tasks, tasks
env = manibench.make("OpenCabinetDrawer-v0")
obs, info = env.reset(seed=0)
obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
print("installed checks: import manibench OK,", len(tasks), "tasks, reward", float(reward))
PY

# 5. MPI ranks from the installed program: its MPI module is found in the
# installation's own library folder, wherever the tree lies (it used to be
# looked for only beside the program and at the configured prefix).
if command -v mpirun >/dev/null && [[ -n "$(find "$prefix/lib" -name libmanibench_mpi.so)" ]]; then
  env -u MANIBENCH_PLUGIN_PATH -u MANIBENCH_DATA_DIR HOME="$work" mpirun --allow-run-as-root --oversubscribe \
    --mca btl self,vader -np 2 "$cli" eval Reach-v0 --policy random --objects 8 --levels 0-3 \
    --set episode.max_steps=10 --no-progress --out "$work/mpi" >"$work/mpi.log" 2>&1 ||
    { cat "$work/mpi.log"; fail "mpirun -np 2 manibench eval"; }
  grep -q '"complete": true' "$work/mpi/summary.json" || { cat "$work/mpi.log"; fail "MPI eval summary incomplete"; }
  echo "installed checks: mpirun -np 2 manibench eval OK"
else
  echo "installed checks: no mpirun or no MPI module installed, MPI check skipped"
fi
