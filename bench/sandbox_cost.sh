#!/usr/bin/env bash
# The cost of the sandboxed policy process (docs/evaluation.md, "Sandbox"):
# `manibench eval` with one worker, the policy sandboxed (the default) and
# with --trusted-policy (in the worker's process), in alternated pairs on
# the same episodes. Per run: environment steps per second of wall time
# (episodes x mean steps / the run's seconds from summary.json, worker and
# policy process start included) and CPU milliseconds per 1000 steps (user +
# system of every process of the run: on a loaded machine the steadier one).
# Usage: bench/sandbox_cost.sh [BUILD_DIR] [ROUNDS] [TASK] [OBS] [POLICY] [EPISODES_PER_OBJECT] [OBJECTS]
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
task=${3:-Reach-v0}
obs=${4:-state}
policy=${5:-zero}
per_object=${6:-25}
objects=${7:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

python3 - "$build/bin/manibench" "$rounds" "$task" "$obs" "$policy" "$per_object" "$objects" "$work" <<'EOF'
import filecmp, json, os, resource, statistics, subprocess, sys

cli, rounds, task, obs, policy, per_object, objects, work = sys.argv[1:]

def run(kind):
    out = os.path.join(work, kind)
    command = [cli, "eval", task, "--obs", obs, "--policy", policy, "--episodes-per-object",
               per_object, "--workers", "1", "--no-progress", "--out", out]
    if objects:
        command += ["--objects", objects]
    if kind == "trusted":
        command.append("--trusted-policy")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    summary = json.load(open(os.path.join(out, "summary.json")))
    steps = summary["overall"]["episodes"] * summary["overall"]["mean_steps"]
    return steps / summary["timing"]["seconds"], 1000 * cpu / steps * 1000

print(f"| round | {task} {obs}, {policy}: trusted steps/s | sandboxed steps/s | wall cost "
      f"| trusted CPU ms/1000 steps | sandboxed | CPU cost | load |")
print("|---|---|---|---|---|---|---|---|")
wall, cpu = [], []
for r in range(1, int(rounds) + 1):
    order = ["trusted", "sandboxed"] if r % 2 else ["sandboxed", "trusted"]
    results = {kind: run(kind) for kind in order}
    if not filecmp.cmp(os.path.join(work, "trusted", "episodes.csv"),
                       os.path.join(work, "sandboxed", "episodes.csv"), shallow=False):
        print("episodes differ!", file=sys.stderr)
    (ts, tc), (ss, sc) = results["trusted"], results["sandboxed"]
    wall.append(1 - ss / ts)
    cpu.append(sc / tc - 1)
    print(f"| {r} | {ts:.0f} | {ss:.0f} | {100 * wall[-1]:.1f} % | {tc:.0f} | {sc:.0f} "
          f"| {100 * cpu[-1]:.1f} % | {os.getloadavg()[0]:.1f} |")
print(f"median: wall cost {100 * statistics.median(wall):.1f} %, CPU cost {100 * statistics.median(cpu):.1f} %")
EOF
