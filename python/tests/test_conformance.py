"""gymnasium's environment checks, restated (from gymnasium 1.x's documented
API, not its code) so that they run with or without gymnasium: every task
in every observation mode. Where gymnasium is installed,
test_gymnasium.py runs gymnasium's own check_env as well."""
import copy
import inspect

import numpy as np
import pytest

import manibench
from manibench import _gym

TASKS = manibench.list_tasks()
CASES = [(task, mode) for task in TASKS for mode in manibench.OBS_MODES]


def same(a, b):
    """gymnasium's data_equivalence, exact: same types, keys, shapes,
    dtypes and values."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
    return a == b


def check_box(space, kind):
    assert space.low.shape == space.high.shape == space.shape
    assert np.all(space.low <= space.high)
    if kind == "action":  # normalized and symmetric, as gymnasium recommends
        assert np.all(space.low == -1) and np.all(space.high == 1)
    if len(space.shape) == 3 and space.dtype == np.uint8:  # an image: bounds [0, 255]
        assert np.all(space.low == 0) and np.all(space.high == 255)


def check_obs(obs, space):
    """In the space, with the space's dtypes exactly (gymnasium's passive
    checker warns about another dtype) and finite."""
    assert obs in space
    if isinstance(space, _gym.Dict):
        for key in space:
            check_obs(obs[key], space[key])
        return
    assert isinstance(obs, np.ndarray) and obs.dtype == space.dtype
    assert np.all(np.isfinite(obs))


@pytest.mark.parametrize("task,mode", CASES)
def test_environment_passes_the_checks_of_check_env(task, mode):
    env = manibench.make(task, obs_mode=mode, render_size=(64, 48))
    assert isinstance(env, _gym.Env)
    assert env.unwrapped is env
    assert not callable(getattr(env, "seed", None))  # gymnasium warns about a seed() method
    # Spaces.
    assert isinstance(env.action_space, _gym.Box) and env.action_space.dtype == np.float32
    check_box(env.action_space, "action")
    spaces = env.observation_space.values() if mode != "state" else [env.observation_space]
    assert isinstance(env.observation_space, _gym.Dict if mode != "state" else _gym.Box)
    for space in spaces:
        check_box(space, "observation")
    # reset's signature and return.
    parameters = inspect.signature(env.reset).parameters
    assert parameters["seed"].default is None and parameters["options"].default is None
    assert "return_info" not in parameters
    result = env.reset()
    assert isinstance(result, tuple) and len(result) == 2
    check_obs(result[0], env.observation_space)
    assert isinstance(result[1], dict)
    # Seeding: reset(seed=...) seeds the environment's own generator.
    obs_1, _ = env.reset(seed=123)
    assert env.unwrapped._np_random is not None
    rng_123 = copy.deepcopy(env.unwrapped._np_random)
    assert env.np_random is env.unwrapped._np_random
    obs_2, _ = env.reset()
    obs_3, _ = env.reset(seed=123)
    assert same(obs_1, obs_3)
    assert env.unwrapped._np_random.bit_generator.state == rng_123.bit_generator.state
    obs_4, _ = env.reset()
    assert same(obs_2, obs_4)  # reset() after reset(seed=123) is deterministic too
    env.reset(seed=456)
    assert env.unwrapped._np_random.bit_generator.state != rng_123.bit_generator.state
    env.reset(options={})
    # step: types, the space, determinism.
    env.action_space.seed(123)
    action = env.action_space.sample()
    env.reset(seed=123)
    step_1 = env.step(action)
    rng_after = copy.deepcopy(env.unwrapped._np_random)
    env.reset(seed=123)
    step_2 = env.step(action)
    assert env.unwrapped._np_random.bit_generator.state == rng_after.bit_generator.state
    assert isinstance(step_1, tuple) and len(step_1) == 5
    obs, reward, terminated, truncated, info = step_1
    check_obs(obs, env.observation_space)
    assert isinstance(reward, float) and np.isfinite(reward)
    assert isinstance(terminated, bool) and isinstance(truncated, bool)
    assert isinstance(info, dict) and info["is_success"] == info["success"]
    assert all(same(a, b) for a, b in zip(step_1, step_2))
    # render: declared modes, frames per second, an RGB image.
    assert env.render_mode in env.metadata["render_modes"]
    assert isinstance(env.metadata["render_fps"], (int, float)) and env.metadata["render_fps"] > 0
    frame = env.render()
    assert isinstance(frame, np.ndarray) and frame.dtype == np.uint8 and frame.shape == (48, 64, 3)
    # spec: makes the environment again, in every render mode; close twice.
    assert env.spec is not None and env.spec.id == task
    for render_mode in env.metadata["render_modes"]:
        other = env.spec.make(render_mode=render_mode)
        assert other.spec.id == task and other.render_mode == render_mode
        assert other.observation_space == env.observation_space
        other.close()
        other.close()
    env.close()
    env.close()


def test_np_random_is_the_generator_of_the_episode_seeds():
    with manibench.make("Reach-v0") as env:
        env.reset(seed=9)
        expected = np.random.default_rng(9)  # what reset(seed=9) seeded
        assert env.np_random_seed == 9
        seeds = [env.reset()[1]["seed"] for _ in range(3)]
        assert seeds == [int(expected.integers(2**32)) for _ in range(3)]
        env.np_random = np.random.default_rng(4)  # as gymnasium: settable, seed unknown (-1)
        assert env.np_random_seed == -1
        assert env.reset()[1]["seed"] == int(np.random.default_rng(4).integers(2**32))


def test_the_spec_names_the_arguments():
    with manibench.make("Reach-v0", obs_mode="pointcloud", overrides={"episode.max_steps": 7},
                        render_size=(32, 32)) as env:
        spec = env.spec
        assert spec.entry_point == "manibench.env:ManibenchEnv"
        assert spec.vector_entry_point == "manibench.vector:make_vec"
        assert spec.kwargs["env_id"] == "Reach-v0" and spec.kwargs["obs_mode"] == "pointcloud"
        assert spec.name == "Reach" and spec.version == 0
        with spec.make() as again:
            # (gymnasium's spec.make() wraps it: its attributes are the unwrapped env's)
            assert again.unwrapped.max_episode_steps == 7
            assert again.unwrapped.obs_mode == "pointcloud"


def test_the_ids_registered_with_gymnasium_are_those_manibench_objects_names():
    ids = manibench.env_ids()
    assert set(TASKS) <= set(ids) and len(ids) == len(set(ids))
    for task in TASKS:
        objects = manibench.objects(task, "train") + manibench.objects(task, "test")
        base, version = task.rsplit("-v", 1)
        for object_id in objects:
            assert f"{base}_{object_id}-v{version}" in ids
            if "_link_" in object_id:  # the articulated object: all its target links
                assert f"{base}_{object_id.rsplit('_link_', 1)[0]}-v{version}" in ids
    for env_id in ["Reach_3-v0", next(i for i in ids if i.startswith("OpenCabinetDrawer_"))]:
        with manibench.make(env_id) as env:  # each is an environment
            assert env.spec.id == env_id and env.list_objects("test")
    # What gymnasium.register is called with (here a list stands in for it).
    from manibench._registration import register_all
    calls = []
    done = register_all(lambda **kwargs: calls.append(kwargs), registered=["Reach-v0"])
    assert "Reach-v0" not in done and len(done) == len(ids) - 1 == len(calls)
    assert calls[0] == {"id": done[0], "entry_point": "manibench.env:ManibenchEnv",
                        "vector_entry_point": "manibench.vector:make_vec",
                        "kwargs": {"env_id": done[0]}}
