"""Evaluate a Python policy with the evaluation kit (supplement B.5).

    PYTHONPATH=build/python python3 examples/python/evaluate_policy.py [TASK] [--workers N]
    build/bin/manibench eval Reach-v0 --policy examples/python/evaluate_policy.py --workers 2

This file is both the solution and its launcher: the kit (`manibench eval
TASK --policy THIS_FILE`) imports it in every worker and uses `UserPolicy`;
run as a script, it starts the kit on the task's test split and prints the
summary. The CLI is found through $MANIBENCH_BIN, then next to the build
tree's package (build/bin/manibench), then on PATH.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np


class UserPolicy:
    """A policy as ManiSkill's kit expects it: act(obs) -> action."""

    def __init__(self, info):
        # info: task, obs_mode, observation_dim, action_dim and the segments.
        self.action_dim = info["action_dim"]
        self.rng = np.random.default_rng(0)

    def reset(self, seed):
        # Seeded by the kit per episode: two evaluations give the same numbers.
        self.rng = np.random.default_rng(seed)

    def act(self, obs):
        # Replace with your agent: obs is the vector (state) or the dict of
        # arrays (pointcloud, rgbd) that manibench.make returns.
        return self.rng.uniform(-1.0, 1.0, self.action_dim)


def find_cli():
    if os.environ.get("MANIBENCH_BIN"):
        return os.environ["MANIBENCH_BIN"]
    try:
        import manibench  # build/python/manibench -> build/bin/manibench
        candidate = os.path.join(os.path.dirname(manibench.__file__), "..", "..", "bin", "manibench")
        if os.path.isfile(candidate):
            return os.path.normpath(candidate)
    except ImportError:
        pass
    found = shutil.which("manibench")
    if found is None:
        sys.exit("manibench CLI not found: set MANIBENCH_BIN or put it on PATH")
    return found


def main(argv):
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("task", nargs="?", default="Reach-v0")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--episodes-per-object", type=int, default=1)
    parser.add_argument("--out", default=None, help="results folder (default: a temporary one)")
    args = parser.parse_args(argv)
    out = args.out or tempfile.mkdtemp(prefix="manibench-eval-")
    command = [find_cli(), "eval", args.task, "--policy", os.path.abspath(__file__),
               "--workers", str(args.workers), "--episodes-per-object", str(args.episodes_per_object),
               "--out", out, "--no-progress"]
    print(" ".join(command), flush=True)
    subprocess.run(command, check=True)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    print(f"results in {out}")
    return summary


if __name__ == "__main__":
    main(sys.argv[1:])
