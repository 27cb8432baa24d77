"""manibench.make and friends on Reach-v0 (the cheap task): spaces, shapes,
determinism, state save/restore, errors."""
import os
import subprocess

import numpy as np
import pytest

import manibench
from conftest import assert_same_obs


def test_list_tasks_and_plugins():
    tasks = manibench.list_tasks()
    assert "Reach-v0" in tasks and "OpenCabinetDrawer-v0" in tasks
    plugins = manibench.list_plugins()
    kinds = {p["kind"] for p in plugins["plugins"]}
    assert {"task", "controller", "policy"} <= kinds
    assert plugins["search_path"]


def test_info_mirrors_the_task():
    info = manibench.info("Reach-v0")
    assert info["task"] == "Reach-v0"
    assert info["obs_mode"] == "state"
    assert info["observation"]["state"]["shape"] == (info["observation_dim"],)
    assert info["action_dim"] == 2
    assert info["success_conditions"][-1] == "success"
    assert info["objects"]["train"] > 0 and info["objects"]["test"] > 0
    assert sum(s["size"] for s in info["action_segments"]) == info["action_dim"]
    pc = manibench.info("Reach-v0", obs_mode="pointcloud")["observation"]
    assert set(pc) == {"xyz", "rgb", "seg", "agent"}
    assert pc["xyz"]["shape"] == (1200, 3) and pc["xyz"]["dtype"] == "float32"
    rgbd = manibench.info("Reach-v0", obs_mode="rgbd")["observation"]
    assert rgbd["rgb"]["shape"] == (240, 320, 3) and rgbd["depth"]["shape"] == (240, 320, 1)


def test_objects_mirror_the_cli():
    train = manibench.objects("Reach-v0", "train")
    assert train and train != manibench.objects("Reach-v0", "test")
    binary = os.environ.get("MANIBENCH_BIN")
    if binary:
        out = subprocess.run([binary, "objects", "Reach-v0", "--ids"], check=True,
                             capture_output=True, text=True).stdout.split()
        assert out == train
    with pytest.raises(ValueError):
        manibench.objects("Reach-v0", "validation")


def test_spaces():
    env = manibench.make("Reach-v0")
    try:
        a = env.action_space
        assert a.shape == (2,) and a.dtype == np.float32
        assert np.all(a.low == -1) and np.all(a.high == 1)
        a.seed(3)
        first = a.sample()
        a.seed(3)
        assert np.array_equal(first, a.sample())
        assert a.contains(first) and not a.contains(first * 3) and not a.contains(first[:1])
        o = env.observation_space
        assert o.shape == (env.description["observation_dim"],) and o.dtype == np.float32
    finally:
        env.close()


def test_reset_and_step_state():
    with manibench.make("Reach-v0") as env:
        obs, info = env.reset(seed=3)
        assert isinstance(obs, np.ndarray) and obs.dtype == np.float32
        assert obs.shape == env.observation_space.shape
        assert info["seed"] == 3 and info["object_id"] in env.list_objects("train")
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert obs.shape == env.observation_space.shape and np.all(np.isfinite(obs))
        assert isinstance(reward, float) and np.isfinite(reward)
        assert terminated is False and truncated is False
        assert list(info["eval_info"]) == env.success_conditions
        assert info["elapsed_steps"] == 1 and info["success"] is False
        assert info["is_success"] is False  # Stable-Baselines3's name for it
        # The observation is a copy: the next step does not change it.
        kept = obs.copy()
        env.step(np.zeros(2))
        assert np.array_equal(obs, kept)


def test_dtypes_compact_rounds_the_cpp_vectors_to_float32(actions):
    with manibench.make("Reach-v0", obs_mode="pointcloud") as compact, \
            manibench.make("Reach-v0", obs_mode="pointcloud", dtypes="cpp") as cpp:
        assert compact.observation_space["agent"].dtype == np.float32
        assert cpp.observation_space["agent"].dtype == np.float64
        assert compact.action_space.dtype == np.float32 and cpp.action_space.dtype == np.float64
        a, _ = compact.reset(seed=2)
        b, _ = cpp.reset(seed=2)
        for action in actions[:3]:
            # The same trajectory: float32 actions are float64 actions exactly.
            assert a["agent"].tobytes() == b["agent"].astype(np.float32).tobytes()
            assert a["xyz"].tobytes() == b["xyz"].tobytes()
            a = compact.step(action.astype(np.float32))[0]
            b = cpp.step(action.astype(np.float32).astype(np.float64))[0]
        assert a["agent"].tobytes() == b["agent"].astype(np.float32).tobytes()
    with pytest.raises(ValueError, match="dtypes"):
        manibench.make("Reach-v0", dtypes="float16")


def test_compact_rgbd_rgb_is_the_cpp_rgb_as_bytes():
    with manibench.make("Reach-v0", obs_mode="rgbd") as compact, \
            manibench.make("Reach-v0", obs_mode="rgbd", dtypes="cpp") as cpp:
        space = compact.observation_space["rgb"]
        assert space.dtype == np.uint8 and space.low.max() == 0 and space.high.min() == 255
        assert cpp.observation_space["rgb"].dtype == np.float32
        a, _ = compact.reset(seed=4)
        b, _ = cpp.reset(seed=4)
        assert a["rgb"].dtype == np.uint8 and b["rgb"].dtype == np.float32
        assert np.array_equal(a["rgb"].astype(np.float32) / np.float32(255), b["rgb"])
        assert a["depth"].tobytes() == b["depth"].tobytes()
        assert a["seg"].tobytes() == b["seg"].tobytes()
    # cpp keeps the configuration's: observation.rgb_dtype chooses there.
    with manibench.make("Reach-v0", obs_mode="rgbd", dtypes="cpp",
                        overrides={"observation.rgb_dtype": "uint8"}) as env:
        assert env.reset(seed=4)[0]["rgb"].tobytes() == a["rgb"].tobytes()


def test_reset_options_and_fixed_object_ids():
    with manibench.make("Reach-v0") as env:
        _, info = env.reset(seed=0, options={"object_id": "2"})
        assert info["object_id"] == "2"
        with pytest.raises(ValueError):
            env.reset(seed=0, options={"objet_id": "2"})
    with manibench.make("Reach_3-v0") as env:
        assert env.list_objects("test") == ["3"]
        _, info = env.reset(seed=11)
        assert info["object_id"] == "3"
        with pytest.raises(manibench.InvalidArgument, match="3"):  # a ValueError and a manibench.Error
            env.reset(seed=0, options={"object_id": "4"})


def test_time_limit_truncates():
    with manibench.make("Reach-v0", overrides={"episode.max_steps": 3}) as env:
        env.reset(seed=1)
        flags = [env.step(np.zeros(2))[3] for _ in range(3)]
        assert flags == [False, False, True]


@pytest.mark.parametrize("mode", ["pointcloud", "rgbd"])
def test_visual_observations_match_their_space(mode):
    with manibench.make("Reach-v0", obs_mode=mode) as env:
        space = env.observation_space
        obs, _ = env.reset(seed=2)
        for step in range(2):
            assert set(obs) == set(space.keys())
            for key, value in obs.items():
                assert value.shape == space[key].shape, key
                assert value.dtype == space[key].dtype, key
            assert obs["agent"].shape == (env.description["agent_state_dim"],)
            # Something was seen (Reach's "robot" mask is declared, never filled).
            seen = obs["xyz"].any(axis=1) if mode == "pointcloud" else obs["depth"] > 0
            assert seen.sum() > 100
            if mode == "pointcloud":  # per-point features: floats in [0, 1]
                assert obs["rgb"].dtype == np.float32 and obs["rgb"].max() <= 1
            else:  # an image: bytes (dtypes="compact")
                assert obs["rgb"].dtype == np.uint8 and obs["rgb"].max() > 1
            obs = env.step(env.action_space.sample())[0]


def test_render_returns_an_rgb_image():
    with manibench.make("Reach-v0", render_size=(160, 120)) as env:
        env.reset(seed=0)
        image = env.render()
        assert image.shape == (120, 160, 3) and image.dtype == np.uint8
        assert image.std() > 1  # not a blank frame


def run_episode(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    trajectory = [obs]
    for action in actions:
        obs, reward, terminated, truncated, _ = env.step(action)
        trajectory += [obs, np.float64(reward)]
        if terminated or truncated:
            break
    return trajectory


@pytest.mark.parametrize("mode", ["state", "pointcloud"])
def test_same_seed_and_actions_give_identical_arrays(mode, actions):
    steps = actions if mode == "state" else actions[:4]
    with manibench.make("Reach-v0", obs_mode=mode) as a, \
            manibench.make("Reach-v0", obs_mode=mode) as b:
        first = run_episode(a, 5, steps)
        run_episode(a, 6, steps)  # whatever ran before
        second = run_episode(a, 5, steps)
        third = run_episode(b, 5, steps)
    for x, y, z in zip(first, second, third):
        assert_same_obs(x, y)
        assert_same_obs(x, z)
    other = manibench.make("Reach-v0", obs_mode=mode)
    assert not np.array_equal(run_episode(other, 6, steps)[-2 if mode == "state" else -1],
                              first[-2 if mode == "state" else -1])
    other.close()


def test_reset_without_seed_follows_the_last_seed():
    with manibench.make("Reach-v0") as env:
        env.reset(seed=9)
        a = [env.reset()[1]["seed"] for _ in range(3)]
        env.reset(seed=9)
        b = [env.reset()[1]["seed"] for _ in range(3)]
        assert a == b and len(set(a)) == 3


def test_set_state_continues_bit_identically(actions):
    with manibench.make("Reach-v0") as env:
        env.reset(seed=4)
        for action in actions[:10]:
            env.step(action)
        blob = env.get_state()
        assert isinstance(blob, bytes) and len(blob) > 0
        after = [env.step(action) for action in actions[10:20]]
        env.reset(seed=99)  # somewhere else entirely
        env.set_state(blob)
        assert env.elapsed_steps == 10
        again = [env.step(action) for action in actions[10:20]]
    for x, y in zip(after, again):
        assert_same_obs(x[0], y[0])
        assert x[1:4] == y[1:4]
    with manibench.make("Reach-v0") as fresh:  # another environment of the task
        fresh.set_state(blob)
        assert_same_obs(fresh.step(actions[10])[0], after[0][0])


def test_errors_carry_the_cpp_message():
    with pytest.raises(manibench.PluginError, match="NoSuchTask-v0"):
        manibench.make("NoSuchTask-v0")
    with pytest.raises(manibench.Error):  # the common base
        manibench.make("NoSuchTask-v0")
    with pytest.raises(manibench.ConfigError, match="physics.no_such_key"):
        manibench.make("Reach-v0", overrides={"physics.no_such_key": 1})
    with pytest.raises(manibench.ConfigError, match="control.frame_skip"):
        manibench.make("Reach-v0", overrides=["control.frame_skip=-3"])
    with pytest.raises(ValueError, match="obs_mode"):
        manibench.make("Reach-v0", obs_mode="voxels")
    with pytest.raises(manibench.Error, match="no_such_controller"):
        manibench.make("Reach-v0", controller="no_such_controller")
    with manibench.make("Reach-v0") as env:
        with pytest.raises(RuntimeError, match="before reset"):
            env.step(np.zeros(2))
        env.reset(seed=0)
        with pytest.raises(manibench.InvalidAction, match="has 3 values"):
            env.step(np.zeros(3))
        with pytest.raises(ValueError):  # InvalidAction is a ValueError too
            env.step(np.full(2, np.nan))
        with pytest.raises(ValueError, match="1-d"):
            env.step(np.zeros((2, 1)))
        with pytest.raises(ValueError):
            env.set_state(b"not a state")
        env.step(np.zeros(2))  # still usable after the errors
    env.close()
    with pytest.raises(RuntimeError, match="closed"):
        env.reset(seed=0)
