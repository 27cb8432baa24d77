# The Python examples run as a user runs them (a real interpreter, the build
# tree's package, plugins and CLI).
import json
import os
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(__file__), "..", ".."))
EXAMPLES = os.path.join(ROOT, "examples", "python")


def run_example(name, *args):
    return subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args],
                          capture_output=True, text=True, timeout=600)


def test_random_agent_runs_one_episode():
    r = run_example("random_agent.py", "Reach-v0")
    assert r.returncode == 0, r.stderr
    assert "steps, return" in r.stdout and "success conditions" in r.stdout


def test_evaluate_policy_evaluates_its_own_policy_with_the_kit(tmp_path):
    r = run_example("evaluate_policy.py", "Reach-v0", "--workers", "2", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["complete"] and summary["episodes_run"] == summary["episodes_planned"] > 0
    assert summary["policy"]["name"] == "python", summary["policy"]
    assert summary["overall"]["failures"] == 0
