"""manibench from Python: gymnasium-style environments over the C++ core.

    import manibench
    env = manibench.make("OpenCabinetDrawer-v0", obs_mode="pointcloud",
                         controller="mobile_panda_ee")
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

Plugins are found as the ``manibench`` program finds them
($MANIBENCH_PLUGIN_PATH, ~/.local/lib/manibench/plugins, then the
lib/manibench/plugins of the installation or build tree this module lies
in). docs/python.md has the whole story.
"""

from __future__ import annotations

import os
from typing import Any

from . import _core
from . import _gym
from ._core import (ConfigError, EpisodeFailure, Error, InvalidAction, InvalidArgument,
                    PluginCallError, PluginError)
from ._gym import AutoresetMode
from .env import DTYPES, OBS_MODES, ConfigFiles, ManibenchEnv, Overrides, check_dtypes
from .env import make_config_files as _make_config_files
from .env import make_overrides as _make_overrides
from .vector import VectorEnv, make_vec

__version__ = _core.get_version()

__all__ = [
    "AutoresetMode", "ConfigError", "DTYPES", "EpisodeFailure", "Error", "InvalidAction",
    "InvalidArgument", "ManibenchEnv", "OBS_MODES", "PluginCallError", "PluginError", "VectorEnv",
    "env_ids", "info", "list_plugins", "list_tasks", "make", "make_vec", "objects",
]


def make(env_id: str, obs_mode: str | None = None, controller: str | None = None,
         config: ConfigFiles = None, overrides: Overrides = None, **kwargs: Any) -> ManibenchEnv:
    """An environment: a task name ("OpenCabinetDrawer-v0") or a fixed-object
    id ("OpenCabinetDrawer_1000-v0").

    obs_mode: "state", "pointcloud" or "rgbd" (default: the configuration's,
    state). controller: a controller plugin (default: the task's). config: a
    YAML file or a list of them (as --config). overrides: {key: value} or
    ["key=value", ...] (as --set). Further keywords: split ("train": where
    resets without an object_id draw from), stop_on_success (True),
    render_mode ("rgb_array"), render_size ((512, 512)), dtypes
    ("compact": float32 vectors and actions; "cpp": the C++ program's
    float64, byte for byte).
    """
    return ManibenchEnv(env_id, obs_mode=obs_mode, controller=controller, config=config,
                        overrides=overrides, **kwargs)


def list_tasks():
    """The registered task names (`manibench list`)."""
    return list(_core.list_tasks())


def list_plugins():
    """Every registered plugin (kind, name, summary, library), and the
    libraries refused, as `manibench list` prints them."""
    return {"plugins": list(_core.list_plugins()),
            "failures": [{"path": p, "message": m} for p, m in _core.list_load_failures()],
            "search_path": list(_core.get_search_path())}


def _describe(env_id, obs_mode, controller, config, overrides, dtypes):
    core = _core.Environment(env_id, _make_config_files(config),
                             _make_overrides(overrides, obs_mode, controller, dtypes), True,
                             check_dtypes(dtypes) == "compact")
    try:
        d = core.describe()
        d["objects"] = {"train": len(core.list_objects("train")),
                        "test": len(core.list_objects("test"))}
        return d
    finally:
        core.close()


def info(env_id: str, obs_mode: str | None = None, controller: str | None = None,
         config: ConfigFiles = None, overrides: Overrides = None,
         dtypes: str = "compact") -> dict[str, Any]:
    """What `manibench info` prints, as a dict: timing, observation layout
    and the shapes of each observation array (``observation``; their dtypes
    those of make(..., dtypes=dtypes)), the controller's action layout,
    success conditions, masks, objects per split, cameras."""
    return _describe(env_id, obs_mode, controller, config, overrides, dtypes)


def objects(env_id, split="train", config=None, overrides=None):
    """The object ids of a split (`manibench objects --ids`); a fixed-object
    id's own objects whatever the split."""
    if split not in ("train", "test"):
        raise ValueError(f"split must be 'train' or 'test', got {split!r}")
    core = _core.Environment(env_id, _make_config_files(config), _make_overrides(overrides), True)
    try:
        return list(core.list_objects(split))
    finally:
        core.close()


def __getattr__(name: str) -> Any:
    # manibench.demos on first use: it imports h5py (and torch, where it is
    # installed), which a user of the environments alone should not wait for.
    if name == "demos":
        import importlib
        return importlib.import_module(".demos", __name__)
    raise AttributeError(f"module 'manibench' has no attribute {name!r}")


def env_ids() -> list[str]:
    """Every task and every fixed-object id (`manibench objects` names them):
    the ids registered with gymnasium on import where it is importable
    (gymnasium.make(id, **make's keywords), gymnasium.make_vec(id, n))."""
    from ._registration import list_env_ids
    return list_env_ids()


# make_vec's spawned workers set MANIBENCH_GYMNASIUM_REGISTER=0: they need no ids.
if _gym.is_available() and os.environ.get("MANIBENCH_GYMNASIUM_REGISTER", "1") != "0":  # pragma: no cover
    from ._registration import register_all as _register_all
    _register_all(_gym.gymnasium.register, _gym.gymnasium.registry)
