"""make_vec: N environments in worker processes, batched numpy observations.

Each worker owns one ManibenchEnv (its own plugins, scene and, in the visual
modes, its own EGL context, as the evaluation kit's workers do). Workers are
forked while this process has not rendered anything (no EGL context to
inherit), else spawned (a fresh interpreter importing manibench.vector).

Steps go through a shared memory block (_core.StepBlock,
python/src/step_block.hpp): the parent stores the actions and waits; each
worker answers in C++ (Environment.serve_steps) without Python, writing its
observation into its slot. Everything else (reset, call, close, errors, the
auto-reset's new episode) goes through the worker's pipe, pickled; the
block says when a step's result is there instead.

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
import traceback

import numpy as np

from . import _core
from . import spaces as _spaces
from .env import make_step_info


def _field_bytes(description):
    """The observation's fields (name, shape, dtype) in the order the
    workers write them into the step block, and their sizes in bytes."""
    fields = [(name, tuple(f["shape"]), np.dtype(f["dtype"]))
              for name, f in description["observation"].items()]
    return fields, [int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
                    for _, shape, dtype in fields]


def _block_layout(description, num_envs):
    """StepBlock.create's and attach's arguments after the name."""
    return (num_envs, description["action_dim"], len(description["success_conditions"]),
            _field_bytes(description)[1])


def _error_message(e):
    """An exception as the ("error", ...) message the parent re-raises."""
    return ("error", (type(e).__name__, str(e), traceback.format_exc()))


def _send_error(conn, e):
    conn.send(_error_message(e))


def _worker(conn, make_kwargs, spin_wait=0.0):
    # Imported here: a spawned worker imports this module first.
    from .env import ManibenchEnv

    try:
        env = ManibenchEnv(**make_kwargs)
        conn.send(("ok", env.description))
    except BaseException as e:  # the parent re-raises it
        _send_error(conn, e)
        conn.close()
        return
    # The process that started this one: when it is gone, the pipe says so.
    parent_pid = os.getppid()
    block, slot = None, None
    try:
        while True:
            if block is not None:
                # Steps are answered in the block without Python until the
                # parent sends a command through the pipe, or an episode
                # that ended gets a step (the auto-reset, answered here).
                try:
                    reason = env._env.serve_steps(block, slot, spin_wait, env.max_episode_steps,
                                                  parent_pid)
                except Exception as e:  # the step's error, through the pipe
                    # Finished first: the parent reads the pipe only then,
                    # and a large message would not fit the pipe's buffer.
                    block.finish_on_pipe(slot)
                    _send_error(conn, e)
                    continue
                if reason == _core.SERVE_AUTO_RESET:
                    try:
                        obs, info = env.reset()
                        block.set_needs_reset(slot, False)
                        message = ("ok", (obs, 0.0, False, False, info))
                    except Exception as e:
                        message = _error_message(e)
                    block.finish_on_pipe(slot)
                    conn.send(message)
                    continue
            # Another worker may hold the parent's end of this pipe (forked
            # after it was made), so its end-of-file is not enough to notice
            # that the parent died.
            while not conn.poll(0.5):
                if os.getppid() != parent_pid:
                    return
            command, payload = conn.recv()
            try:
                if command == "attach":
                    name, slot, layout = payload
                    block = _core.StepBlock.attach(name, *layout)
                    conn.send(("ok", None))
                elif command == "reset":
                    seed, options = payload
                    obs, info = env.reset(seed=seed, options=options)
                    if block is not None:
                        block.set_needs_reset(slot, False)
                    conn.send(("ok", (obs, info)))
                elif command == "episode":
                    conn.send(("ok", (env._env.object_id, env._env.seed)))
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
                _send_error(conn, e)
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
        self._stepping = False  # a step_async not yet waited for
        self._block = None
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
        try:
            self._attach_block()
        except BaseException:
            self.close(terminate=True)
            raise
        self.obs_mode = self.description["obs_mode"]
        self.single_observation_space = _spaces.make_observation_space(
            self.description["observation"], self.obs_mode)
        self.single_action_space = _spaces.make_action_space(
            self.description["action_dim"],
            np.float64 if make_kwargs.get("dtypes") == "cpp" else np.float32)
        self.observation_space = _spaces.batch_space(self.single_observation_space, num_envs)
        self.action_space = _spaces.batch_space(self.single_action_space, num_envs)

    def _attach_block(self):
        """Makes the shared step block and has every worker map it (then
        the name goes: nothing is left in /dev/shm, whatever happens)."""
        layout = _block_layout(self.description, self.num_envs)
        self._block = _core.StepBlock.create(*layout)
        try:
            for slot, pipe in enumerate(self._pipes):
                pipe.send(("attach", (self._block.name, slot, layout)))
            self._receive_all()
        finally:
            self._block.unlink_name()
        self._fields, field_bytes = _field_bytes(self.description)
        memory = np.frombuffer(memoryview(self._block), dtype=np.uint8)
        self._views = []
        for slot in range(self.num_envs):
            views = {}
            for index, ((name, shape, dtype), size) in enumerate(zip(self._fields, field_bytes)):
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
        if self._stepping:
            raise _core.Error(f"{command}: a step_async is pending (call step_wait first)")
        if self._block is not None:  # the workers leave their step loops
            self._block.post_to_pipe()
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
        for i, (_, info) in enumerate(results):
            self._set_episode(i, info["object_id"], info["seed"])
        return _stack([r[0] for r in results]), _stack_infos([r[1] for r in results])

    def step(self, actions):
        self.step_async(actions)
        return self.step_wait()

    def step_async(self, actions):
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
        if self._closed:
            raise _core.Error("the vector environment is closed")
        if self._stepping:
            raise _core.Error("step_async: the previous step_async has not been waited for "
                              "(call step_wait first)")
        self._block.post_step(actions)
        self._stepping = True

    def step_wait(self):
        """The results of step_async's step: (obs, rewards, terminated,
        truncated, info), as step() returns them."""
        if not self._stepping:
            raise _core.Error("step_wait: no step_async to wait for")
        self._stepping = False
        self._wait_block()
        (rewards, terminated, truncated, success, elapsed, flags, values, on_pipe,
         points) = self._block.results()
        piped, error = {}, None
        for i in (np.flatnonzero(on_pipe) if on_pipe.any() else ()):  # auto-resets, errors
            try:
                status, payload = self._pipes[i].recv()
            except EOFError:
                self._processes[i].join(timeout=5)
                status, payload = "error", ("Error", f"died (exit code "
                                                     f"{self._processes[i].exitcode})", "")
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
        infos = []
        for i in range(self.num_envs):
            if i in piped:
                _, rewards[i], terminated[i], truncated[i], info = piped[i]
                self._set_episode(i, info["object_id"], info["seed"])
            else:
                info = make_step_info(self._object_ids[i], self._seeds[i], elapsed[i], success[i],
                                      self.description["success_conditions"], flags[i],
                                      values[i])
            infos.append(info)
        return obs, rewards, terminated, truncated, _stack_infos(infos)

    def _wait_block(self):
        """Waits for every worker's step; a worker that died is an error."""
        pending = self._block.wait_all(0.25)
        while pending:
            for i in pending:
                process = self._processes[i]
                if not process.is_alive():
                    process.join(timeout=5)
                    raise _core.Error(f"worker {i}: died (exit code {process.exitcode})")
            pending = self._block.wait_all(0.25)

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
        """_stack_infos of every environment's make_step_info, built from the
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

    def call(self, name, *args):
        """Calls method `name` of every environment; returns the results."""
        self._send_all("call", [(name, args)] * self.num_envs)
        results = self._receive_all()
        # A call (set_state) may have changed the episodes' objects and seeds.
        self._send_all("episode", [None] * self.num_envs)
        for i, (object_id, seed) in enumerate(self._receive_all()):
            self._set_episode(i, object_id, seed)
        return results

    def render(self):
        return np.stack(self.call("render"))

    def close(self, terminate=False):
        """Stops every worker and waits for it (terminating one that does
        not answer within 10 s)."""
        if self._closed:
            return
        self._closed = True
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
