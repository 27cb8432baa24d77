#!/usr/bin/python3
"""Soak runs (issue 30; docs/robustness.md "Soak" has the measured numbers).

Not part of `make test`: they take minutes to hours. Two kinds:

  resets  many resets of each task in one environment (objects drawn from
          the train split by seed, as a training loop does), resident
          memory (VmRSS of this process, which holds the environment, its
          plugins and in the visual modes the EGL renderer) sampled as it
          goes. Flat: what the last tenth adds over the first tenth after
          warm-up, per 1000 resets.

      PYTHONPATH=build/python /usr/bin/python3 bench/soak.py resets --obs state --count 10000
      PYTHONPATH=build/python /usr/bin/python3 bench/soak.py resets --obs rgbd --count 500

  kill    one `manibench eval` of many episodes with a worker SIGKILLed
          every --kill-every seconds; then every (object, level) of the run
          must appear exactly once in episodes.csv (finished, or failed as
          a crash when its worker was the one killed), and summary.json's
          episode count must equal the list's.

      /usr/bin/python3 bench/soak.py kill --cli build/bin/manibench --task Reach-v0 \\
          --objects 8-11 --levels 0-499 --workers 2 --kill-every 30

Exit status 0 when memory is flat (growth under --max-growth-kb per 1000
resets) and the accounting exact, 1 otherwise.
"""

import argparse
import csv
import json
import os
import signal
import subprocess
import sys
import tempfile
import time


def read_rss_kb() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return -1


def soak_resets(args: argparse.Namespace) -> bool:
    import manibench  # noqa: PLC0415 (only this mode needs the package)

    tasks = args.tasks.split(",") if args.tasks else manibench.list_tasks()
    flat = True
    for task in tasks:
        env = manibench.make(task, obs_mode=args.obs)
        samples = []  # (resets done, VmRSS kB, seconds)
        start = time.monotonic()
        every = max(1, args.count // 20)
        for i in range(args.count):
            env.reset(seed=i)
            if (i + 1) % every == 0:
                samples.append((i + 1, read_rss_kb(), time.monotonic() - start))
        env.close()
        # The first tenth warms up (every object's meshes seen once, caches
        # filled); the growth is the mean RSS of the last two samples over
        # that of the second and third, per 1000 resets.
        early = (samples[1][1] + samples[2][1]) / 2
        late = (samples[-2][1] + samples[-1][1]) / 2
        span = (samples[-2][0] + samples[-1][0] - samples[1][0] - samples[2][0]) / 2
        growth = (late - early) / span * 1000
        ok = growth < args.max_growth_kb
        flat = flat and ok
        print(json.dumps({"task": task, "obs": args.obs, "resets": args.count,
                          "seconds": round(samples[-1][2], 1),
                          "rss_kb": [s[1] for s in samples],
                          "rss_first_kb": samples[0][1], "rss_last_kb": samples[-1][1],
                          "growth_kb_per_1000_resets": round(growth, 1), "flat": ok}),
              flush=True)
    return flat


def parse_range(text: str) -> list[str]:
    """"0-3,7" -> ["0", "1", "2", "3", "7"]"""
    out = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            out += [str(k) for k in range(int(a), int(b) + 1)]
        else:
            out.append(part)
    return out


def child_pids(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as f:
            return [int(p) for p in f.read().split()]
    except OSError:
        return []


def soak_kill(args: argparse.Namespace) -> bool:
    out = tempfile.mkdtemp(prefix="manibench_soak_kill_")
    objects = parse_range(args.objects)
    levels = parse_range(args.levels)
    command = [args.cli, "eval", args.task, "--policy", args.policy, "--objects", ",".join(objects),
               "--levels", args.levels, "--workers", str(args.workers), "--out", out,
               "--no-progress"] + args.extra
    start = time.monotonic()
    run = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    kills = []
    next_kill = start + args.kill_every
    while run.poll() is None:
        time.sleep(0.2)
        if time.monotonic() < next_kill:
            continue
        next_kill += args.kill_every
        # The coordinator's children are the workers (each policy process is
        # a worker's child).
        workers = child_pids(run.pid)
        if workers:
            victim = workers[len(kills) % len(workers)]
            try:
                os.kill(victim, signal.SIGKILL)
                kills.append(round(time.monotonic() - start, 1))
            except ProcessLookupError:
                pass
    stdout, stderr = run.communicate()
    seconds = time.monotonic() - start
    with open(os.path.join(out, "episodes.csv")) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    keys = [(r["object"], r["level"]) for r in rows]
    expected = {(o, lv) for o in objects for lv in levels}
    missing = expected - set(keys)
    duplicated = len(keys) - len(set(keys))
    unexpected = set(keys) - expected
    failures = {}
    for r in rows:
        if r["failure"]:
            failures[r["failure"]] = failures.get(r["failure"], 0) + 1
    counted = summary["overall"]["episodes"]
    per_object = sum(o["episodes"] for o in summary["per_object"])
    ok = (not missing and not duplicated and not unexpected and len(rows) == len(expected)
          and counted == len(rows) == per_object == summary["episodes_planned"]
          and summary["failures"] == failures and run.returncode in (0, 1))
    print(json.dumps({"task": args.task, "episodes_expected": len(expected), "episodes_listed": len(rows),
                      "summary_episodes": counted, "summary_failures": summary["failures"],
                      "worker_restarts": summary["timing"]["worker_restarts"], "missing": len(missing), "duplicated": duplicated,
                      "unexpected": len(unexpected), "failures": failures, "kills_at_s": kills,
                      "seconds": round(seconds, 1), "exit_status": run.returncode, "out": out,
                      "exact": ok}), flush=True)
    if not ok:
        sys.stderr.write(stderr[-4000:])
    return ok


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="kind", required=True)
    r = sub.add_parser("resets")
    r.add_argument("--tasks", default="", help="comma-separated (default: every task)")
    r.add_argument("--obs", default="state", choices=["state", "pointcloud", "rgbd"])
    r.add_argument("--count", type=int, default=10000)
    r.add_argument("--max-growth-kb", type=float, default=1024.0,
                   help="per 1000 resets after warm-up (default 1 MiB)")
    k = sub.add_parser("kill")
    k.add_argument("--cli", default="build/bin/manibench")
    k.add_argument("--task", default="Reach-v0")
    k.add_argument("--policy", default="reach_expert")
    k.add_argument("--objects", default="8-11", help="of the test split")
    k.add_argument("--levels", default="0-499")
    k.add_argument("--workers", type=int, default=2)
    k.add_argument("--kill-every", type=float, default=30.0)
    k.add_argument("extra", nargs="*", help="more eval options, after --")
    args = parser.parse_args()
    return 0 if (soak_resets(args) if args.kind == "resets" else soak_kill(args)) else 1


if __name__ == "__main__":
    sys.exit(main())
