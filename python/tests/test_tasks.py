"""Every task in every observation mode: the arrays of a reset and a step
have the shapes and dtypes of the spaces, which are those `manibench info`
describes (observation_dim, agent_state_dim, cameras, masks)."""
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
                assert o.dtype == space.dtype == np.float64
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
