"""Python policies in the evaluation kit: `manibench eval --policy file.py`
runs the class in the workers through the `python` policy plugin's embedded
interpreter; a Python exception fails only its episodes, with the traceback
in their message."""
import csv
import json
import os
import subprocess
import textwrap

import pytest

BINARY = os.environ.get("MANIBENCH_BIN")
pytestmark = pytest.mark.skipif(not BINARY, reason="needs MANIBENCH_BIN (set by ctest)")

RANDOM_POLICY = """
import numpy as np

class UserPolicy:
    def __init__(self, info):
        assert info["task"] == "Reach-v0" and info["obs_mode"] == "{mode}"
        self.dim = info["action_dim"]

    def reset(self, seed):
        self.rng = np.random.default_rng(seed)

    def act(self, obs):
        if "{mode}" == "pointcloud":
            assert obs["xyz"].shape == (1200, 3) and obs["seg"].dtype == bool
            assert obs["agent"].dtype == np.float32  # as manibench.make gives them
        elif "{mode}" == "rgbd":
            assert obs["rgb"].dtype == np.uint8 and obs["rgb"].shape == (240, 320, 3)
            assert obs["rgb"].max() > 1 and obs["agent"].dtype == np.float32
        else:
            assert obs.shape == (15,) and obs.dtype == np.float32
        return self.rng.uniform(-1, 1, self.dim)
"""

# Raises at step 3 of the episodes whose seed is odd; the others run on.
SOMETIMES_RAISING_POLICY = """
import numpy as np

def check(seed, step):
    if seed % 2 == 1 and step == 3:
        raise ValueError(f"odd seed {seed}")

class Policy:
    def __init__(self):
        self.seed, self.step = 0, 0

    def reset(self, seed):
        self.seed, self.step = seed, 0

    def act(self, obs):
        self.step += 1
        check(self.seed, self.step)
        return np.zeros(2)
"""


def evaluate(tmp_path, source, *extra):
    policy = tmp_path / "solution.py"
    policy.write_text(textwrap.dedent(source))
    out = tmp_path / "results"
    run = subprocess.run([BINARY, "eval", "Reach-v0", "--policy", str(policy), "--split", "test",
                          "--episodes-per-object", "2", "--workers", "2", "--no-progress",
                          "--out", str(out), *extra], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "episodes.csv", newline="") as f:
        episodes = list(csv.DictReader(f))
    return summary, episodes


@pytest.mark.parametrize("mode", ["state", "pointcloud", "rgbd"])
def test_a_python_random_policy_is_evaluated(tmp_path, mode):
    summary, episodes = evaluate(tmp_path, RANDOM_POLICY.format(mode=mode), "--obs", mode)
    assert summary["episodes_run"] == 8 and summary["complete"]
    assert summary["failures"] == {}
    assert summary["policy"]["name"] == "python"
    assert all(int(e["steps"]) > 3 for e in episodes)


def test_a_raising_python_policy_fails_only_its_episodes(tmp_path):
    summary, episodes = evaluate(tmp_path, SOMETIMES_RAISING_POLICY)
    odd = [e for e in episodes if int(e["seed"]) % 2 == 1]
    even = [e for e in episodes if int(e["seed"]) % 2 == 0]
    assert odd and even
    assert summary["failures"] == {"policy_error": len(odd)}
    for e in odd:
        assert e["failure"] == "policy_error" and e["failure_step"] == "2"
        assert "Traceback (most recent call last)" in e["message"]
        assert "in check" in e["message"] and f"ValueError: odd seed {e['seed']}" in e["message"]
    for e in even:
        assert e["failure"] == "" and int(e["steps"]) > 3


def test_python_policy_errors_name_the_file(tmp_path):
    policy = tmp_path / "broken.py"
    policy.write_text("class UserPolicy:\n    def act(self, obs):\n        return [0, 0]\nsyntax error\n")
    run = subprocess.run([BINARY, "eval", "Reach-v0", "--policy", str(policy), "--episodes-per-object",
                          "1", "--no-progress", "--out", str(tmp_path / "r")],
                         capture_output=True, text=True)
    assert run.returncode != 0
    assert "broken.py" in run.stderr + run.stdout and "SyntaxError" in run.stderr + run.stdout
    missing = subprocess.run([BINARY, "eval", "Reach-v0", "--policy", str(tmp_path / "none.py")],
                             capture_output=True, text=True)
    assert missing.returncode != 0 and "none.py" in missing.stderr


def test_python_policy_dtypes_cpp_gives_the_float64_vectors(tmp_path):
    policy = tmp_path / "solution.py"
    policy.write_text("import numpy as np\n\nclass UserPolicy:\n    def act(self, obs):\n"
                      "        assert obs.dtype == np.float64, obs.dtype\n"
                      "        return np.zeros(2)\n")
    for dtypes, failures in (("cpp", {}), ("compact", {"policy_error": 1})):
        config = tmp_path / f"{dtypes}.yaml"
        config.write_text(f"file: {policy}\ndtypes: {dtypes}\n")
        out = tmp_path / dtypes
        run = subprocess.run([BINARY, "eval", "Reach-v0", "--policy", "python", "--policy-config",
                              str(config), "--objects", "8", "--episodes-per-object", "1",
                              "--workers", "1", "--no-progress", "--out", str(out)],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stdout + run.stderr
        assert json.loads((out / "summary.json").read_text())["failures"] == failures, dtypes


# Misbehaves ({what}) on object 8 only (told apart by its link lengths,
# part of Reach's state), from its second step; object 9's episode runs on.
MISBEHAVING_POLICY = """
import ctypes, time
import numpy as np

class UserPolicy:
    def reset(self):
        self.step = 0

    def act(self, obs):
        self.step += 1
        if self.step >= 2 and abs(obs[10] - {length!r}) < 1e-12:
            if "{what}" == "hang":
                time.sleep(600)
            elif "{what}" == "segfault":
                ctypes.string_at(0)
            elif "{what}" == "nan":
                return np.full(2, np.nan)
            elif "{what}" == "wrong size":
                return np.zeros(5)
        return np.zeros(2)
"""


@pytest.mark.parametrize("what,failure", [("hang", "timeout"), ("segfault", "crash"),
                                          ("nan", "invalid_action"),
                                          ("wrong size", "invalid_action")])
def test_a_misbehaving_python_policy_fails_only_its_episode(tmp_path, what, failure):
    import manibench
    with manibench.make("Reach-v0") as env:
        length = float(env.reset(seed=0, options={"object_id": "8"})[0][10])
        assert env.reset(seed=0, options={"object_id": "9"})[0][10] != length
    policy = tmp_path / "solution.py"
    policy.write_text(textwrap.dedent(MISBEHAVING_POLICY.format(what=what, length=length)))
    out = tmp_path / "results"
    run = subprocess.run([BINARY, "eval", "Reach-v0", "--policy", str(policy), "--objects", "8,9",
                          "--episodes-per-object", "1", "--workers", "2", "--step-timeout", "2",
                          "--no-progress", "--out", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    with open(out / "episodes.csv", newline="") as f:
        episodes = {e["object"]: e for e in csv.DictReader(f)}
    assert episodes["8"]["failure"] == failure and episodes["8"]["failure_step"] == "1"
    assert episodes["9"]["failure"] == "" and int(episodes["9"]["steps"]) > 3


# reach_expert's inverse kinematics (plugins/reach/reach_expert.cpp) for 50
# steps (it reaches in under 40), then full speed away from the target.
REACH_THEN_LEAVE_POLICY = """
import numpy as np

class UserPolicy:
    def reset(self, seed):
        self.step = 0

    def act(self, obs):
        self.step += 1
        if self.step > 50:
            return np.array([1.0, 1.0])
        s = obs.astype(np.float64)
        q, target, shoulder, (l1, l2) = s[0:2], s[7:10], s[12:15], s[10:12]
        u, w = target[0] - shoulder[0], -(target[2] - shoulder[2])
        c2 = np.clip((u * u + w * w - l1 * l1 - l2 * l2) / (2 * l1 * l2), -1, 1)
        best = None
        for sign in (1.0, -1.0):
            q2 = sign * np.arccos(c2)
            q1 = np.arctan2(w, u) - np.arctan2(l2 * np.sin(q2), l1 + l2 * np.cos(q2))
            c = np.array([q1, q2])
            if best is None or np.linalg.norm(c - q) < np.linalg.norm(best - q):
                best = c
        return np.clip(2.0 * (best - q), -1, 1)
"""


def test_without_the_early_done_success_once_counts_a_success_the_end_lost(tmp_path):
    """ManiSkill3's two metrics (docs/evaluation.md, "Protocols"): a policy
    that reaches, then leaves, succeeds once but not at the end."""
    summary, episodes = evaluate(tmp_path, REACH_THEN_LEAVE_POLICY, "--objects", "8", "--no-early-done")
    assert summary["early_done"] is False and len(episodes) == 2
    for e in episodes:
        assert e["steps"] == "100" and e["failure"] == ""
        assert e["success_once"] == "1" and e["success_at_end"] == "0" and e["success"] == "0"
    overall = summary["overall"]
    assert overall["success_once_rate"] == 1 and overall["success_at_end_rate"] == 0
    low, high = overall["success_once_interval"]
    assert 0 < low < 1 and high == 1
    # With the early done the same policy's episodes end at the reach: a success.
    (tmp_path / "results").rename(tmp_path / "full")
    summary, episodes = evaluate(tmp_path, REACH_THEN_LEAVE_POLICY, "--objects", "8")
    assert summary["early_done"] is True
    assert all(e["success"] == e["success_once"] == e["success_at_end"] == "1" for e in episodes)
    assert all(int(e["steps"]) <= 50 for e in episodes)
