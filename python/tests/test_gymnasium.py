"""Against gymnasium itself, where it is installed (Debian 12 does not
package it: on this project's machines these are skipped, and
test_conformance.py, test_vector_api.py and test_spaces.py restate its
checks). gymnasium's check_env on every task and mode, registration on
import, gymnasium.make / make_vec, the vector wrappers over make_vec, and
make_vec against gymnasium's own SyncVectorEnv in both autoreset modes."""
import warnings

import numpy as np
import pytest

import manibench  # registers the tasks with gymnasium, where it is importable

try:
    import gymnasium
    from gymnasium.utils.env_checker import check_env
    if not hasattr(gymnasium.vector, "AutoresetMode"):  # before 1.1
        gymnasium = None
except ImportError:
    gymnasium = None

# Every test is collected and skipped (a module skipped whole is "no tests
# collected": pytest's exit status 5, a failure for ctest).
pytestmark = pytest.mark.skipif(gymnasium is None, reason="gymnasium >= 1.1 is not installed")

TASKS = manibench.list_tasks()


@pytest.mark.parametrize("task", TASKS)
@pytest.mark.parametrize("mode", manibench.OBS_MODES)
def test_check_env_passes(task, mode):
    env = gymnasium.make(task, obs_mode=mode, render_size=(64, 48))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # infinite bounds, depth and masks are not images
        check_env(env.unwrapped)
    env.close()


def test_tasks_and_fixed_object_ids_are_registered():
    for task in TASKS:
        assert task in gymnasium.registry
    for object_id in manibench.objects("Reach-v0", "train"):
        assert f"Reach_{object_id}-v0" in gymnasium.registry
    env = gymnasium.make("Reach_3-v0")
    assert env.unwrapped.list_objects("test") == ["3"]
    env.close()


def test_make_vec_is_a_gymnasium_vector_env_and_the_vector_wrappers_work():
    venv = gymnasium.make_vec("Reach-v0", num_envs=2, obs_mode="state",
                              overrides={"episode.max_steps": 3})
    assert isinstance(venv.unwrapped, manibench.VectorEnv)
    assert isinstance(venv, gymnasium.vector.VectorEnv)
    venv = gymnasium.wrappers.vector.RecordEpisodeStatistics(venv)
    venv = gymnasium.wrappers.vector.NormalizeObservation(venv)
    venv.reset(seed=0)
    episodes = 0
    for _ in range(8):
        _, _, _, _, info = venv.step(venv.action_space.sample())
        if "episode" in info:
            episodes += int(info["_episode"].sum())
    assert episodes >= 2
    venv.close()


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_make_vec_equals_gymnasiums_sync_vector_env(mode):
    overrides = {"episode.max_steps": 3}
    autoreset = gymnasium.vector.AutoresetMode(mode)
    ours = manibench.make_vec("Reach-v0", num_envs=2, overrides=overrides, autoreset_mode=autoreset)
    theirs = gymnasium.vector.SyncVectorEnv(
        [lambda: manibench.make("Reach-v0", overrides=overrides)] * 2, autoreset_mode=autoreset)
    a, b = ours.reset(seed=5), theirs.reset(seed=5)
    actions = np.random.default_rng(0).uniform(-1, 1, (8, 2, 2)).astype(np.float32)
    for t in range(8):
        a, b = ours.step(actions[t]), theirs.step(actions[t])
        assert gymnasium.utils.env_checker.data_equivalence(a[:4], b[:4], exact=True)
        assert gymnasium.utils.env_checker.data_equivalence(a[4], b[4], exact=True), t
    ours.close()
    theirs.close()
