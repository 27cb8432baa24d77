"""Every task in every observation mode: the arrays of a reset and a step
have the shapes and dtypes of the spaces, which are those `manibench info`
describes (observation_dim, agent_state_dim, cameras, masks)."""
import os
import re
import subprocess

import numpy as np
import pytest

import manibench

TASKS = [t for t in manibench.list_tasks()]


@pytest.mark.parametrize("task", TASKS)
@pytest.mark.parametrize("mode", manibench.OBS_MODES)
def test_observations_match_spaces_and_info(task, mode):
    info = manibench.info(task, obs_mode=mode)
    if mode != "state" and not info["cameras"]:
        pytest.skip(f"{task} has no cameras")
    with manibench.make(task, obs_mode=mode) as env:
        space = env.observation_space
        obs, _ = env.reset(seed=0)
        step = env.step(env.action_space.sample())
        assert env.action_space.shape == (info["action_dim"],)
        for o in (obs, step[0]):
            if mode == "state":
                assert o.shape == space.shape == (info["observation_dim"],)
                assert o.dtype == space.dtype == np.float32  # dtypes="compact"
                continue
            assert set(o) == set(space.keys()) == set(info["observation"])
            for key, value in o.items():
                assert value.shape == space[key].shape == tuple(info["observation"][key]["shape"])
                assert value.dtype == space[key].dtype, key
            assert o["agent"].shape == (info["agent_state_dim"],)
            cameras, masks = len(info["cameras"]), len(info["masks"])
            if mode == "rgbd":
                h, w = info["cameras"][0]["height"], info["cameras"][0]["width"]
                assert o["rgb"].shape == (h, w, 3 * cameras)
                assert o["depth"].shape == (h, w, cameras)
                assert o["seg"].shape == (h, w, masks * cameras)
            else:
                assert o["seg"].shape[1] == masks


def parse_cli_info(task):
    """observation_dim, agent_state_dim, action_dim, masks and cameras
    (name, width, height) as `manibench info TASK` prints them."""
    text = subprocess.run([os.environ["MANIBENCH_BIN"], "info", task], check=True,
                          capture_output=True, text=True).stdout
    cameras = re.search(r"^cameras:(.*)$", text, re.M).group(1)
    return {
        "observation_dim": int(re.search(r"observation \(state\), (\d+) values", text).group(1)),
        "agent_state_dim": int(re.search(r"modes: the first (\d+) values", text).group(1)),
        "action_dim": int(re.search(r"^action, (\d+) values", text, re.M).group(1)),
        "masks": re.search(r"^masks:(.*)$", text, re.M).group(1).split(),
        "cameras": [(n, int(w), int(h)) for n, w, h in re.findall(r"(\S+) \((\d+)x(\d+)", cameras)],
    }


@pytest.mark.skipif("MANIBENCH_BIN" not in os.environ, reason="needs MANIBENCH_BIN (set by ctest)")
@pytest.mark.parametrize("task", TASKS)
def test_spaces_have_the_shapes_the_cli_prints(task):
    cli = parse_cli_info(task)
    masks = 0 if cli["masks"] == ["(none)"] else len(cli["masks"])
    with manibench.make(task) as env:
        assert env.observation_space.shape == (cli["observation_dim"],)
        assert env.action_space.shape == (cli["action_dim"],)
    if not cli["cameras"]:
        return
    pc = manibench.info(task, obs_mode="pointcloud")["observation"]
    assert pc["agent"]["shape"] == (cli["agent_state_dim"],)
    assert pc["seg"]["shape"] == (1200, masks)
    rgbd = manibench.info(task, obs_mode="rgbd")["observation"]
    k, (_, w, h) = len(cli["cameras"]), cli["cameras"][0]
    assert rgbd["rgb"]["shape"] == (h, w, 3 * k)
    assert rgbd["depth"]["shape"] == (h, w, k)
    assert rgbd["seg"]["shape"] == (h, w, masks * k)
    assert rgbd["agent"]["shape"] == (cli["agent_state_dim"],)
