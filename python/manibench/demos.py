"""Demonstration files (docs/demonstrations.md) from Python: trajectories as
numpy arrays under the layout table's names, and, where torch is
importable, a torch.utils.data.Dataset over one or more files.

    from manibench import demos
    with demos.DemoFile("drawer.h5") as f:
        print(f.meta["task"], len(f))
        t = f[0]                       # or f["traj_0"]
        t["actions"], t["obs"], t["rewards"], t.attrs["seed"], t.state(0)

    data = demos.TransitionDataset(["drawer.h5"], fields="transition")
    for batch in data.loader(batch_size=256, shuffle=True):
        obs, action, reward, next_obs, done = batch

Reading needs h5py (Debian's python3-h5py; scripts/install-deps installs it).
"""

from __future__ import annotations

import os
import re
from typing import Any, Iterator, Sequence

import numpy as np

FORMAT = "manibench-demonstrations"

# The per-step datasets of a trajectory group besides obs (layout table).
STEP_FIELDS = ("actions", "rewards", "terminated", "truncated", "success", "conditions")


def _h5py():
    try:
        import h5py
    except ImportError as e:  # pragma: no cover - install-deps installs it
        raise ImportError("manibench.demos needs h5py (Debian: apt install python3-h5py)") from e
    return h5py


def _text(value: Any) -> Any:
    """An attribute as Python: strings decoded, arrays of strings as lists,
    numpy scalars as Python numbers."""
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "SO":
            return [_text(v) for v in value.tolist()]
        return value.tolist() if value.ndim else value.item()
    if isinstance(value, np.generic):
        return value.item()
    return value


class Trajectory(dict):
    """One trajectory: the layout table's datasets as numpy arrays by name
    (``actions``, ``rewards``, ``terminated``, ``truncated``, ``success``,
    ``conditions``, ``obs`` (an array in the state mode, else a dict:
    ``agent``, ``xyz``, ``rgb``, ``seg``, ``depth``, ``point_count``),
    ``env_states``, ``env_state_offsets``), ``attrs`` (task, object_id,
    level, seed, steps, success, total_reward) and ``name``."""

    def __init__(self, name: str, attrs: dict, arrays: dict):
        super().__init__(arrays)
        self.name = name
        self.attrs = attrs

    @property
    def steps(self) -> int:
        return int(self.attrs["steps"])

    def state(self, t: int) -> bytes:
        """The environment state after the reset (t = 0) or step t
        (ManibenchEnv.set_state takes it)."""
        offsets = self["env_state_offsets"]
        return self["env_states"][int(offsets[t]):int(offsets[t + 1])].tobytes()


def _trajectory_index(name: str) -> int:
    match = re.fullmatch(r"traj_(\d+)", name)
    return int(match.group(1)) if match else -1


class DemoFile:
    """A demonstration file, read with h5py. ``meta``: the set's
    description (/meta attributes: task, env_id, controller, obs_mode,
    condition_names, config, ...); ``names``: the trajectories in order;
    ``f[i]`` or ``f["traj_i"]`` reads one (``states=False`` skips the
    environment states, the largest part)."""

    def __init__(self, path: str | os.PathLike):
        self.path = os.fspath(path)
        self._file = _h5py().File(self.path, "r")
        try:
            if _text(self._file.attrs.get("format")) != FORMAT:
                raise ValueError(f"{self.path}: not a manibench demonstration file (no format "
                                 f"attribute '{FORMAT}')")
            self.meta = {k: _text(v) for k, v in self._file["meta"].attrs.items()}
            self.names = sorted((n for n in self._file if _trajectory_index(n) >= 0),
                                key=_trajectory_index)
        except BaseException:
            self._file.close()
            raise

    @property
    def controller(self) -> str:
        """The controller whose actions the file holds."""
        return self.meta.get("controller", "")

    @property
    def converted_from(self) -> str | None:
        """For a file `demos convert` made: the input file; else None."""
        return self.meta.get("converted_from")

    @property
    def conversion(self) -> str | None:
        """For a converted file: "observations" (another observation mode),
        "exact" (another controller's actions, the same physics bit for bit)
        or "tracked" (another controller following the recorded states);
        else None."""
        return self.meta.get("conversion")

    def __len__(self) -> int:
        return len(self.names)

    def __getitem__(self, key: int | str) -> Trajectory:
        return self.read(self.names[key] if isinstance(key, int) else key)

    def __iter__(self) -> Iterator[Trajectory]:
        for name in self.names:
            yield self.read(name)

    def read(self, name: str, states: bool = True, fields: Sequence[str] | None = None) -> Trajectory:
        """Trajectory `name`; `fields` limits the datasets read (names of
        the layout table, "obs" for every observation array)."""
        if name not in self._file:
            raise KeyError(f"{self.path}: no trajectory {name!r}")
        group = self._file[name]
        wanted = set(fields) if fields is not None else None
        arrays = {}
        for key, item in group.items():
            if wanted is not None and key not in wanted:
                continue
            if not states and key.startswith("env_state"):
                continue
            if key == "obs" and not hasattr(item, "shape"):
                arrays[key] = {k: v[()] for k, v in item.items()}
            else:
                arrays[key] = item[()]
        return Trajectory(name, {k: _text(v) for k, v in group.attrs.items()}, arrays)

    def dataset(self, name: str, key: str) -> Any:
        """The h5py dataset `key` ("actions", "obs", "obs/xyz", ...) of
        trajectory `name`, unread (for read_direct and slices)."""
        return self._file[name][key]

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> "DemoFile":
        return self

    def __exit__(self, *exc: Any) -> bool:
        self.close()
        return False


def read(path: str | os.PathLike, states: bool = True) -> list[Trajectory]:
    """Every trajectory of a file."""
    with DemoFile(path) as f:
        return [f.read(name, states=states) for name in f.names]


FIELDS = {
    "bc": ("obs", "action"),
    "transition": ("obs", "action", "reward", "next_obs", "done"),
}


def _read_steps(paths: Sequence[str], keys: Sequence[str]) -> tuple[dict, list[int]]:
    """Dataset `key` of every trajectory of every file, one trajectory after
    another in one array per key, and each trajectory's number of steps.
    Through h5py's low-level calls: one open per dataset, each read
    straight into its rows of the preallocated array (the high-level
    objects and a concatenation cost about a fifth more: 0.53 against
    0.42 s for the actions and observations of 500 drawer trajectories)."""
    h5py = _h5py()
    handles, files = {key: [] for key in keys}, []
    try:
        for path in paths:
            f = DemoFile(path)
            files.append(f)
            if f.meta.get("obs_mode") != "state":
                raise ValueError(f"{f.path}: TransitionDataset reads state-mode files, this one "
                                 f"is {f.meta.get('obs_mode')!r}")
            for name in f.names:
                group = h5py.h5g.open(f._file.id, name.encode())
                for key in keys:
                    handles[key].append(h5py.h5d.open(group, key.encode()))
        if not handles[keys[0]]:
            raise ValueError("no trajectories in " + ", ".join(map(str, paths)))
        columns = {}
        for key in keys:
            first = handles[key][0]
            rows = [d.shape[0] for d in handles[key]]
            out = np.empty((sum(rows),) + first.shape[1:], dtype=first.dtype)
            at = 0
            for dataset, n in zip(handles[key], rows):
                if n:
                    dataset.read(h5py.h5s.ALL, h5py.h5s.ALL, out[at:at + n])
                at += n
            columns[key] = out
        steps = [d.shape[0] for d in handles["actions"]]
        return columns, steps
    finally:
        for key in handles:
            for dataset in handles[key]:
                dataset.close()
        for f in files:
            f.close()


def _dataset_class():
    try:
        import torch
        import torch.utils.data
    except ImportError:  # pragma: no cover - depends on the machine
        return None, None
    return torch, torch.utils.data.Dataset


_torch, _TorchDataset = _dataset_class()


if _TorchDataset is not None:
    class TransitionDataset(_TorchDataset):
        """The steps of every trajectory of one or more state-mode files as
        a torch Dataset: fields="bc" gives (obs, action) pairs,
        "transition" gives (obs, action, reward, next_obs, done), done
        being ``terminated`` (the episode ended by success; a trajectory
        cut by the time limit is not done). Loaded into memory once, as
        tensors of `dtype` (float32: the compact dtypes) and bool; each
        trajectory's T + 1 observations are kept once (obs and next_obs
        are rows of one tensor).

        ``data[i]`` is step i; ``data[indices]`` (a list or tensor of
        indices) a whole batch at once: ``loader()`` uses that, one gather
        per batch instead of one call per step and a collate.
        """

        def __init__(self, paths: str | os.PathLike | Sequence[str | os.PathLike],
                     fields: str = "bc", dtype: Any = None):
            if fields not in FIELDS:
                raise ValueError(f"fields must be one of {', '.join(FIELDS)}, got {fields!r}")
            self.fields = FIELDS[fields]
            dtype = _torch.float32 if dtype is None else dtype
            if isinstance(paths, (str, os.PathLike)):
                paths = [paths]
            keys = ["actions", "obs"] + (["rewards", "terminated"] if "reward" in self.fields else [])
            columns, steps = _read_steps([os.fspath(p) for p in paths], keys)
            self.steps_per_trajectory = steps
            # Step i of trajectory k is observation row i + k (each trajectory
            # has one more observation than steps); its successor the next row.
            self._rows = _torch.from_numpy(np.arange(sum(steps), dtype=np.int64)
                                           + np.repeat(np.arange(len(steps)), steps))
            self._obs = _torch.from_numpy(columns["obs"]).to(dtype)
            self._action = _torch.from_numpy(columns["actions"]).to(dtype)
            if "reward" in self.fields:
                self._reward = _torch.from_numpy(columns["rewards"]).to(dtype)
                self._done = _torch.from_numpy(columns["terminated"].astype(np.bool_))

        def __len__(self) -> int:
            return int(self._rows.shape[0])

        def __getitem__(self, index: Any) -> tuple:
            rows = self._rows[index]
            if len(self.fields) == 2:
                return self._obs[rows], self._action[index]
            return (self._obs[rows], self._action[index], self._reward[index],
                    self._obs[rows + 1], self._done[index])

        def loader(self, batch_size: int = 256, shuffle: bool = True, drop_last: bool = False,
                   generator: Any = None, **kwargs: Any) -> Any:
            """A DataLoader of whole batches (``data[indices]``, no collate)."""
            if shuffle:
                sampler = _torch.utils.data.RandomSampler(self, generator=generator)
            else:
                sampler = _torch.utils.data.SequentialSampler(self)
            batches = _torch.utils.data.BatchSampler(sampler, batch_size, drop_last)
            return _torch.utils.data.DataLoader(self, sampler=batches, batch_size=None, **kwargs)
