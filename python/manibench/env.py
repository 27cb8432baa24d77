"""ManibenchEnv: one manibench environment with the gymnasium API.

A gymnasium.Env where gymnasium (1.x) is importable, else the stand-in base
class of manibench._standin with the same protocol (docs/python.md)."""

from __future__ import annotations

import numbers
import os
from typing import Any, Iterable, Mapping, Sequence, Union

import numpy as np

from . import _core
from . import _gym
from . import spaces as _spaces

OBS_MODES = ("state", "pointcloud", "rgbd")


def _to_yaml(value):
    """A Python value as the YAML text of a --set override."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        v = float(value)
        if np.isnan(v):
            return ".nan"
        if np.isinf(v):
            return ".inf" if v > 0 else "-.inf"
        return repr(v)
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_to_yaml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_to_yaml(v)}" for k, v in value.items()) + "}"
    return str(value)


def make_overrides(overrides=None, obs_mode=None, controller=None, dtypes="cpp"):
    """The --set KEY=VALUE list of make()'s arguments, in the CLI's order:
    the overrides, then the controller, then the observation mode; then,
    for dtypes="compact", rgbd's rgb as bytes (observation.rgb_dtype)."""
    if overrides is None:
        sets = []
    elif isinstance(overrides, dict):
        sets = [f"{key}={_to_yaml(value)}" for key, value in overrides.items()]
    elif isinstance(overrides, str):
        sets = [overrides]
    else:
        sets = [str(s) for s in overrides]
    for s in sets:
        if "=" not in s:
            raise ValueError(f"override '{s}' is not KEY=VALUE")
    if controller is not None:
        sets.append(f"control.controller={controller}")
    if obs_mode is not None:
        if obs_mode not in OBS_MODES:
            raise ValueError(f"obs_mode must be one of {', '.join(OBS_MODES)}, got {obs_mode!r}")
        sets.append(f"observation.mode={obs_mode}")
    if check_dtypes(dtypes) == "compact":
        sets.append("observation.rgb_dtype=uint8")
    return sets


def make_config_files(config):
    if config is None:
        return []
    if isinstance(config, (str, os.PathLike)):
        return [os.fspath(config)]
    return [os.fspath(c) for c in config]


# make()'s `dtypes`: "compact" (float32 vectors and actions, as gymnasium's
# Box default, Stable-Baselines3 and ManiSkill3 use, and rgbd's rgb as uint8
# images) or "cpp" (the C++ program's float64 vectors and actions and the
# configuration's rgb, float32 by default: the arrays are byte for byte
# those of `manibench run` and demonstration files).
DTYPES = ("compact", "cpp")

# What make() and make_vec() accept besides the environment id (a spec's kwargs).
ConfigFiles = Union[str, "os.PathLike[str]", Sequence[Union[str, "os.PathLike[str]"]], None]
Overrides = Union[Mapping[str, Any], Sequence[str], str, None]


def check_dtypes(dtypes: str) -> str:
    if dtypes not in DTYPES:
        raise ValueError(f"dtypes must be one of {', '.join(DTYPES)}, got {dtypes!r}")
    return dtypes


def make_step_info(object_id, seed, elapsed_steps, success, conditions, flags, values):
    """A step's info: ManibenchEnv.step's, and make_vec's for each worker.
    ``is_success`` is ``success`` under the name Stable-Baselines3 logs."""
    return {"object_id": object_id, "seed": seed, "elapsed_steps": int(elapsed_steps),
            "success": bool(success), "is_success": bool(success),
            "eval_info": {c: bool(f) for c, f in zip(conditions, flags)},
            "eval_values": {c: float(v) for c, v in zip(conditions, values)}}


def make_spec(env_id: str, **kwargs: Any) -> "_gym.EnvSpec":
    """The spec of make(env_id, **kwargs): spec.make(**more) makes another,
    gymnasium.make_vec(spec) a make_vec."""
    return _gym.EnvSpec(id=env_id, entry_point="manibench.env:ManibenchEnv",
                        vector_entry_point="manibench.vector:make_vec",
                        kwargs={"env_id": env_id, **kwargs})


class ManibenchEnv(_gym.Env):
    """A task (or fixed-object id) with gymnasium's calling convention.

    reset(seed, options) -> (obs, info); step(action) -> (obs, reward,
    terminated, truncated, info). ``terminated``: the task's ``success``
    held (with stop_on_success); ``truncated``: the time limit was reached.
    ``info``: ``success`` (and ``is_success``), ``eval_info`` (each success
    condition's flag), ``eval_values`` (its value), ``object_id``, ``seed``,
    ``elapsed_steps``. ``np_random`` is the generator that draws the seeds
    of resets without one; reset(seed=s) seeds it with s.
    """

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(self, env_id: str, obs_mode: str | None = None, controller: str | None = None,
                 config: ConfigFiles = None, overrides: Overrides = None, split: str = "train",
                 stop_on_success: bool = True, render_mode: str | None = "rgb_array",
                 render_size: tuple[int, int] = (512, 512), dtypes: str = "compact"):
        if split not in ("train", "test"):
            raise ValueError(f"split must be 'train' or 'test', got {split!r}")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be 'rgb_array' or None, got {render_mode!r}")
        self.dtypes = check_dtypes(dtypes)
        self._env = _core.Environment(env_id, make_config_files(config),
                                      make_overrides(overrides, obs_mode, controller, dtypes),
                                      bool(stop_on_success), dtypes == "compact")
        self.description = self._env.describe()
        self.env_id = env_id
        self.obs_mode = self.description["obs_mode"]
        self.split = split
        self.stop_on_success = bool(stop_on_success)
        self.render_mode = render_mode
        self.render_size = tuple(int(n) for n in render_size)
        self.max_episode_steps = self.description["max_episode_steps"]
        self.success_conditions = list(self.description["success_conditions"])
        self.observation_space = _spaces.make_observation_space(self.description["observation"],
                                                                self.obs_mode)
        self.action_space = _spaces.make_action_space(
            self.description["action_dim"], np.float32 if dtypes == "compact" else np.float64)
        self.metadata = dict(self.metadata, render_fps=self.description["control_frequency"]
                             / self.description["frame_skip"])
        self.spec = make_spec(env_id, obs_mode=obs_mode, controller=controller, config=config,
                              overrides=overrides, split=split, stop_on_success=stop_on_success,
                              render_mode=render_mode, render_size=self.render_size,
                              dtypes=dtypes)

    # ---- gymnasium API ---------------------------------------------------

    def reset(self, *, seed: int | None = None,
              options: Mapping[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        """Starts an episode. ``seed`` is the episode's seed (as ``manibench
        run --seed``) and reseeds ``np_random``, which draws the seeds of
        later resets without one. ``options``: ``object_id`` (default:
        drawn from the split by the seed, as the CLI draws it)."""
        options = dict(options or {})
        object_id = options.pop("object_id", None)
        if options:
            raise ValueError(f"unknown reset option(s): {', '.join(sorted(options))} "
                             "(known: object_id)")
        if seed is not None:
            if not isinstance(seed, numbers.Integral) or not 0 <= int(seed) < 2**64:
                raise ValueError(f"seed must be an integer in [0, 2^64), got {seed!r}")
            seed = int(seed)
        super().reset(seed=seed)  # seeds np_random (gymnasium.Env.reset)
        episode_seed = seed if seed is not None else int(self.np_random.integers(2**32))
        if object_id is None:
            object_id = self._env.choose_object(self.split, episode_seed)
        self._env.reset(str(object_id), episode_seed)
        return self._env.get_observation(), self._make_info()

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        reward, terminated, truncated, success, flags, values = self._env.step(
            np.asarray(action, dtype=np.float64))
        info = make_step_info(self._env.object_id, self._env.seed, self._env.elapsed_steps,
                              success, self.success_conditions, flags, values)
        return self._env.get_observation(), float(reward), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """An RGB image (height, width, 3; uint8) of the current state from a
        third-person camera above and in front of the robot."""
        if self.render_mode is None:
            return None
        width, height = self.render_size
        return self._env.render(width, height)

    def close(self) -> None:
        """Frees the scene; closing again does nothing."""
        self._env.close()

    def __enter__(self) -> "ManibenchEnv":
        return self

    def __exit__(self, *exc: Any) -> bool:
        self.close()
        return False

    def __repr__(self) -> str:
        return f"<ManibenchEnv {self.env_id} obs_mode={self.obs_mode}>"

    # ---- beyond gymnasium ----------------------------------------------

    def get_obs(self) -> Any:
        """The current observation (a fresh copy)."""
        return self._env.get_observation()

    def get_state(self) -> bytes:
        """The whole episode state as bytes (Environment::saveState): the
        steps after set_state(blob) are bit-identical to those after the save."""
        return self._env.save_state()

    def set_state(self, blob: bytes) -> Any:
        """Restores get_state()'s bytes (of this task); returns the observation."""
        self._env.restore_state(bytes(blob))
        return self._env.get_observation()

    def list_objects(self, split: str = "train") -> list[str]:
        return self._env.list_objects(split)

    @property
    def object_id(self) -> str:
        return self._env.object_id

    @property
    def elapsed_steps(self) -> int:
        return self._env.elapsed_steps

    def _make_info(self) -> dict[str, Any]:
        return {"object_id": self._env.object_id, "seed": self._env.seed,
                "elapsed_steps": self._env.elapsed_steps}
