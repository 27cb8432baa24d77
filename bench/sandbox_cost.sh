#!/usr/bin/env bash
# The cost of the sandboxed policy process (docs/evaluation.md, "Sandbox"):
# `manibench eval` with one worker, the policy sandboxed (the default) and
# with --trusted-policy (in the worker's process), in alternated pairs on
# the same episodes; environment steps per second of each run from its
# summary.json (episodes x mean steps / seconds, the whole run: worker and
# policy process start included).
# Usage: bench/sandbox_cost.sh [BUILD_DIR] [ROUNDS] [TASK] [OBS] [POLICY] [EPISODES_PER_OBJECT] [OBJECTS]
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
task=${3:-Reach-v0}
obs=${4:-state}
policy=${5:-zero}
per_object=${6:-25}
objects=${7:-}
cli="$build/bin/manibench"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

steps_per_second() {  # of the run whose files are in $1
  python3 - "$1" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1] + "/summary.json"))
o = s["overall"]
print(f'{o["episodes"] * o["mean_steps"] / s["timing"]["seconds"]:.0f}')
EOF
}

run() {  # sandboxed|trusted -> env steps/s
  local extra=()
  [[ $1 == trusted ]] && extra=(--trusted-policy)
  [[ -n $objects ]] && extra+=(--objects "$objects")
  "$cli" eval "$task" --obs "$obs" --policy "$policy" --episodes-per-object "$per_object" \
    --workers 1 --no-progress --out "$work/$1" "${extra[@]}" >/dev/null
  steps_per_second "$work/$1"
}

echo "| round | $task $obs, policy $policy: trusted steps/s | sandboxed steps/s | cost |"
echo "|---|---|---|---|"
for round in $(seq "$rounds"); do
  # Alternate which goes first, so that a load change does not favour one.
  if ((round % 2)); then
    t=$(run trusted)
    s=$(run sandboxed)
  else
    s=$(run sandboxed)
    t=$(run trusted)
  fi
  cmp -s "$work/trusted/episodes.csv" "$work/sandboxed/episodes.csv" || echo "episodes differ!" >&2
  echo "| $round | $t | $s | $(python3 -c "print(f'{100 * (1 - $s / $t):.1f} %')") |"
done
