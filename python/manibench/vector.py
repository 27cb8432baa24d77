"""make_vec: N environments in worker processes, batched numpy observations.

VectorEnv is a gymnasium.vector.VectorEnv where gymnasium (1.x) is
importable (else the stand-in base of manibench._standin) with gymnasium
1.x's interface: metadata["autoreset_mode"], spec, render_mode, closed,
np_random, reset / reset_async / reset_wait (options={"reset_mask": ...}),
step / step_async / step_wait, call / call_async / call_wait, get_attr,
set_attr, render, close.

Each worker owns one ManibenchEnv (its own plugins, scene and, in the visual
modes, its own EGL context, as the evaluation kit's workers do). Workers are
forked while this process has not rendered anything (no EGL context to
inherit), else started as a fresh interpreter that imports manibench and
nothing else (not the caller's __main__, so a script without an
``if __name__ == "__main__":`` guard works).

Steps go through a shared memory block (_core.StepBlock,
python/src/step_block.hpp): the parent stores the actions and waits; each
worker answers in C++ (Environment.serve_steps) without Python, writing its
observation into its slot. Everything else (reset, call, close, errors, the
auto-reset's new episode) goes through the worker's pipe, pickled; the
block says when a step's result is there instead.

Auto-reset (gymnasium's AutoresetMode): NEXT_STEP (the default): the step
on which an environment terminates or truncates returns that episode's
last observation, reward and flags; the next step() ignores that
environment's action and returns the first observation of a new episode
(reward 0, terminated and truncated False, and its reset info). SAME_STEP:
that step returns the new episode's first observation and reset info, with
the last observation and step info in info["final_obs"] and
info["final_info"]. DISABLED: a step of an ended episode is an error; the
caller resets it (options={"reset_mask": ...}). The new episode's seed is
drawn from the environment's generator, which reset(seed=...) seeds.
"""

from __future__ import annotations

import builtins
import multiprocessing
import os
import time
from typing import Any, Sequence

import numpy as np

from . import _core
from . import _gym
from . import spaces as _spaces
from ._worker import SpawnedProcess, block_layout, field_bytes, run_worker
from .env import ConfigFiles, Overrides, check_dtypes, make_spec, make_step_info

AutoresetMode = _gym.AutoresetMode


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


def stack_infos(num_envs, infos):
    """gymnasium's vector info of {index: info}: per key an array over the
    environments and "_key" saying which environments have it."""
    out = {}
    for index, info in infos.items():
        _gym.add_info(num_envs, out, info, index)
    return out


def _as_mode(mode):
    """An AutoresetMode from either enum (gymnasium's or the stand-in's) or its value."""
    return AutoresetMode(getattr(mode, "value", mode))


# Half a millisecond: about one state-mode env step of the cabinet tasks, so a
# worker stepped in lockstep rarely sleeps, and at most this much CPU is
# spent per step waiting when the caller is slow.
DEFAULT_SPIN_WAIT = 0.0005

CONTEXTS = ("fork", "spawn", "forkserver")


class VectorEnv(_gym.VectorEnv):
    """num_envs ManibenchEnvs in worker processes (make_vec)."""

    def __init__(self, env_id: str, num_envs: int, context: str | None = None,
                 spin_wait: float | None = None,
                 autoreset_mode: Any = AutoresetMode.NEXT_STEP, **make_kwargs: Any):
        self._pipes, self._processes = [], []
        self._block = None
        self._pending = None  # the *_async call not yet waited for
        self.closed = False
        if not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        if spin_wait is None:
            # Spinning pays only while every worker has a core of its own.
            spin_wait = DEFAULT_SPIN_WAIT if num_envs <= (os.cpu_count() or 1) else 0.0
        if not spin_wait >= 0:
            raise ValueError(f"spin_wait must be a non-negative number of seconds, got {spin_wait!r}")
        if context is None:
            context = "spawn" if _core.has_rendered() else "fork"
        if context not in CONTEXTS:
            raise ValueError(f"context must be one of {', '.join(CONTEXTS)}, got {context!r}")
        try:
            self.autoreset_mode = _as_mode(autoreset_mode)
        except ValueError:
            raise ValueError(f"autoreset_mode must be one of "
                             f"{', '.join(m.value for m in AutoresetMode)}, got "
                             f"{autoreset_mode!r}") from None
        self.dtypes = check_dtypes(make_kwargs.get("dtypes", "compact"))
        self.spin_wait = float(spin_wait)
        self.num_envs = num_envs
        self.env_id = env_id
        self.context = context
        self.render_mode = make_kwargs.get("render_mode", "rgb_array")
        self.spec = make_spec(env_id, **make_kwargs)
        make_kwargs = dict(make_kwargs, env_id=env_id)
        args = (make_kwargs, self.spin_wait, self.autoreset_mode.value)
        try:
            for _ in range(num_envs):
                if context == "spawn":
                    parent, child = multiprocessing.Pipe()
                    process = SpawnedProcess(child)
                    parent.send(args)
                else:
                    ctx = multiprocessing.get_context(context)
                    parent, child = ctx.Pipe()
                    process = ctx.Process(target=run_worker, args=(child,) + args, daemon=True)
                    process.start()
                child.close()
                self._pipes.append(parent)
                self._processes.append(process)
            descriptions = self._receive_all()
            self.description = descriptions[0]
            self._attach_block()
        except BaseException:
            self.close(terminate=True)
            raise
        self.obs_mode = self.description["obs_mode"]
        self.metadata = {"render_modes": ["rgb_array"],
                         "render_fps": self.description["control_frequency"]
                         / self.description["frame_skip"],
                         "autoreset_mode": self.autoreset_mode}
        self.single_observation_space = _spaces.make_observation_space(
            self.description["observation"], self.obs_mode)
        self.single_action_space = _spaces.make_action_space(
            self.description["action_dim"], np.float32 if self.dtypes == "compact" else np.float64)
        self.observation_space = _spaces.batch_space(self.single_observation_space, num_envs)
        self.action_space = _spaces.batch_space(self.single_action_space, num_envs)

    def _attach_block(self):
        """Makes the shared step block and has every worker map it (then
        the name goes: nothing is left in /dev/shm, whatever happens)."""
        layout = block_layout(self.description, self.num_envs)
        self._block = _core.StepBlock.create(*layout)
        try:
            for slot, pipe in enumerate(self._pipes):
                pipe.send(("attach", (self._block.name, slot, layout)))
            self._receive_all()
        finally:
            self._block.unlink_name()
        self._fields, sizes = field_bytes(self.description)
        memory = np.frombuffer(memoryview(self._block), dtype=np.uint8)
        self._views = []
        for slot in range(self.num_envs):
            views = {}
            for index, ((name, shape, dtype), size) in enumerate(zip(self._fields, sizes)):
                offset = self._block.field_offset(slot, index)
                views[name] = memory[offset:offset + size].view(dtype).reshape(shape)
            self._views.append(views)
        self._object_ids = [None] * self.num_envs
        self._seeds = [None] * self.num_envs
        self._episode_arrays = None  # object_id and seed arrays, until they change
        # Every environment has every key of a plain step's info: one
        # read-only "_key" array serves them all.
        self._all_envs = np.ones(self.num_envs, bool)
        self._all_envs.flags.writeable = False

    # ---- the pipes ---------------------------------------------------------

    def _receive(self, index):
        """Worker `index`'s answer: (status, payload); a dead worker is an
        error answer."""
        pipe, process = self._pipes[index], self._processes[index]
        try:
            return pipe.recv()
        except EOFError:
            process.join(timeout=5)
            return "error", ("Error", f"died (exit code {process.exitcode})", "")

    def _receive_all(self, indices=None, timeout=None):
        """The answers of the workers `indices` (default: all), in order;
        the first error is raised after every answer is read. With
        `timeout` (seconds), multiprocessing.TimeoutError when not every
        answer is there by then (none is read then)."""
        indices = range(self.num_envs) if indices is None else indices
        if timeout is not None:
            deadline = time.monotonic() + timeout
            for index in indices:
                if not self._pipes[index].poll(max(0.0, deadline - time.monotonic())):
                    raise multiprocessing.TimeoutError(
                        f"worker {index} has not answered within {timeout} s")
        results, error = [], None
        for index in indices:
            status, payload = self._receive(index)
            if status == "error" and error is None:
                error = _make_error(index, payload)
            results.append(payload)
        if error is not None:
            raise error
        return results

    def _check_idle(self, call):
        if self.closed:
            raise _core.Error("the vector environment is closed")
        if self._pending is not None:
            raise _core.Error(f"{call}: a {self._pending}_async is pending (call "
                              f"{self._pending}_wait first)")

    def _send(self, messages):
        """Sends {index: (command, payload)}; the workers leave their step loops first."""
        if self._block is not None:
            self._block.post_to_pipe()
        for index, message in messages.items():
            try:
                self._pipes[index].send(message)
            except OSError:  # a dead worker: _receive reports it
                pass

    def _start(self, call, messages):
        self._check_idle(call + "_async")
        self._send(messages)
        self._pending = call

    def _finish(self, call, timeout):
        """The answers of `call`_async; on a timeout it stays pending."""
        if self._pending != call:
            raise _core.Error(f"{call}_wait: no {call}_async to wait for")
        try:
            results = self._receive_all(None, timeout)
        except multiprocessing.TimeoutError:
            raise
        except BaseException:
            self._pending = None  # every answer was read: the errors are the results
            raise
        self._pending = None
        return results

    # ---- gymnasium's VectorEnv -----------------------------------------------

    def reset(self, *, seed: int | Sequence[int | None] | None = None,
              options: dict[str, Any] | Sequence[dict] | None = None) -> tuple[Any, dict]:
        """Resets every environment, or those of options["reset_mask"] (a
        bool array; the others keep their observation and get no info).
        seed: an int (environment i gets seed + i), a list of ints or None
        per environment, or None. options: one dict for all (object_id,
        reset_mask), or a list of dicts (e.g. per-environment object_id)."""
        self.reset_async(seed=seed, options=options)
        return self.reset_wait()

    def reset_async(self, seed: int | Sequence[int | None] | None = None,
                    options: dict[str, Any] | Sequence[dict] | None = None) -> None:
        """reset's first half: sends the resets and returns."""
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
        mask = np.ones(self.num_envs, bool)
        if options is None or isinstance(options, dict):
            options = dict(options or {})
            if "reset_mask" in options:
                mask = options.pop("reset_mask")
                if not (isinstance(mask, np.ndarray) and mask.dtype == np.bool_
                        and mask.shape == (self.num_envs,)):
                    raise ValueError(f"options['reset_mask'] must be a bool numpy array of shape "
                                     f"({self.num_envs},), got {mask!r}")
                if not mask.any():
                    raise ValueError("options['reset_mask'] resets no environment")
            options = [options] * self.num_envs
        else:
            options = list(options)
        if len(seeds) != self.num_envs or len(options) != self.num_envs:
            raise ValueError(f"expected {self.num_envs} seeds and options")
        self._start("reset", {i: ("reset", (seeds[i], options[i])) if mask[i] else ("get_obs", None)
                              for i in range(self.num_envs)})
        self._reset_mask = mask.copy()

    def reset_wait(self, timeout: float | None = None) -> tuple[Any, dict]:
        """reset's second half: the observations and infos of reset_async."""
        results = self._finish("reset", timeout)
        mask, observations, infos = self._reset_mask, [], {}
        for i, result in enumerate(results):
            if mask[i]:
                obs, infos[i] = result
                self._set_episode(i, infos[i]["object_id"], infos[i]["seed"])
            else:
                obs = result
            observations.append(obs)
        return _stack(observations), stack_infos(self.num_envs, infos)

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict]:
        self.step_async(actions)
        return self.step_wait()

    def step_async(self, actions: Any) -> None:
        """Starts a step of every environment and returns at once (as
        gymnasium's AsyncVectorEnv): the policy can work while the workers
        step; step_wait() returns the results. One step at a time."""
        actions = np.asarray(actions, dtype=np.float64)
        if actions.ndim != 2 or actions.shape[0] != self.num_envs:
            raise ValueError(f"actions must have shape ({self.num_envs}, action_dim), got "
                             f"{actions.shape}")
        if actions.shape[1] != self.description["action_dim"]:
            raise _core.InvalidAction(
                f"actions must have shape ({self.num_envs}, {self.description['action_dim']}) "
                f"(the controller {self.description['controller']}), got {actions.shape}")
        self._check_idle("step_async")
        self._block.post_step(actions)
        self._pending = "step"

    def step_wait(self, timeout: float | None = None) -> tuple[Any, np.ndarray, np.ndarray,
                                                               np.ndarray, dict]:
        """The results of step_async's step: (obs, rewards, terminated,
        truncated, info), as step() returns them. With `timeout` (seconds),
        multiprocessing.TimeoutError if the workers have not finished by
        then (the step stays pending: call step_wait again)."""
        if self._pending != "step":
            raise _core.Error("step_wait: no step_async to wait for")
        self._wait_block(None if timeout is None else time.monotonic() + timeout)
        self._pending = None
        (rewards, terminated, truncated, success, elapsed, flags, values, on_pipe,
         points) = self._block.results()
        piped, error = {}, None
        for i in (np.flatnonzero(on_pipe) if on_pipe.any() else ()):  # episode ends, errors
            status, payload = self._receive(int(i))
            if status == "error":
                error = error or _make_error(int(i), payload)
            else:
                piped[int(i)] = payload
        if error is not None:
            raise error
        obs = _stack([piped[i][0] if i in piped else self._block_obs(i, points[i])
                      for i in range(self.num_envs)])
        if not piped:
            return obs, rewards, terminated, truncated, self._block_infos(
                elapsed, success, flags, values)
        infos = {}
        for i in range(self.num_envs):
            if i in piped:
                _, rewards[i], terminated[i], truncated[i], infos[i] = piped[i]
                self._set_episode(i, infos[i]["object_id"], infos[i]["seed"])
            else:
                infos[i] = make_step_info(self._object_ids[i], self._seeds[i], elapsed[i],
                                          success[i], self.description["success_conditions"],
                                          flags[i], values[i])
        return obs, rewards, terminated, truncated, stack_infos(self.num_envs, infos)

    def _wait_block(self, deadline=None):
        """Waits for every worker's step; a worker that died is an error;
        past `deadline` (time.monotonic), multiprocessing.TimeoutError."""
        while True:
            wait = 0.25 if deadline is None else min(0.25, max(0.0, deadline - time.monotonic()))
            pending = self._block.wait_all(wait)
            if not pending:
                return
            for i in pending:
                process = self._processes[i]
                if not process.is_alive():
                    process.join(timeout=5)
                    self._pending = None
                    raise _core.Error(f"worker {i}: died (exit code {process.exitcode})")
            if deadline is not None and time.monotonic() >= deadline:
                raise multiprocessing.TimeoutError(
                    f"step_wait: workers {list(pending)} have not finished their step")

    def _block_obs(self, i, points):
        views = self._views[i]
        if self.obs_mode == "state":
            return views["state"]
        if self.obs_mode == "pointcloud":  # without padding, fewer rows
            return {k: v[:points] if k != "agent" else v for k, v in views.items()}
        return views

    def _set_episode(self, i, object_id, seed):
        """Environment i's episode (its step infos' object_id and seed)."""
        self._object_ids[i], self._seeds[i] = object_id, seed
        self._episode_arrays = None

    def _block_infos(self, elapsed, success, flags, values):
        """stack_infos of every environment's make_step_info, built from the
        arrays directly (a plain step: every environment has every key).
        What does not change from step to step (the "_key" arrays, object
        ids and seeds within episodes) is shared and read-only: this runs
        in the parent between two steps of every worker."""
        if self._episode_arrays is None:
            object_ids = np.array(self._object_ids, dtype=object)
            seeds = np.array(self._seeds)
            object_ids.flags.writeable = seeds.flags.writeable = False
            self._episode_arrays = (object_ids, seeds)
        object_ids, seeds = self._episode_arrays
        everyone = self._all_envs
        conditions = self.description["success_conditions"]
        eval_info, eval_values = {}, {}
        for k, c in enumerate(conditions):
            eval_info[c], eval_info["_" + c] = flags[:, k], everyone
            eval_values[c], eval_values["_" + c] = values[:, k], everyone
        return {"object_id": object_ids, "_object_id": everyone,
                "seed": seeds, "_seed": everyone,
                "elapsed_steps": elapsed, "_elapsed_steps": everyone,
                "success": success, "_success": everyone,
                "is_success": success, "_is_success": everyone,
                "eval_info": eval_info, "_eval_info": everyone,
                "eval_values": eval_values, "_eval_values": everyone}

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple:
        """Every environment's `name`: called with the arguments when it is
        callable, else its value (as gymnasium's vector environments)."""
        self.call_async(name, *args, **kwargs)
        return self.call_wait()

    def call_async(self, name: str, *args: Any, **kwargs: Any) -> None:
        self._start("call", {i: ("call", (name, args, kwargs)) for i in range(self.num_envs)})

    def call_wait(self, timeout: float | None = None) -> tuple:
        results = self._finish("call", timeout)
        # A call (set_state, reset) may have changed the episodes' objects and seeds.
        for i, (_, (object_id, seed)) in enumerate(results):
            if (object_id, seed) != (self._object_ids[i], self._seeds[i]):
                self._set_episode(i, object_id, seed)
        return tuple(result for result, _ in results)

    def get_attr(self, name: str) -> tuple:
        """Every environment's attribute `name` (gymnasium: call(name))."""
        return self.call(name)

    def set_attr(self, name: str, values: Any) -> None:
        """Sets attribute `name` of every environment: values[i] for
        environment i when `values` is a list or tuple, else `values`."""
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(f"Values must be a list or tuple with length equal to the number of "
                             f"environments. Got `{len(values)}` values for {self.num_envs} "
                             "environments.")
        self._check_idle("set_attr")
        self._send({i: ("set_attr", (name, values[i])) for i in range(self.num_envs)})
        self._receive_all()

    @property
    def np_random(self) -> tuple:
        """Each environment's generator (copies: they live in the workers)."""
        return self.get_attr("np_random")

    @property
    def np_random_seed(self) -> tuple:
        return self.get_attr("np_random_seed")

    def render(self) -> tuple:
        """Each environment's render() (an RGB image, uint8)."""
        return self.call("render")

    def close_extras(self, terminate: bool = False, **kwargs: Any) -> None:
        """Stops every worker and waits for it (terminating one that does
        not answer within 10 s)."""
        if self._block is not None:  # the workers leave their step loops
            self._block.post_to_pipe()
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

    def close(self, **kwargs: Any) -> None:
        """Stops the workers (close_extras); closing again does nothing."""
        if self.closed:
            return
        self.closed = True
        self.close_extras(**kwargs)

    def __enter__(self) -> "VectorEnv":
        return self

    def __exit__(self, *exc: Any) -> bool:
        self.close()
        return False

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


def make_vec(env_id: str, num_envs: int = 1, context: str | None = None,
             spin_wait: float | None = None, autoreset_mode: Any = AutoresetMode.NEXT_STEP, *,
             obs_mode: str | None = None, controller: str | None = None,
             config: ConfigFiles = None, overrides: Overrides = None,
             **make_kwargs: Any) -> VectorEnv:
    """num_envs environments of make(env_id, ...) in worker processes.
    context: "fork" or "spawn" (default fork unless this process has
    rendered; spawn starts a fresh interpreter that imports only manibench).
    spin_wait: seconds a worker busy-polls for its next command before it
    blocks (default DEFAULT_SPIN_WAIT while num_envs <= the number of
    cores, else 0). autoreset_mode: AutoresetMode.NEXT_STEP (default),
    SAME_STEP or DISABLED (or their values). Further keywords as make().
    Returns a VectorEnv: reset(seed) -> (obs, info), step(actions) -> (obs,
    rewards, terminated, truncated, info), all batched along axis 0."""
    for key, value in (("obs_mode", obs_mode), ("controller", controller), ("config", config),
                       ("overrides", overrides)):
        if value is not None:
            make_kwargs[key] = value
    return VectorEnv(env_id, num_envs, context=context, spin_wait=spin_wait,
                     autoreset_mode=autoreset_mode, **make_kwargs)
