"""Observation and action spaces.

With gymnasium importable, make() returns gymnasium's own ``Box`` and
``Dict``. Without it (Debian 12 does not package gymnasium) these small
classes stand in with the same attributes: ``shape``, ``dtype``, ``low``,
``high``, ``sample()``, ``seed()``, ``contains()``.
"""

import numpy as np

try:  # pragma: no cover - depends on the machine
    import gymnasium as _gymnasium
except ImportError:  # pragma: no cover
    _gymnasium = None


class Box:
    """Arrays of one shape and dtype within [low, high] (gymnasium.spaces.Box)."""

    def __init__(self, low, high, shape, dtype, seed=None):
        self.shape = tuple(int(n) for n in shape)
        self.dtype = np.dtype(dtype)
        self.low = np.full(self.shape, low, dtype=self.dtype)
        self.high = np.full(self.shape, high, dtype=self.dtype)
        self.np_random = np.random.default_rng(seed)

    def seed(self, seed=None):
        self.np_random = np.random.default_rng(seed)
        return [seed]

    def sample(self):
        """Uniform within finite bounds; normal where a bound is infinite."""
        if self.dtype == np.bool_:
            return self.np_random.integers(0, 2, size=self.shape).astype(np.bool_)
        low = self.low.astype(np.float64)
        high = self.high.astype(np.float64)
        out = self.np_random.normal(size=self.shape)
        bounded = np.isfinite(low) & np.isfinite(high)
        out[bounded] = self.np_random.uniform(low[bounded], high[bounded])
        below = np.isfinite(low) & ~np.isfinite(high)
        out[below] = low[below] + self.np_random.exponential(size=int(below.sum()))
        above = ~np.isfinite(low) & np.isfinite(high)
        out[above] = high[above] - self.np_random.exponential(size=int(above.sum()))
        return out.astype(self.dtype)

    def contains(self, x):
        x = np.asarray(x)
        if x.shape != self.shape or not np.can_cast(x.dtype, self.dtype):
            return False
        return bool(np.all(x >= self.low) and np.all(x <= self.high))

    __contains__ = contains

    def __repr__(self):
        low = self.low.flat[0] if self.low.size else None
        high = self.high.flat[0] if self.high.size else None
        return f"Box({low}, {high}, {self.shape}, {self.dtype})"

    def __eq__(self, other):
        return (isinstance(other, Box) and self.shape == other.shape and self.dtype == other.dtype
                and np.array_equal(self.low, other.low) and np.array_equal(self.high, other.high))


class Dict:
    """A dict of spaces (gymnasium.spaces.Dict); shape and dtype are None."""

    def __init__(self, spaces, seed=None):
        self.spaces = dict(spaces)
        self.shape = None
        self.dtype = None
        self.seed(seed)

    def seed(self, seed=None):
        seeds = np.random.SeedSequence(seed).spawn(len(self.spaces))
        for space, s in zip(self.spaces.values(), seeds):
            space.seed(int(s.generate_state(1)[0]))
        return [seed]

    def sample(self):
        return {key: space.sample() for key, space in self.spaces.items()}

    def contains(self, x):
        return (isinstance(x, dict) and set(x) == set(self.spaces)
                and all(self.spaces[k].contains(v) for k, v in x.items()))

    __contains__ = contains

    def __getitem__(self, key):
        return self.spaces[key]

    def keys(self):
        return self.spaces.keys()

    def items(self):
        return self.spaces.items()

    def __repr__(self):
        return "Dict(" + ", ".join(f"{k!r}: {v}" for k, v in self.spaces.items()) + ")"


def make_box(low, high, shape, dtype):
    """gymnasium's Box when gymnasium is importable, else ours."""
    if _gymnasium is not None:  # pragma: no cover
        return _gymnasium.spaces.Box(low=low, high=high, shape=tuple(shape), dtype=np.dtype(dtype))
    return Box(low, high, shape, dtype)


def make_dict(spaces):
    if _gymnasium is not None:  # pragma: no cover
        return _gymnasium.spaces.Dict(spaces)
    return Dict(spaces)


def make_observation_space(fields, obs_mode):
    """The space of an observation described by _core's describe()['observation']."""
    boxes = {name: make_box(f["low"], f["high"], f["shape"], f["dtype"]) for name, f in fields.items()}
    if obs_mode == "state":
        return boxes["state"]
    return make_dict(boxes)


def make_action_space(action_dim):
    """Normalized actions in [-1, 1] (the environment clips to it)."""
    return make_box(-1.0, 1.0, (action_dim,), np.float64)


def batch_space(space, n):
    """The space of n stacked samples of `space` (gymnasium.vector.utils.batch_space)."""
    if isinstance(space, Dict) or (space.shape is None and hasattr(space, "spaces")):
        return make_dict({k: batch_space(s, n) for k, s in space.spaces.items()})
    return make_box(np.broadcast_to(space.low, (n,) + space.shape).copy(),
                    np.broadcast_to(space.high, (n,) + space.shape).copy(), (n,) + space.shape,
                    space.dtype)
