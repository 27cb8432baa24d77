#!/usr/bin/env bash
# Builds examples/hello_task the way a user outside this tree would: against
# the installed SDK (find_package(manibench) + manibench_add_plugin), then
# loads it into the already built host through MANIBENCH_PLUGIN_PATH.
set -euo pipefail
: "${MANIBENCH_CLI:?}" "${MANIBENCH_BUILD_DIR:?}" "${MANIBENCH_SOURCE_DIR:?}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$MANIBENCH_BUILD_DIR" --prefix "$work/prefix" >/dev/null
cp -r "$MANIBENCH_SOURCE_DIR/examples/hello_task" "$work/src"
cmake -S "$work/src" -B "$work/build" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/build" >/dev/null
plugin=$(find "$work/build" -maxdepth 1 -name '*.so')
[[ -n "$plugin" ]] || { echo "FAIL: no plugin library was built"; exit 1; }

list=$(MANIBENCH_PLUGIN_PATH="$work/build" "$MANIBENCH_CLI" list)
echo "$list"
grep -E "^task +HelloSlider-v0 +1\.0\.0 +$work/build/" <<<"$list" >/dev/null ||
  { echo "FAIL: manibench list does not show HelloSlider-v0 from $work/build"; exit 1; }

run=$(MANIBENCH_PLUGIN_PATH="$work/build" "$MANIBENCH_CLI" run HelloSlider-v0 --policy hello_expert --seed 3)
echo "$run"
grep -E "^  success +yes" <<<"$run" >/dev/null ||
  { echo "FAIL: the out-of-tree task did not succeed with its expert"; exit 1; }
echo "out-of-tree plugin: OK"
