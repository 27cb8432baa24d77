"""`--policy FILE.py` in every command that runs a policy on a task (run,
eval, bench, render, demos generate, view): one resolution (cli.hpp's
choosePolicy) hands the file to the `python` policy plugin. Each test runs
a small Python policy and checks that what happened came from it: the
actions recorded are the ones it computes, or it counted its own calls.
`--policy FILE.pt` (a `manibench train` checkpoint, through torch_policy)
is checked where the learning module is built."""
import csv
import json
import os
import shutil
import subprocess
import textwrap

import numpy as np
import pytest

BINARY = os.environ.get("MANIBENCH_BIN")
pytestmark = pytest.mark.skipif(not BINARY, reason="needs MANIBENCH_BIN (set by ctest)")

# Reach-v0's expert (plugins/reach/reach_expert.cpp) with a gain of its own,
# 1.5 where the C++ one has 2: its actions are its alone. With
# POLICY_LOG set (commands that run it in their own process, unsandboxed),
# it appends a line per act(). Visual observations (a dict) get zeros.
POLICY = """
import os
import numpy as np

GAIN = 1.5

def expert(s):
    s = np.asarray(s, dtype=np.float64)
    q, target, l1, l2, shoulder = s[0:2], s[7:10], s[10], s[11], s[12:15]
    u, w = target[0] - shoulder[0], -(target[2] - shoulder[2])
    c2 = np.clip((u * u + w * w - l1 * l1 - l2 * l2) / (2 * l1 * l2), -1.0, 1.0)
    best, best_distance = None, np.inf
    for sign in (1.0, -1.0):
        q2 = sign * np.arccos(c2)
        q1 = np.arctan2(w, u) - np.arctan2(l2 * np.sin(q2), l1 + l2 * np.cos(q2))
        candidate = np.array([q1, q2])
        if np.linalg.norm(candidate - q) < best_distance:
            best, best_distance = candidate, np.linalg.norm(candidate - q)
    return np.clip(GAIN * (best - q), -1.0, 1.0)

class Policy:
    def act(self, obs):
        if os.environ.get("POLICY_LOG"):
            with open(os.environ["POLICY_LOG"], "a") as log:
                log.write("act\\n")
        return np.zeros(2) if isinstance(obs, dict) else expert(obs)
"""

namespace = {}
exec(textwrap.dedent(POLICY), namespace)
expert = namespace["expert"]


@pytest.fixture
def policy(tmp_path):
    path = tmp_path / "gain_expert.py"
    path.write_text(textwrap.dedent(POLICY))
    return path


def manibench(*args, log=None, **kwargs):
    env = dict(os.environ)
    if log:
        env["POLICY_LOG"] = str(log)
    run = subprocess.run([BINARY, *map(str, args)], capture_output=True, text=True, env=env, **kwargs)
    assert run.returncode == 0, run.stdout + run.stderr
    return run.stdout


def count_calls(log):
    return len(log.read_text().splitlines()) if log.exists() else 0


def assert_actions_are_the_policys(observations, actions):
    assert len(actions) > 0
    for obs, action in zip(observations, actions):
        # The policy saw float32 observations; the records are float64.
        np.testing.assert_allclose(action, expert(obs), rtol=0, atol=1e-4)


def test_run(tmp_path, policy):
    trace = tmp_path / "trace.csv"
    out = manibench("run", "Reach-v0", "--policy", policy, "--seed", "1", "--trace", trace)
    assert "policy python" in out and "success         yes" in out, out
    with open(trace, newline="") as f:
        rows = list(csv.DictReader(f))
    observations = [[float(r[k]) for k in r if k.startswith("obs.")] for r in rows]
    actions = [[float(r[k]) for k in r if k.startswith("action.")] for r in rows]
    assert_actions_are_the_policys(observations, actions)


def test_eval(tmp_path, policy):
    out = tmp_path / "results"
    manibench("eval", "Reach-v0", "--policy", policy, "--split", "test", "--episodes-per-object", "1",
              "--no-progress", "--out", out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["policy"]["name"] == "python"
    assert f"--policy {policy}" in summary["configuration"]
    with open(out / "episodes.csv", newline="") as f:
        episodes = list(csv.DictReader(f))
    assert len(episodes) == summary["episodes_run"] > 0
    assert all(e["success"] == "1" for e in episodes), episodes  # a zero or random policy fails


def test_bench(tmp_path, policy):
    log = tmp_path / "calls.log"
    out = manibench("bench", "Reach-v0", "--policy", policy, "--steps", "60", log=log)
    assert "policy python" in out and "60 env steps" in out, out
    assert count_calls(log) == 60


@pytest.mark.skipif(not shutil.which("ffmpeg"), reason="needs ffmpeg")
def test_render_video(tmp_path, policy):
    log = tmp_path / "calls.log"
    video = tmp_path / "episode.mp4"
    out = manibench("render", "Reach-v0", "--out", tmp_path / "images", "--video", video, "--video-size",
                    "64x48", "--policy", policy, "--obs", "pointcloud", log=log)
    line = next(l for l in out.splitlines() if l.startswith(f"wrote {video}"))
    steps = int(line.split(" frames, ")[1].split(" steps")[0])
    assert line.endswith("steps of policy python") and steps > 0, out
    assert count_calls(log) == steps and video.stat().st_size > 0


def test_demos_generate(tmp_path, policy):
    demos = pytest.importorskip("manibench.demos")
    path = tmp_path / "demos.h5"
    manibench("demos", "generate", "Reach-v0", "--policy", policy, "--objects", "0,1", "--no-progress",
              "--out", path)
    with demos.DemoFile(path) as f:
        assert f.meta["policy"].startswith("python (") and len(f) == 2
        for trajectory in f:
            assert_actions_are_the_policys(trajectory["obs"][:-1], trajectory["actions"])


@pytest.fixture
def display():
    if not shutil.which("Xvfb"):
        pytest.skip("needs Xvfb")
    read, write = os.pipe()
    server = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "1280x720x24", "-nolisten",
                               "tcp", "-noreset"], pass_fds=(write,), stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    os.close(write)
    with os.fdopen(read) as numbers:
        number = numbers.readline().strip()  # written once it accepts connections
    try:
        if not number:
            pytest.skip("Xvfb did not start")
        yield ":" + number
    finally:
        server.kill()
        server.wait()


def test_view(tmp_path, policy, display):
    record = tmp_path / "watched.h5"
    env = dict(os.environ, DISPLAY=display)
    run = subprocess.run([BINARY, "view", "Reach-v0", "--policy", str(policy), "--record", str(record),
                          "--measure", "2", "--size", "320x240"], capture_output=True, text=True, env=env,
                         timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "python" in run.stdout and "recorded" in run.stdout, run.stdout
    demos = pytest.importorskip("manibench.demos")
    with demos.DemoFile(record) as f:
        assert f.meta["policy"].startswith("python (") and len(f) >= 1
        for trajectory in f:
            assert_actions_are_the_policys(trajectory["obs"][:-1], trajectory["actions"])


def test_a_checkpoint_runs_through_torch_policy(tmp_path):
    if "torch_policy" not in manibench("list"):
        pytest.skip("this build has no learning module (libtorch)")
    demos_file, training = tmp_path / "reach.h5", tmp_path / "bc"
    manibench("demos", "generate", "Reach-v0", "--policy", "reach_expert", "--objects", "0,1", "--no-progress",
              "--out", demos_file)
    manibench("train", "bc", "--demos", demos_file, "--out", training, "--iterations", "20", "--batch-size", "16")
    checkpoint = training / "checkpoints" / "iter_0000020.pt"
    environment = training / "environment.yaml"
    traces = {}
    for name, policy in {"file": ["--policy", checkpoint],
                         "configured": ["--policy", "torch_policy", "--policy-config", training / "policy.yaml"],
                         "zero": ["--policy", "zero"]}.items():
        traces[name] = tmp_path / f"{name}.csv"
        manibench("run", "Reach-v0", *policy, "--config", environment, "--no-early-stop", "--trace", traces[name])
    # The file is the checkpoint torch_policy runs (and not nothing).
    assert traces["file"].read_text() == traces["configured"].read_text()
    assert traces["file"].read_text() != traces["zero"].read_text()
    out = tmp_path / "results"
    manibench("eval", "Reach-v0", "--policy", checkpoint, "--config", environment, "--objects", "8",
              "--episodes-per-object", "1", "--no-progress", "--out", out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["policy"]["name"] == "torch_policy" and f"--policy {checkpoint}" in summary["configuration"]
    assert summary["episodes_run"] == 1 and summary["failures"] == {}
