"""make_vec: worker processes, batched arrays, auto-reset, seeds per
environment, the same trajectories as sequential environments."""
import glob
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import manibench
from conftest import assert_same_info, assert_same_obs


def sequential_reference(seed, actions, **make_kwargs):
    """What environment i of make_vec(...).reset(seed) then step(actions)
    gives, computed with one ManibenchEnv per environment in this process,
    with the next-step auto-reset written out."""
    n = actions.shape[1]
    out = []
    for i in range(n):
        with manibench.make("Reach-v0", **make_kwargs) as env:
            obs, _ = env.reset(seed=seed + i)
            rows, needs_reset = [(obs, 0.0, False, False, None)], False
            for t in range(actions.shape[0]):
                if needs_reset:
                    obs, info = env.reset()
                    rows.append((obs, 0.0, False, False, info))
                    needs_reset = False
                else:
                    obs, reward, terminated, truncated, info = env.step(actions[t, i])
                    rows.append((obs, reward, terminated, truncated, info))
                    needs_reset = terminated or truncated
            out.append(rows)
    return out


def test_vector_env_matches_sequential_envs_with_auto_reset():
    overrides = {"episode.max_steps": 4}
    actions = np.random.default_rng(7).uniform(-1, 1, size=(10, 2, 2))
    with manibench.make_vec("Reach-v0", num_envs=2, overrides=overrides) as venv:
        # Forked unless this process rendered (other tests in the same run).
        assert venv.context == ("spawn" if manibench._core.has_rendered() else "fork")
        assert venv.single_action_space.shape == (2,)
        assert venv.action_space.shape == (2, 2)
        dim = venv.single_observation_space.shape[0]
        assert venv.observation_space.shape == (2, dim)
        obs, info = venv.reset(seed=20)
        assert obs.shape == (2, dim) and obs.dtype == np.float32
        assert list(info["seed"]) == [20, 21]
        rows = [(obs, np.zeros(2), np.zeros(2, bool), np.zeros(2, bool), info)]
        for t in range(actions.shape[0]):
            obs, rewards, terminated, truncated, info = venv.step(actions[t])
            assert rewards.shape == (2,) and terminated.dtype == bool
            rows.append((obs, rewards, terminated, truncated, info))
            if t == 4:  # the auto-reset step: reset infos, no step keys
                assert "success" not in info and info["_seed"].all()
            if t == 3:
                assert truncated.all() and info["_success"].all()
    expected = sequential_reference(20, actions, overrides=overrides)
    for t, (obs, rewards, terminated, truncated, info) in enumerate(rows):
        for i in range(2):
            e_obs, e_reward, e_terminated, e_truncated, _ = expected[i][t]
            assert_same_obs(obs[i], e_obs)
            assert rewards[i] == e_reward
            assert terminated[i] == e_terminated and truncated[i] == e_truncated
        if t > 0:  # the batched info is gymnasium's stacking of the envs' infos
            assert_same_info(info, manibench.vector.stack_infos(
                2, {0: expected[0][t][4], 1: expected[1][t][4]}))
    # The two environments ran different episodes (seeds 20 and 21).
    assert not np.array_equal(rows[1][0][0], rows[1][0][1])


def test_vector_env_reaps_its_workers_and_reports_errors():
    venv = manibench.make_vec("Reach-v0", num_envs=2)
    processes = list(venv._processes)
    venv.reset(seed=0)
    with pytest.raises(manibench.InvalidAction, match="worker 0"):
        venv.step(np.full((2, 2), np.nan))
    with pytest.raises(ValueError, match="shape"):
        venv.step(np.zeros((3, 2)))
    venv.step(np.zeros((2, 2)))  # the workers survived the errors
    venv.close()
    assert all(not p.is_alive() and p.exitcode == 0 for p in processes)
    with pytest.raises(manibench.Error, match="closed"):
        venv.step(np.zeros((2, 2)))
    with pytest.raises(manibench.ConfigError, match="worker"):
        manibench.make_vec("Reach-v0", num_envs=2, overrides={"physics.nope": 1})
    with pytest.raises(ValueError):
        manibench.make_vec("Reach-v0", num_envs=0)


def test_vector_pointcloud_batches_dicts():
    with manibench.make_vec("Reach-v0", num_envs=2, obs_mode="pointcloud") as venv:
        obs, _ = venv.reset(seed=1, options=[{"object_id": "0"}, {"object_id": "1"}])
        space = venv.single_observation_space
        for key, value in obs.items():
            assert value.shape == (2,) + space[key].shape and value.dtype == space[key].dtype
        obs, *_ = venv.step(np.zeros((2, 2)))
        assert obs["xyz"].shape == (2, 1200, 3)


def test_a_dead_worker_is_an_error_not_a_hang():
    venv = manibench.make_vec("Reach-v0", num_envs=2)
    venv.reset(seed=0)
    victim = venv._processes[1]
    os.kill(victim.pid, signal.SIGKILL)
    victim.join(timeout=10)
    with pytest.raises(manibench.Error, match=r"worker 1: died \(exit code -9\)"):
        venv.step(np.zeros((2, 2)))
    survivor = venv._processes[0]
    venv.close()
    assert not survivor.is_alive() and survivor.exitcode == 0


def test_spawned_workers_give_the_forked_workers_trajectories():
    actions = np.random.default_rng(3).uniform(-1, 1, size=(5, 2, 2))
    runs = []
    for context in ("spawn", "fork"):
        with manibench.make_vec("Reach-v0", num_envs=2, context=context) as venv:
            assert venv.context == context
            rows = [venv.reset(seed=8)[0]] + [venv.step(a)[0] for a in actions]
        runs.append(np.stack(rows))
    assert runs[0].tobytes() == runs[1].tobytes()


def test_spin_wait_changes_the_waiting_not_the_trajectories():
    actions = np.random.default_rng(4).uniform(-1, 1, size=(5, 2, 2))
    runs = []
    for spin_wait in (0.0, 0.002):
        with manibench.make_vec("Reach-v0", num_envs=2, spin_wait=spin_wait) as venv:
            assert venv.spin_wait == spin_wait
            rows = [venv.reset(seed=9)[0]] + [venv.step(a)[0] for a in actions]
        runs.append(np.stack(rows))
    assert runs[0].tobytes() == runs[1].tobytes()
    # The default spins only while every worker can have a core.
    with manibench.make_vec("Reach-v0", num_envs=1) as venv:
        assert venv.spin_wait == manibench.vector.DEFAULT_SPIN_WAIT
    with pytest.raises(ValueError, match="spin_wait"):
        manibench.make_vec("Reach-v0", num_envs=1, spin_wait=-1)


@pytest.mark.parametrize("mode", ["state", "pointcloud", "rgbd"])
def test_shared_block_observations_are_the_workers_observations(mode):
    # Steps come back through the shared block; each worker's own
    # get_obs (pickled through its pipe) is the reference.
    with manibench.make_vec("Reach-v0", num_envs=2, obs_mode=mode,
                            overrides={"episode.max_steps": 3}) as venv:
        venv.reset(seed=5)
        for t, action in enumerate(np.random.default_rng(6).uniform(-1, 1, size=(5, 2, 2))):
            obs, *_ = venv.step(action)
            for i, own in enumerate(venv.call("get_obs")):
                assert_same_obs(obs[i] if mode == "state" else {k: v[i] for k, v in obs.items()},
                                own)


def test_no_shared_memory_is_left_behind():
    before = set(glob.glob("/dev/shm/manibench-vec-*"))
    with manibench.make_vec("Reach-v0", num_envs=2) as venv:
        venv.reset(seed=0)
        venv.step(np.zeros((2, 2)))
        assert set(glob.glob("/dev/shm/manibench-vec-*")) == before  # unlinked once mapped
    assert set(glob.glob("/dev/shm/manibench-vec-*")) == before


def test_workers_of_a_killed_parent_end():
    # The parent dies without closing anything (SIGKILL): its workers,
    # waiting in their step loop, notice and end instead of waiting forever.
    program = textwrap.dedent("""
        import os, signal, sys
        import numpy as np
        import manibench
        venv = manibench.make_vec("Reach-v0", num_envs=2, context=sys.argv[1])
        venv.reset(seed=0)
        venv.step(np.zeros((2, 2)))
        print(" ".join(str(p.pid) for p in venv._processes), flush=True)
        os.kill(os.getpid(), signal.SIGKILL)
    """)
    for context in ("fork", "spawn"):
        result = subprocess.run([sys.executable, "-c", program, context], capture_output=True,
                                text=True, timeout=120)
        assert result.returncode == -signal.SIGKILL, result.stderr
        pids = [int(p) for p in result.stdout.split()]
        assert len(pids) == 2
        deadline = time.monotonic() + 20
        alive = pids
        while alive and time.monotonic() < deadline:
            time.sleep(0.1)
            alive = [p for p in alive if os.path.exists(f"/proc/{p}")
                     and open(f"/proc/{p}/stat").read().split(") ")[1][0] != "Z"]
        assert not alive, f"{context} workers {alive} outlived their parent"


def test_step_async_and_step_wait_are_step_in_two_halves():
    actions = np.random.default_rng(11).uniform(-1, 1, size=(6, 2, 2))
    runs = []
    for split in (False, True):
        with manibench.make_vec("Reach-v0", num_envs=2, overrides={"episode.max_steps": 4}) as venv:
            rows = [venv.reset(seed=12)[0]]
            for a in actions:
                if split:
                    venv.step_async(a)
                    rows.append(venv.step_wait()[0])
                else:
                    rows.append(venv.step(a)[0])
        runs.append(np.stack(rows))
    assert runs[0].tobytes() == runs[1].tobytes()
    with manibench.make_vec("Reach-v0", num_envs=2) as venv:
        venv.reset(seed=0)
        with pytest.raises(manibench.Error, match="no step_async"):
            venv.step_wait()
        venv.step_async(np.zeros((2, 2)))
        with pytest.raises(manibench.Error, match="step_wait first"):
            venv.step_async(np.zeros((2, 2)))
        with pytest.raises(manibench.Error, match="step_wait first"):
            venv.reset(seed=1)
        obs, rewards, *_ = venv.step_wait()
        assert obs.shape[0] == 2 and rewards.shape == (2,)
        venv.step_async(np.zeros((2, 2)))  # closing with a step pending is fine


def test_bad_actions_and_blocks_are_errors_that_say_what():
    with manibench.make_vec("Reach-v0", num_envs=2) as venv:
        venv.reset(seed=0)
        with pytest.raises(manibench.InvalidAction, match=r"\(2, 2\).*got \(2, 5\)"):
            venv.step(np.zeros((2, 5)))
        venv.step(np.zeros((2, 2)))  # nothing was posted: the next step works
    with pytest.raises(RuntimeError, match=r"shm_open\(/manibench-vec-none\): No such file"):
        manibench._core.StepBlock.attach("/manibench-vec-none", 1, 2, 0, [16])
    block = manibench._core.StepBlock.create(1, 2, 0, [16])
    try:
        with pytest.raises(RuntimeError, match="different observation layouts"):
            manibench._core.StepBlock.attach(block.name, 1, 2, 0, [4096])
    finally:
        block.unlink_name()


def test_a_script_without_a_main_guard_can_make_vec_after_rendering(tmp_path):
    # After render() the workers are not forked (an EGL context does not
    # survive fork); they are fresh interpreters that import manibench and
    # not this script, so the script needs no `if __name__ == "__main__":`.
    script = tmp_path / "no_guard.py"
    script.write_text(textwrap.dedent("""
        import numpy as np
        import manibench
        env = manibench.make("Reach-v0", render_size=(32, 32))
        env.reset(seed=0)
        env.render()
        venv = manibench.make_vec("Reach-v0", num_envs=2)
        obs, _ = venv.reset(seed=0)
        obs, *_ = venv.step(np.zeros((2, 2)))
        print("context", venv.context, "obs", obs.shape)
        venv.close()
    """))
    package_root = os.path.dirname(os.path.dirname(os.path.abspath(manibench.__file__)))
    result = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                            timeout=300, cwd=tmp_path,
                            env=dict(os.environ, PYTHONPATH=package_root))
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("context spawn obs (2,") == 1  # the script ran once
