"""Observation and action spaces.

``Box`` and ``Dict`` are gymnasium's where gymnasium (1.x) is importable,
else manibench._standin's, which follow the same protocol: iterable,
sized, comparable dicts with sorted keys, ``seed()`` returning the seeds
used, ``sample(mask=None)``, and the same samples from the same seed.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from ._gym import Box, Dict, Space, batch_space

__all__ = ["Box", "Dict", "Space", "batch_space", "make_action_space", "make_observation_space"]


def make_observation_space(fields: Mapping[str, Mapping[str, Any]], obs_mode: str) -> Space:
    """The space of an observation described by _core's describe()['observation']:
    a Box in the state mode, else a Dict of Boxes."""
    boxes = {name: Box(low=f["low"], high=f["high"], shape=tuple(f["shape"]),
                       dtype=np.dtype(f["dtype"]))
             for name, f in fields.items()}
    if obs_mode == "state":
        return boxes["state"]
    return Dict(boxes)


def make_action_space(action_dim: int, dtype: Any = np.float32) -> Box:
    """Normalized actions in [-1, 1] (the environment clips to it)."""
    return Box(low=-1.0, high=1.0, shape=(action_dim,), dtype=np.dtype(dtype))
