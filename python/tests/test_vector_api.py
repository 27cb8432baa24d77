"""gymnasium 1.x's vector API, restated (from its documentation) so that it
runs with or without gymnasium: make_vec for every task in every
observation mode, then each part of the interface on Reach-v0."""
import multiprocessing
import os
import signal

import numpy as np
import pytest

import manibench
from manibench import _gym
from conftest import assert_same_info, assert_same_obs

TASKS = manibench.list_tasks()
CASES = [(task, mode) for task in TASKS for mode in manibench.OBS_MODES]


def batch_obs(obs, i):
    return {k: v[i] for k, v in obs.items()} if isinstance(obs, dict) else obs[i]


def check_batch(obs, space):
    assert obs in space
    if isinstance(space, _gym.Dict):
        for key in space:
            assert obs[key].dtype == space[key].dtype, key
    else:
        assert obs.dtype == space.dtype


@pytest.mark.parametrize("task,mode", CASES)
def test_make_vec_follows_the_vector_api(task, mode):
    with manibench.make(task, obs_mode=mode) as env:
        single_obs, single_action = env.observation_space, env.action_space
    venv = manibench.make_vec(task, num_envs=2, obs_mode=mode, overrides={"episode.max_steps": 2})
    try:
        assert isinstance(venv, _gym.VectorEnv)
        assert venv.num_envs == 2 and not venv.closed
        assert venv.metadata["autoreset_mode"] == _gym.AutoresetMode.NEXT_STEP
        assert venv.render_mode == "rgb_array" and venv.spec.id == task
        assert venv.unwrapped is venv
        assert venv.single_observation_space == single_obs
        assert venv.single_action_space == single_action
        assert venv.observation_space == _gym.batch_space(single_obs, 2)
        assert venv.action_space == _gym.batch_space(single_action, 2)
        obs, info = venv.reset(seed=3)
        check_batch(obs, venv.observation_space)
        assert list(info["seed"]) == [3, 4] and info["_seed"].all()
        venv.action_space.seed(5)
        for t in range(3):
            obs, rewards, terminated, truncated, info = venv.step(venv.action_space.sample())
            check_batch(obs, venv.observation_space)
            assert rewards.dtype == np.float64 and rewards.shape == (2,)
            assert terminated.dtype == truncated.dtype == np.bool_ and truncated.shape == (2,)
            if t == 1:  # the time limit
                assert (terminated | truncated).all()
                assert np.array_equal(info["is_success"], info["success"])
            if t == 2:  # the next step resets: reset infos, no step keys
                assert not (terminated | truncated).any() and "success" not in info
                assert list(venv.get_attr("elapsed_steps")) == [0, 0]
    finally:
        venv.close()
    assert venv.closed
    venv.close()  # closing again does nothing


def sequential_same_step(seed, actions, **make_kwargs):
    """What environment i of make_vec(..., autoreset_mode=SAME_STEP) gives,
    with one ManibenchEnv per environment in this process."""
    out = []
    for i in range(actions.shape[1]):
        with manibench.make("Reach-v0", **make_kwargs) as env:
            rows = [(env.reset(seed=seed + i)[0], 0.0, False, False, None, None, None)]
            for t in range(actions.shape[0]):
                obs, reward, terminated, truncated, info = env.step(actions[t, i])
                final_obs = final_info = None
                if terminated or truncated:
                    final_obs, final_info = obs, info
                    obs, info = env.reset()
                rows.append((obs, reward, terminated, truncated, info, final_obs, final_info))
            out.append(rows)
    return out


def test_same_step_autoreset_returns_the_new_episode_and_the_final_one_in_info():
    overrides = {"episode.max_steps": 3}
    actions = np.random.default_rng(2).uniform(-1, 1, size=(8, 2, 2)).astype(np.float32)
    expected = sequential_same_step(30, actions, overrides=overrides)
    with manibench.make_vec("Reach-v0", num_envs=2, overrides=overrides,
                            autoreset_mode=_gym.AutoresetMode.SAME_STEP) as venv:
        assert venv.metadata["autoreset_mode"] == _gym.AutoresetMode.SAME_STEP
        obs, _ = venv.reset(seed=30)
        for i in range(2):
            assert_same_obs(obs[i], expected[i][0][0])
        for t in range(actions.shape[0]):
            obs, rewards, terminated, truncated, info = venv.step(actions[t])
            rows = [expected[i][t + 1] for i in range(2)]
            for i, (e_obs, e_reward, e_term, e_trunc, e_info, e_final, e_final_info) in enumerate(rows):
                assert_same_obs(obs[i], e_obs)
                assert rewards[i] == e_reward
                assert terminated[i] == e_term and truncated[i] == e_trunc
            infos = {i: dict(rows[i][4]) for i in range(2)}
            for i in range(2):
                if rows[i][5] is not None:
                    infos[i].update(final_obs=rows[i][5], final_info=rows[i][6])
            assert_same_info(info, manibench.vector.stack_infos(2, infos))
            if t == 2:  # both episodes end on their third step
                assert truncated.all() and info["_final_obs"].all()
                assert info["final_obs"].shape == (2,) + venv.single_observation_space.shape
                assert info["final_info"]["elapsed_steps"].tolist() == [3, 3]
                assert info["elapsed_steps"].tolist() == [0, 0] and "success" not in info
    # A string works as well as the enum, and a wrong one is an error.
    with manibench.make_vec("Reach-v0", num_envs=1, autoreset_mode="SameStep") as venv:
        assert venv.autoreset_mode == _gym.AutoresetMode.SAME_STEP
    with pytest.raises(ValueError, match="autoreset_mode"):
        manibench.make_vec("Reach-v0", num_envs=1, autoreset_mode="Sometimes")


def test_reset_mask_resets_only_the_masked_environments():
    with manibench.make_vec("Reach-v0", num_envs=3) as venv:
        venv.reset(seed=0)
        zeros = np.zeros((3, 2), np.float32)
        obs, *_ = venv.step(zeros)
        obs, info = venv.reset(seed=[None, 50, None],
                               options={"reset_mask": np.array([False, True, False])})
        assert info["_seed"].tolist() == [False, True, False] and info["seed"][1] == 50
        with manibench.make("Reach-v0") as env:
            assert_same_obs(obs[1], env.reset(seed=50)[0])
        before = venv.call("get_obs")
        assert_same_obs(obs[0], before[0])
        assert_same_obs(obs[2], before[2])
        assert list(venv.get_attr("elapsed_steps")) == [1, 0, 1]
        for bad in ([True, False, True], np.array([1, 0, 1]), np.zeros(3, bool), np.ones(2, bool)):
            with pytest.raises(ValueError, match="reset_mask"):
                venv.reset(options={"reset_mask": bad})


def test_async_halves_give_the_whole_calls():
    with manibench.make_vec("Reach-v0", num_envs=2) as a, manibench.make_vec("Reach-v0", num_envs=2) as b:
        a.reset_async(seed=4)
        with pytest.raises(manibench.Error, match="reset_wait first"):
            a.step(np.zeros((2, 2)))
        obs_a, info_a = a.reset_wait(timeout=60)
        obs_b, info_b = b.reset(seed=4)
        assert obs_a.tobytes() == obs_b.tobytes() and list(info_a["seed"]) == list(info_b["seed"])
        with pytest.raises(manibench.Error, match="no reset_async"):
            a.reset_wait()
        a.call_async("get_obs")
        assert all(x.tobytes() == y.tobytes() for x, y in zip(a.call_wait(), b.call("get_obs")))
        a.step_async(np.zeros((2, 2)))
        result = a.step_wait(timeout=60)
        assert result[0].tobytes() == b.step(np.zeros((2, 2)))[0].tobytes()


def test_call_get_attr_and_set_attr():
    with manibench.make_vec("Reach-v0", num_envs=2) as venv:
        venv.reset(seed=1)
        venv.step(np.zeros((2, 2)))
        assert venv.call("elapsed_steps") == (1, 1)  # an attribute: its value
        assert venv.get_attr("max_episode_steps") == venv.call("max_episode_steps")
        objects = venv.call("list_objects", split="test")  # a method: called, with keywords
        assert isinstance(objects, tuple) and objects[0] == manibench.objects("Reach-v0", "test")
        venv.set_attr("render_size", [(16, 12), (32, 24)])
        assert venv.get_attr("render_size") == ((16, 12), (32, 24))
        frames = venv.render()
        assert isinstance(frames, tuple) and frames[0].shape == (12, 16, 3)
        assert frames[1].shape == (24, 32, 3) and frames[0].dtype == np.uint8
        with pytest.raises(ValueError, match="length"):
            venv.set_attr("render_size", [(16, 12)])
        with pytest.raises(AttributeError, match="worker 0"):
            venv.get_attr("no_such_attribute")
        # np_random: each environment's generator (copies from the workers).
        venv.reset(seed=7)
        generators = venv.np_random
        assert len(generators) == 2 and venv.np_random_seed == (7, 8)
        assert generators[1].bit_generator.state == np.random.default_rng(8).bit_generator.state


def test_disabled_autoreset_wants_a_masked_reset():
    with manibench.make_vec("Reach-v0", num_envs=2, overrides={"episode.max_steps": 1},
                            autoreset_mode=_gym.AutoresetMode.DISABLED) as venv:
        venv.reset(seed=0)
        _, _, _, truncated, _ = venv.step(np.zeros((2, 2)))
        assert truncated.all()
        with pytest.raises(manibench.Error, match="reset_mask"):
            venv.step(np.zeros((2, 2)))
        obs, info = venv.reset(options={"reset_mask": np.array([True, True])})
        assert info["_seed"].all()
        venv.step(np.zeros((2, 2)))  # usable again


def test_step_wait_timeout_keeps_the_step_pending():
    # Worker 1 is stopped (SIGSTOP) until the timeouts have been seen: a
    # pointcloud step takes milliseconds, and on a busy machine the workers
    # finished it before step_wait(timeout=0) was called (a clean clone's
    # make test beside a training, 2026-11-27).
    with manibench.make_vec("Reach-v0", num_envs=2, obs_mode="pointcloud") as venv:
        venv.reset(seed=0)
        stopped = venv._processes[1].pid
        os.kill(stopped, signal.SIGSTOP)
        try:
            venv.step_async(np.zeros((2, 2)))
            with pytest.raises(multiprocessing.TimeoutError):
                venv.step_wait(timeout=0)
            with pytest.raises(multiprocessing.TimeoutError):
                venv.step_wait(timeout=0.2)  # still pending after a wait
        finally:
            os.kill(stopped, signal.SIGCONT)
        obs, *_ = venv.step_wait()  # still pending: its result comes now
        assert obs["xyz"].shape[0] == 2
