#!/usr/bin/env bash
# The viewer's frame rate (docs/viewer.md): `manibench view TASK --measure S`
# in a virtual X display (Xvfb) at 1280x720 with the overlay, per task
# family, showing the scene and showing the point cloud; the free camera
# turns every frame, so every frame renders anew. Beside each family, the
# machine's reference in the same minutes: `manibench bench
# OpenCabinetDrawer-v0 --obs pointcloud` (its render stage is llvmpipe's
# speed; docs/rendering.md has it on the idle machine).
# Usage: bench/viewer_frame_rate.sh [BUILD_DIR] [SECONDS] [ROUNDS]
set -euo pipefail
build=${1:-build}
seconds=${2:-5}
rounds=${3:-1}
cli="$build/bin/manibench"
work=$(mktemp -d)
trap 'kill "$xvfb" 2>/dev/null || true; rm -rf "$work"' EXIT
Xvfb -displayfd 3 -screen 0 1600x900x24 -nolisten tcp 3>"$work/display" 2>/dev/null &
xvfb=$!
for _ in $(seq 100); do [[ -s "$work/display" ]] && break; sleep 0.1; done
export DISPLAY=":$(cat "$work/display")"

frames() {  # "frames/s (CPU ms per frame)" of one measurement
  "$cli" view "$@" --measure "$seconds" |
    sed -n 's/.* s: \([0-9.]*\) frames\/s.*CPU (all threads) \([0-9.]*\) ms.*/\1 (\2 ms)/p'
}
echo "| round | task | scene frames/s (CPU per frame) | point cloud frames/s (CPU per frame) | reference: bench env steps/s, render ms | load |"
echo "|---|---|---|---|---|---|"
for round in $(seq "$rounds"); do
  for task in OpenCabinetDrawer-v0 OpenCabinetDoor-v0 PushChair-v0 MoveBucket-v0; do
    reference=$("$cli" bench OpenCabinetDrawer-v0 --obs pointcloud --policy zero --steps 200 |
      sed -n -e 's/.*, \([0-9.]*\) env steps\/s.*/\1/p' -e 's/.*render \([0-9.]*\),.*/\1/p' | paste -sd, -)
    scene=$(frames "$task")
    points=$(frames "$task" --points)
    echo "| $round | $task | $scene | $points | $reference | $(cut -d' ' -f1 /proc/loadavg) |"
  done
done
