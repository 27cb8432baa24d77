"""manibench.demos: demonstration files written by `manibench demos
generate`, read from Python (h5py) under the layout table's names, and the
torch Dataset over them (where torch is importable)."""
import json
import os
import subprocess

import numpy as np
import pytest

import manibench

pytest.importorskip("h5py")
from manibench import demos  # noqa: E402

BINARY = os.environ.get("MANIBENCH_BIN")
pytestmark = pytest.mark.skipif(not BINARY, reason="needs MANIBENCH_BIN (set by ctest)")


def generate(tmp_path, name, *args):
    out = tmp_path / f"{name}.h5"
    subprocess.run([BINARY, "demos", "generate", "Reach-v0", "--policy", "reach_expert",
                    "--split", "train", "--per-object", "1", "--workers", "1", "--no-progress",
                    "--out", str(out), *args], check=True, capture_output=True)
    return out


@pytest.fixture(scope="module")
def state_file(tmp_path_factory):
    return generate(tmp_path_factory.mktemp("demos"), "reach", "--objects", "0,1,2")


def test_a_file_reads_as_the_layout_says(state_file):
    sidecar = json.loads(state_file.with_suffix(".json").read_text())
    with demos.DemoFile(state_file) as f:
        assert f.meta["task"] == "Reach-v0" and f.meta["obs_mode"] == "state"
        assert f.meta["condition_names"][-1] == "success"
        assert len(f) == 3 and f.names == ["traj_0", "traj_1", "traj_2"]
        for trajectory, episode in zip(f, sidecar["episodes"]):
            assert trajectory.name == episode["name"]
            assert trajectory.attrs["object_id"] == episode["object_id"]
            assert trajectory.attrs["seed"] == episode["seed"]
            steps = episode["elapsed_steps"]
            assert trajectory.steps == steps
            assert trajectory["actions"].shape == (steps, 2)
            assert trajectory["actions"].dtype == np.float64
            assert trajectory["obs"].shape == (steps + 1, 15)
            assert trajectory["rewards"].shape == (steps,)
            assert trajectory["conditions"].shape == (steps, 3)
            assert trajectory["terminated"][-1] == 1 and trajectory["env_state_offsets"].shape == (steps + 2,)
        light = f.read("traj_1", states=False)
        assert "env_states" not in light and "actions" in light
        assert list(f.read("traj_1", fields=["actions"])) == ["actions"]
        with pytest.raises(KeyError, match="traj_9"):
            f["traj_9"]


def test_a_converted_file_names_its_source_and_method(state_file, tmp_path):
    out = tmp_path / "converted.h5"
    subprocess.run([BINARY, "demos", "convert", str(state_file), "--obs", "state", "--no-progress",
                    "--out", str(out)], check=True, capture_output=True)
    with demos.DemoFile(state_file) as source, demos.DemoFile(out) as f:
        assert source.converted_from is None and source.conversion is None
        assert f.converted_from == str(state_file) and f.conversion == "observations"
        assert f.controller == source.controller != ""


def test_a_trajectory_replays_through_make_bit_for_bit(state_file):
    # The arrays are the recording: reset to the first state, step the
    # actions, and every observation, reward and state is the file's.
    trajectory = demos.read(state_file)[2]
    with manibench.make("Reach-v0", dtypes="cpp") as env:
        obs = env.set_state(trajectory.state(0))
        assert obs.tobytes() == trajectory["obs"][0].tobytes()
        for t in range(trajectory.steps):
            obs, reward, *_ = env.step(trajectory["actions"][t])
            assert obs.tobytes() == trajectory["obs"][t + 1].tobytes()
            assert reward == trajectory["rewards"][t]
            assert env.get_state() == trajectory.state(t + 1)


def test_manibench_demos_is_there_on_first_use():
    assert manibench.demos is demos


def test_other_files_are_refused_naming_them(tmp_path):
    import h5py
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = np.zeros(3)
    with pytest.raises(ValueError, match="other.h5.*not a manibench demonstration file"):
        demos.DemoFile(other)


try:
    import torch
except ImportError:  # python3-torch: installed with the learning/ folder's dependencies
    torch = None


@pytest.mark.skipif(torch is None, reason="torch is not installed")
def test_transition_dataset_holds_every_step(state_file):
    trajectories = demos.read(state_file, states=False)
    data = demos.TransitionDataset([state_file, state_file], fields="transition")
    steps = sum(t.steps for t in trajectories)
    assert len(data) == 2 * steps
    obs, action, reward, next_obs, done = data[0]
    assert obs.dtype == torch.float32 and done.dtype == torch.bool
    first = trajectories[0]
    assert np.array_equal(obs.numpy(), first["obs"][0].astype(np.float32))
    assert np.array_equal(next_obs.numpy(), first["obs"][1].astype(np.float32))
    assert float(reward) == np.float32(first["rewards"][0])
    # The last step of the first trajectory: its successor is the final
    # observation, and it is done (ended by success).
    last = first.steps - 1
    _, _, _, next_obs, done = data[last]
    assert np.array_equal(next_obs.numpy(), first["obs"][-1].astype(np.float32)) and bool(done)
    second = trajectories[1]
    assert np.array_equal(data[first.steps][0].numpy(), second["obs"][0].astype(np.float32))
    # A batch is one gather; the loader covers every step once per epoch.
    batch = data[[0, 5, 7]]
    assert batch[0].shape == (3, 15) and batch[1].shape == (3, 2)
    seen = torch.cat([b[1] for b in data.loader(batch_size=16, shuffle=True,
                                                 generator=torch.Generator().manual_seed(0))])
    expected = torch.cat([torch.from_numpy(t["actions"]).float() for t in trajectories] * 2)
    assert seen.shape == expected.shape
    assert torch.equal(seen.sort(dim=0).values, expected.sort(dim=0).values)
    bc = demos.TransitionDataset(state_file)
    assert len(bc[0]) == 2 and len(bc) == steps
    with pytest.raises(ValueError, match="fields"):
        demos.TransitionDataset(state_file, fields="everything")
