"""make_vec's worker processes (manibench.vector): the loop each worker runs,
and the start of a worker in a fresh interpreter."""

from __future__ import annotations

import os
import subprocess
import sys
import traceback

import numpy as np

from . import _core
from ._gym import AutoresetMode
from .env import ManibenchEnv, make_step_info


def field_bytes(description):
    """The observation's fields (name, shape, dtype) in the order the
    workers write them into the step block, and their sizes in bytes."""
    fields = [(name, tuple(f["shape"]), np.dtype(f["dtype"]))
              for name, f in description["observation"].items()]
    return fields, [int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
                    for _, shape, dtype in fields]


def block_layout(description, num_envs):
    """StepBlock.create's and attach's arguments after the name."""
    return (num_envs, description["action_dim"], len(description["success_conditions"]),
            field_bytes(description)[1])


def _error_message(e):
    """An exception as the ("error", ...) message the parent re-raises."""
    return ("error", (type(e).__name__, str(e), traceback.format_exc()))


def _send_error(conn, e):
    conn.send(_error_message(e))


def _episode(env):
    """The worker's episode (object id, seed): its step infos' constants."""
    try:
        return env._env.object_id, env._env.seed
    except Exception:  # closed
        return None, None


def _end_episode(env, block, slot, mode):
    """The worker's answer to a step that ended an episode (SAME_STEP: reset
    now, the last observation and info in final_obs and final_info) or to
    a step of an ended one (NEXT_STEP: the new episode; DISABLED: an
    error). Returns the pipe message."""
    if mode == AutoresetMode.DISABLED.value:
        raise _core.Error("the episode ended: reset this environment first "
                          "(reset(options={'reset_mask': mask}))")
    if mode == AutoresetMode.NEXT_STEP.value:
        obs, info = env.reset()
        block.set_needs_reset(slot, False)
        return obs, 0.0, False, False, info
    reward, terminated, truncated, success, flags, values = env._env.get_last_step()
    elapsed = env._env.elapsed_steps
    final_info = make_step_info(env._env.object_id, env._env.seed, elapsed, success,
                                env.success_conditions, flags, values)
    final_obs = env.get_obs()
    obs, info = env.reset()
    block.set_needs_reset(slot, False)
    return obs, reward, terminated, truncated, dict(info, final_obs=final_obs,
                                                    final_info=final_info)


def run_worker(conn, make_kwargs, spin_wait=0.0, mode=AutoresetMode.NEXT_STEP.value):
    """A worker's life: makes its environment, maps the step block when
    told, answers steps there and everything else on the pipe."""

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
                # ends (SAME_STEP) or an ended one gets a step (answered here).
                try:
                    reason = env._env.serve_steps(block, slot, spin_wait, parent_pid,
                                                  mode == AutoresetMode.SAME_STEP.value)
                    if reason != _core.SERVE_TO_PIPE:
                        message = ("ok", _end_episode(env, block, slot, mode))
                except Exception as e:  # the step's error, through the pipe
                    reason, message = None, _error_message(e)
                if reason != _core.SERVE_TO_PIPE:
                    # Finished first: the parent reads the pipe only then,
                    # and a large message would not fit the pipe's buffer.
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
                elif command == "get_obs":
                    conn.send(("ok", env.get_obs()))
                elif command == "call":
                    name, args, kwargs = payload
                    attribute = env.get_wrapper_attr(name)
                    result = attribute(*args, **kwargs) if callable(attribute) else attribute
                    conn.send(("ok", (result, _episode(env))))
                elif command == "set_attr":
                    name, value = payload
                    env.set_wrapper_attr(name, value)
                    conn.send(("ok", None))
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


def run_spawned_worker(fd):
    """A spawned worker's start: the pipe's end is file descriptor `fd`;
    the first message is run_worker's arguments."""
    from multiprocessing.connection import Connection

    conn = Connection(fd)
    run_worker(conn, *conn.recv())


class SpawnedProcess:
    """A worker in a fresh interpreter that runs run_spawned_worker and imports
    nothing else: multiprocessing's spawn would run the caller's main
    script again, which without an ``if __name__ == "__main__":`` guard
    starts the workers again, and they die. The same calls as
    multiprocessing.Process."""

    def __init__(self, child):
        package_root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        code = (f"import sys; sys.path.insert(0, {package_root!r}); "
                f"from manibench._worker import run_spawned_worker; "
                f"run_spawned_worker({child.fileno()})")
        self._popen = subprocess.Popen([sys.executable, "-c", code], pass_fds=[child.fileno()],
                                       stdin=subprocess.DEVNULL,
                                       env=dict(os.environ, MANIBENCH_GYMNASIUM_REGISTER="0"))
        self.pid = self._popen.pid

    def is_alive(self):
        return self._popen.poll() is None

    @property
    def exitcode(self):
        return self._popen.poll()

    def join(self, timeout=None):
        try:
            self._popen.wait(timeout)
        except subprocess.TimeoutExpired:
            pass

    def terminate(self):
        if self.is_alive():
            self._popen.terminate()

    def kill(self):
        if self.is_alive():
            self._popen.kill()
