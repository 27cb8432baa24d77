#!/usr/bin/env bash
# Throughput of `manibench train sac` (docs/learning-results.md, "SAC"): Table 6's
# settings (3 x 256, batch 1024, one gradient step per env step) on one
# drawer with 1, 2 and 4 environment workers, in alternated rounds (the
# shared VM's load moves speeds 2-5x). Each run: WARMUP random steps, then
# UPDATES more env steps with one gradient step each; printed per run from
# log.csv's last row: env steps/s and gradient steps/s over the learning
# steps (and env steps/s during the warm-up: physics and hand-over
# only), and the shares of the learner's time over the whole run in
# physics (the workers' reset and step time, summed), acting, gradient
# steps and waiting for the workers (the hand-over).
# Usage: bench/sac_throughput.sh [BUILD_DIR] [ROUNDS] [UPDATES] [ENV_ID] [WORKERS...]
set -euo pipefail
build=${1:-build}
rounds=${2:-1}
updates=${3:-300}
env_id=${4:-OpenCabinetDrawer_2000_link_0-v0}
shift $(( $# < 4 ? $# : 4 ))
workers=("$@")
[ ${#workers[@]} -gt 0 ] || workers=(1 2 4)
warmup=1024
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for round in $(seq 1 "$rounds"); do
  for w in "${workers[@]}"; do
    out="$work/r${round}_w$w"
    # A round of W workers steps W env steps: the run ends at the first
    # round past the target, so the last row holds the learning rounds only.
    "$build/bin/manibench" train sac "$env_id" --workers "$w" --threads 1 --steps $((warmup + updates)) \
      --random-steps $warmup --learning-starts $warmup --log-every $warmup --checkpoint-every 100000000 \
      --no-progress --out "$out" 2>/dev/null
    python3 - "$out/log.csv" "$round" "$w" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
last = rows[-1]
print(f"round {sys.argv[2]} workers {sys.argv[3]}: warm-up {float(rows[0]['env_steps_per_second']):.0f} env steps/s; "
      f"learning {float(last['env_steps_per_second']):.2f} env steps/s, "
      f"{float(last['updates_per_second']):.2f} updates/s; shares: physics {100*float(last['physics_share']):.1f} %, "
      f"acting {100*float(last['acting_share']):.1f} %, updates {100*float(last['updates_share']):.1f} %, "
      f"waiting {100*float(last['waiting_share']):.1f} %")
PY
  done
done
