"""Every ```python block of docs/python.md runs, as a user would run it: a
fresh interpreter in an empty folder, the build tree's package and CLI
(on PATH). Blocks that import gymnasium or torch run where it is
installed."""
import importlib.util
import os
import re
import subprocess
import sys

import pytest

import manibench

ROOT = os.path.normpath(os.path.join(os.path.dirname(__file__), "..", ".."))
DOC = os.path.join(ROOT, "docs", "python.md")
BLOCKS = re.findall(r"```python\n(.*?)```", open(DOC).read(), re.S)
PACKAGE_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(manibench.__file__)))


def test_the_page_has_its_examples():
    assert len(BLOCKS) >= 6


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_example_runs(index, tmp_path):
    code = BLOCKS[index]
    for module in ("gymnasium", "torch", "h5py"):
        if re.search(rf"^\s*(import|from) {module}\b", code, re.M) or \
                (module in ("torch", "h5py") and "TransitionDataset" in code):
            if importlib.util.find_spec(module) is None:
                pytest.skip(f"{module} is not installed")
    env = dict(os.environ, PYTHONPATH=PACKAGE_ROOT)
    binary = os.environ.get("MANIBENCH_BIN")
    if binary:
        env["PATH"] = os.path.dirname(binary) + os.pathsep + env.get("PATH", "")
    elif "manibench\", \"demos\"" in code:
        pytest.skip("needs MANIBENCH_BIN (set by ctest)")
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, f"block {index}:\n{code}\n{result.stderr}"
