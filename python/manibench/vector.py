"""make_vec: N environments in worker processes, batched numpy observations.

Each worker owns one ManibenchEnv (its own plugins, scene and, in the visual
modes, its own EGL context, as the evaluation kit's workers do). Workers are
forked while this process has not rendered anything (no EGL context to
inherit), else spawned (a fresh interpreter importing manibench.vector).

Auto-reset follows gymnasium's next-step convention: the step on which an
environment terminates or truncates returns that episode's last
observation, reward and flags; the next step() ignores that environment's
action and returns the first observation of a new episode (reward 0,
terminated and truncated False, and its reset info). The new episode's seed
is drawn from the environment's generator, which reset(seed=...) seeds.
"""

import builtins
import multiprocessing
import os
import time
import traceback

import numpy as np

from . import _core
from . import spaces as _spaces


def _wait_for_command(conn, spin_wait):
    # Busy-polls up to spin_wait seconds before blocking: a worker that
    # sleeps between steps lets its core halt, and on virtual machines the
    # next step then runs 20-40 % slower (cold caches, the wake-up itself).
    if spin_wait > 0:
        deadline = time.perf_counter() + spin_wait
        while not conn.poll(0) and time.perf_counter() < deadline:
            pass
    return conn.recv()


def _worker(conn, make_kwargs, spin_wait=0.0):
    # Imported here: a spawned worker imports this module first.
    from .env import ManibenchEnv

    try:
        env = ManibenchEnv(**make_kwargs)
        conn.send(("ok", env.description))
    except BaseException as e:  # the parent re-raises it
        conn.send(("error", (type(e).__name__, str(e), traceback.format_exc())))
        conn.close()
        return
    needs_reset = False
    try:
        while True:
            command, payload = _wait_for_command(conn, spin_wait)
            try:
                if command == "reset":
                    seed, options = payload
                    obs, info = env.reset(seed=seed, options=options)
                    needs_reset = False
                    conn.send(("ok", (obs, info)))
                elif command == "step":
                    if needs_reset:
                        obs, info = env.reset()
                        result = (obs, 0.0, False, False, info)
                        needs_reset = False
                    else:
                        result = env.step(payload)
                        needs_reset = result[2] or result[3]
                    conn.send(("ok", result))
                elif command == "call":
                    name, args = payload
                    conn.send(("ok", getattr(env, name)(*args)))
                elif command == "close":
                    env.close()
                    conn.send(("ok", None))
                    return
                else:
                    raise ValueError(f"unknown worker command {command!r}")
            except Exception as e:
                conn.send(("error", (type(e).__name__, str(e), traceback.format_exc())))
    except (EOFError, KeyboardInterrupt):
        pass
    finally:
        conn.close()


def _make_error(index, error):
    import manibench

    name, message, trace = error
    cls = getattr(manibench, name, None)
    if not (isinstance(cls, type) and issubclass(cls, Exception)):
        cls = getattr(builtins, name, None)
    if not (isinstance(cls, type) and issubclass(cls, Exception)):
        cls = _core.Error
    try:
        exc = cls(f"worker {index}: {message}")
    except Exception:  # a class that wants other arguments
        exc = _core.Error(f"worker {index}: {name}: {message}")
    exc.worker_traceback = trace
    return exc


def _stack(items):
    """Stacks observations (arrays or dicts of arrays) along a new axis 0."""
    if isinstance(items[0], dict):
        return {key: np.stack([item[key] for item in items]) for key in items[0]}
    return np.stack(items)


def _stack_infos(infos):
    """gymnasium's vector info: per key an array over environments, and
    "_key" saying which environments have it (an auto-reset step's info
    lacks the step keys)."""
    keys = []
    for info in infos:
        keys += [k for k in info if k not in keys]
    out = {}
    for key in keys:
        present = np.array([key in info for info in infos])
        values = [info.get(key) for info in infos]
        sample = next(v for v in values if v is not None)
        if isinstance(sample, dict):
            out[key] = _stack_infos([v if v is not None else {} for v in values])
        else:
            if isinstance(sample, str):
                filled, dtype = [v if v is not None else "" for v in values], object
            else:
                filled = [v if v is not None else type(sample)() for v in values]
                dtype = None
            out[key] = np.array(filled, dtype=dtype)
        out["_" + key] = present
    return out


# Half a millisecond: about one state-mode env step of the cabinet tasks, so a
# worker stepped in lockstep rarely sleeps, and at most this much CPU is
# spent per step waiting when the caller is slow.
DEFAULT_SPIN_WAIT = 0.0005


class VectorEnv:
    """num_envs ManibenchEnvs in worker processes (make_vec)."""

    def __init__(self, env_id, num_envs, context=None, spin_wait=None, **make_kwargs):
        if not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        if spin_wait is None:
            # Spinning pays only while every worker has a core of its own.
            spin_wait = DEFAULT_SPIN_WAIT if num_envs <= (os.cpu_count() or 1) else 0.0
        if not spin_wait >= 0:
            raise ValueError(f"spin_wait must be a non-negative number of seconds, got {spin_wait!r}")
        self.spin_wait = float(spin_wait)
        if context is None:
            context = "spawn" if _core.has_rendered() else "fork"
        self.num_envs = num_envs
        self.env_id = env_id
        self.context = context
        self._closed = False
        self._pipes, self._processes = [], []
        ctx = multiprocessing.get_context(context)
        make_kwargs = dict(make_kwargs, env_id=env_id)
        try:
            for _ in range(num_envs):
                parent, child = ctx.Pipe()
                process = ctx.Process(target=_worker, args=(child, make_kwargs, self.spin_wait),
                                      daemon=True)
                process.start()
                child.close()
                self._pipes.append(parent)
                self._processes.append(process)
            descriptions = self._receive_all()
        except BaseException:
            self.close(terminate=True)
            raise
        self.description = descriptions[0]
        self.obs_mode = self.description["obs_mode"]
        self.single_observation_space = _spaces.make_observation_space(
            self.description["observation"], self.obs_mode)
        self.single_action_space = _spaces.make_action_space(self.description["action_dim"])
        self.observation_space = _spaces.batch_space(self.single_observation_space, num_envs)
        self.action_space = _spaces.batch_space(self.single_action_space, num_envs)

    def _receive_all(self):
        results, error = [], None
        for index, (pipe, process) in enumerate(zip(self._pipes, self._processes)):
            try:
                status, payload = pipe.recv()
            except EOFError:
                process.join(timeout=5)
                status, payload = "error", ("Error", f"died (exit code {process.exitcode})", "")
            if status == "error" and error is None:
                error = _make_error(index, payload)
            results.append(payload)
        if error is not None:
            raise error
        return results

    def _send_all(self, command, payloads):
        if self._closed:
            raise _core.Error("the vector environment is closed")
        for pipe, payload in zip(self._pipes, payloads):
            try:
                pipe.send((command, payload))
            except OSError:  # a dead worker: _receive_all reports it
                pass

    def reset(self, *, seed=None, options=None):
        """Resets every environment. seed: an int (environment i gets seed +
        i), a list of ints or None per environment, or None. options: one
        dict for all, or a list of dicts (e.g. per-environment object_id)."""
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
        if options is None or isinstance(options, dict):
            options = [options] * self.num_envs
        if len(seeds) != self.num_envs or len(options) != self.num_envs:
            raise ValueError(f"expected {self.num_envs} seeds and options")
        self._send_all("reset", list(zip(seeds, options)))
        results = self._receive_all()
        return _stack([r[0] for r in results]), _stack_infos([r[1] for r in results])

    def step(self, actions):
        actions = np.asarray(actions, dtype=np.float64)
        if actions.ndim != 2 or actions.shape[0] != self.num_envs:
            raise ValueError(f"actions must have shape ({self.num_envs}, action_dim), got "
                             f"{actions.shape}")
        self._send_all("step", list(actions))
        results = self._receive_all()
        obs = _stack([r[0] for r in results])
        rewards = np.array([r[1] for r in results], dtype=np.float64)
        terminated = np.array([r[2] for r in results], dtype=bool)
        truncated = np.array([r[3] for r in results], dtype=bool)
        return obs, rewards, terminated, truncated, _stack_infos([r[4] for r in results])

    def call(self, name, *args):
        """Calls method `name` of every environment; returns the results."""
        self._send_all("call", [(name, args)] * self.num_envs)
        return self._receive_all()

    def render(self):
        return np.stack(self.call("render"))

    def close(self, terminate=False):
        """Stops every worker and waits for it (terminating one that does
        not answer within 10 s)."""
        if self._closed:
            return
        self._closed = True
        for pipe, process in zip(self._pipes, self._processes):
            if not terminate and process.is_alive():
                try:
                    pipe.send(("close", None))
                    if pipe.poll(10):
                        pipe.recv()
                except (OSError, EOFError, BrokenPipeError):
                    pass
        for pipe, process in zip(self._pipes, self._processes):
            process.join(timeout=10 if not terminate else 0)
            if process.is_alive():
                process.terminate()
                process.join(timeout=5)
            if process.is_alive():
                process.kill()
                process.join()
            pipe.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


def make_vec(env_id, num_envs=1, context=None, spin_wait=None, **make_kwargs):
    """num_envs environments of make(env_id, **make_kwargs) in worker
    processes. context: multiprocessing start method ("fork" or "spawn";
    default fork unless this process has rendered). spin_wait: seconds a
    worker busy-polls for its next command before it blocks (default
    DEFAULT_SPIN_WAIT while num_envs <= the number of cores, else 0).
    Returns a VectorEnv:
    reset(seed) -> (obs, info), step(actions) -> (obs, rewards, terminated,
    truncated, info), all batched along axis 0; auto-reset as the module
    says."""
    return VectorEnv(env_id, num_envs, context=context, spin_wait=spin_wait, **make_kwargs)
