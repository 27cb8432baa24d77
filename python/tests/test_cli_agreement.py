"""Python and the C++ CLI run the same episodes bit for bit: the expert's
trajectories recorded by `manibench demos generate` (actions, rewards,
observations and the environment state after every step) are replayed
through manibench.make and compared byte for byte."""
import json
import os
import shutil
import subprocess

import numpy as np
import pytest

import manibench

BINARY = os.environ.get("MANIBENCH_BIN")
pytestmark = pytest.mark.skipif(not BINARY or not shutil.which("h5dump"),
                                reason="needs MANIBENCH_BIN (set by ctest) and h5dump")


def read_dataset(path, name, dtype, tmp_path):
    """A dataset's raw little-endian bytes through h5dump (hdf5-tools)."""
    out = tmp_path / (name.replace("/", "_") + ".bin")
    subprocess.run(["h5dump", "-b", "LE", "-o", str(out), "-d", name, str(path)], check=True,
                   capture_output=True)
    return np.fromfile(out, dtype=dtype)


@pytest.mark.parametrize("task,policy,controller", [
    ("Reach-v0", "reach_expert", "joint_velocity"),
    ("OpenCabinetDrawer-v0", "open_cabinet_expert", "mobile_panda_ee"),
])
def test_python_replays_the_cli_trajectories_bit_for_bit(task, policy, controller, tmp_path):
    objects = manibench.objects(task, "train")
    demos = tmp_path / "demos.h5"
    subprocess.run([BINARY, "demos", "generate", task, "--policy", policy, "--controller",
                    controller, "--split", "train", "--per-object", "1", "--objects",
                    f"{objects[0]},{objects[-1]}", "--workers", "1", "--out", str(demos)],
                   check=True, capture_output=True)
    sidecar = json.loads((tmp_path / "demos.json").read_text())
    assert len(sidecar["episodes"]) == 2
    # dtypes="cpp": the C++ program's float64 vectors, byte for byte.
    with manibench.make(task, controller=controller, dtypes="cpp") as env:
        dim, adim = env.observation_space.shape[0], env.action_space.shape[0]
        for episode in sidecar["episodes"]:
            name, steps = episode["name"], episode["elapsed_steps"]
            actions = read_dataset(demos, f"/{name}/actions", "<f8", tmp_path).reshape(steps, adim)
            rewards = read_dataset(demos, f"/{name}/rewards", "<f8", tmp_path)
            observations = read_dataset(demos, f"/{name}/obs", "<f8", tmp_path).reshape(-1, dim)
            states = read_dataset(demos, f"/{name}/env_states", "u1", tmp_path).tobytes()
            offsets = read_dataset(demos, f"/{name}/env_state_offsets", "<u8", tmp_path)
            obs, info = env.reset(seed=episode["seed"], options={"object_id": episode["object_id"]})
            assert obs.tobytes() == observations[0].tobytes()
            assert env.get_state() == states[offsets[0]:offsets[1]]
            for t in range(steps):
                obs, reward, terminated, truncated, info = env.step(actions[t])
                assert obs.tobytes() == observations[t + 1].tobytes(), f"{name} step {t}"
                assert np.float64(reward).tobytes() == rewards[t].tobytes(), f"{name} step {t}"
                assert env.get_state() == states[offsets[t + 1]:offsets[t + 2]], f"{name} step {t}"
            assert terminated and info["success"] == episode["success"]
