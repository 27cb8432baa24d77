"""What stands in for gymnasium where it is not importable.

Debian 12 does not package gymnasium, so the package must work without
it, and a program must behave the same with and without it. These classes
follow gymnasium 1.x's documented protocol (written from its API
documentation, not copied): the spaces ``Box`` and ``Dict`` (sampling
draws the same numbers from the same seed as gymnasium's), ``EnvSpec``,
the ``Env`` and ``VectorEnv`` base classes with their seeding,
``AutoresetMode`` and the vector info stacking (``add_info``).
manibench._gym picks gymnasium's classes where it is importable, these
otherwise; python/tests/test_spaces.py checks both against each other where
gymnasium is installed, and these against the documented behaviour always.
"""

from __future__ import annotations

import collections.abc
import copy
import enum
import importlib
import re
from typing import Any, Iterator, Mapping, Sequence

import numpy as np


class Error(Exception):
    """gymnasium.error.Error's stand-in: a misuse of a space or an environment."""


def np_random(seed: int | None = None) -> tuple[np.random.Generator, int]:
    """A generator and the seed it was made from (gymnasium.utils.seeding):
    PCG64 over SeedSequence(seed); without a seed, the OS's entropy, which
    is then the seed returned."""
    if seed is not None and not (isinstance(seed, int) and not isinstance(seed, bool)
                                 and seed >= 0):
        if not isinstance(seed, int):
            raise Error(f"Seed must be a python integer, actual type: {type(seed)}")
        raise Error(f"Seed must be greater or equal to zero, actual value: {seed}")
    sequence = np.random.SeedSequence(seed)
    return np.random.Generator(np.random.PCG64(sequence)), int(sequence.entropy)


# ---- spaces ----------------------------------------------------------------


class Space:
    """gymnasium.spaces.Space: shape, dtype and a generator seeded lazily."""

    def __init__(self, shape: Sequence[int] | None = None, dtype: Any = None,
                 seed: int | np.random.Generator | None = None):
        self._shape = None if shape is None else tuple(shape)
        self.dtype = None if dtype is None else np.dtype(dtype)
        self._np_random = None
        if seed is not None:
            if isinstance(seed, np.random.Generator):
                self._np_random = seed
            else:
                self.seed(seed)

    @property
    def np_random(self) -> np.random.Generator:
        if self._np_random is None:
            self.seed()
        return self._np_random

    @property
    def shape(self) -> tuple[int, ...] | None:
        return self._shape

    @property
    def is_np_flattenable(self) -> bool:
        raise NotImplementedError

    def sample(self, mask: Any = None, probability: Any = None) -> Any:
        raise NotImplementedError

    def seed(self, seed: int | None = None) -> Any:
        """Seeds the space's generator; returns the seeds used (the OS's
        entropy when `seed` is None)."""
        self._np_random, used = np_random(seed)
        return [used]

    def contains(self, x: Any) -> bool:
        raise NotImplementedError

    def __contains__(self, x: Any) -> bool:
        return self.contains(x)

    def to_jsonable(self, sample_n: Sequence[Any]) -> list:
        return list(sample_n)

    def from_jsonable(self, sample_n: list) -> list:
        return sample_n


def _short_repr(array: np.ndarray) -> str:
    if array.size != 0 and np.min(array) == np.max(array):
        return str(np.min(array))
    return str(array)


def _is_scalar(value: Any) -> bool:
    return np.issubdtype(type(value), np.integer) or np.issubdtype(type(value), np.floating)


class Box(Space):
    """gymnasium.spaces.Box: arrays of one shape and dtype (integer,
    floating or bool) within [low, high], bounds possibly infinite."""

    def __init__(self, low: Any, high: Any, shape: Sequence[int] | None = None,
                 dtype: Any = np.float32, seed: int | np.random.Generator | None = None):
        if dtype is None:
            raise ValueError("Box dtype must be explicitly provided, cannot be None.")
        self.dtype = np.dtype(dtype)
        if not (np.issubdtype(self.dtype, np.integer) or np.issubdtype(self.dtype, np.floating)
                or self.dtype == np.bool_):
            raise ValueError(f"Invalid Box dtype ({self.dtype}), must be an integer, floating, "
                             "or bool dtype")
        if shape is not None:
            shape = tuple(int(n) for n in shape)
        elif isinstance(low, np.ndarray) and isinstance(high, np.ndarray):
            if low.shape != high.shape:
                raise ValueError(f"Box low.shape and high.shape don't match, "
                                 f"low.shape={low.shape}, high.shape={high.shape}")
            shape = low.shape
        elif isinstance(low, np.ndarray):
            shape = low.shape
        elif isinstance(high, np.ndarray):
            shape = high.shape
        elif _is_scalar(low) and _is_scalar(high):
            shape = (1,)
        else:
            raise ValueError("Box shape is not specified and cannot be inferred from low and high")
        self._shape = shape
        if self.dtype == np.bool_:
            dtype_min, dtype_max = 0, 1
        elif np.issubdtype(self.dtype, np.floating):
            dtype_min, dtype_max = float(np.finfo(self.dtype).min), float(np.finfo(self.dtype).max)
        else:
            dtype_min, dtype_max = int(np.iinfo(self.dtype).min), int(np.iinfo(self.dtype).max)
        self.low, self.bounded_below = self._cast_bound(low, dtype_min, -1)
        self.high, self.bounded_above = self._cast_bound(high, dtype_max, +1)
        if self.low.shape != shape or self.high.shape != shape:
            raise ValueError(f"Box low.shape {self.low.shape} or high.shape {self.high.shape} "
                             f"doesn't match shape {shape}")
        if np.any(self.low > self.high):
            raise ValueError(f"Box all low values must be less than or equal to high, "
                             f"low={self.low}, high={self.high}")
        self.low_repr = _short_repr(self.low)
        self.high_repr = _short_repr(self.high)
        super().__init__(self._shape, self.dtype, seed)

    def _cast_bound(self, value: Any, limit: Any, sign: int) -> tuple[np.ndarray, np.ndarray]:
        """The bound as an array of the dtype, and where it is finite. An
        infinite bound of a signed integer dtype is the dtype's limit;
        unsigned and bool dtypes take none."""
        name = "low" if sign < 0 else "high"
        array = np.full(self._shape, value, dtype=float) if _is_scalar(value) else value
        if not isinstance(array, np.ndarray):
            raise ValueError(f"Box {name} must be a np.ndarray, integer, or float, "
                             f"actual type={type(value)}")
        if array.dtype.kind not in "biuf":
            raise ValueError(f"Box {name} must be a floating, integer, or bool dtype, actual "
                             f"dtype={array.dtype}")
        numeric = array.astype(float)
        if np.any(np.isnan(numeric)):
            raise ValueError(f"No {name} value can be equal to `np.nan`, {name}={value}")
        bounded = np.isfinite(numeric) | (np.sign(numeric) != sign)
        infinite = np.isinf(numeric) & (np.sign(numeric) == sign)
        if np.any(infinite):
            if self.dtype.kind in "ub":
                raise ValueError(f"Box unsigned int and bool dtypes don't support infinite "
                                 f"bounds, {name}={value}")
            if self.dtype.kind == "i":
                array = array.copy()
                array[infinite] = limit
        elif array.dtype != self.dtype and np.any(sign * (numeric - limit) > 0):
            raise ValueError(f"Box {name} is out of bounds of the dtype range, {name}={value}")
        return array.astype(self.dtype), bounded

    @property
    def shape(self) -> tuple[int, ...]:
        return self._shape

    @property
    def is_np_flattenable(self) -> bool:
        return True

    def is_bounded(self, manner: str = "both") -> bool:
        below, above = bool(np.all(self.bounded_below)), bool(np.all(self.bounded_above))
        if manner == "both":
            return below and above
        if manner == "below":
            return below
        if manner == "above":
            return above
        raise ValueError(f"manner is not in {{'below', 'above', 'both'}}, actual value: {manner}")

    def sample(self, mask: None = None, probability: None = None) -> np.ndarray:
        """Per coordinate: uniform on [low, high], low + exponential,
        high - exponential, or normal, as the bounds are finite; integer
        dtypes take the floor of a draw over [low, high + 1). The draws, in
        this order, are gymnasium's, so the same seed gives the same sample."""
        if mask is not None:
            raise Error(f"Box.sample cannot be provided a mask, actual value: {mask}")
        if probability is not None:
            raise Error(f"Box.sample cannot be provided a probability mask, actual value: "
                        f"{probability}")
        high = self.high if self.dtype.kind == "f" else self.high.astype("int64") + 1
        out = np.empty(self._shape)
        unbounded = ~self.bounded_below & ~self.bounded_above
        above_only = ~self.bounded_below & self.bounded_above
        below_only = self.bounded_below & ~self.bounded_above
        bounded = self.bounded_below & self.bounded_above
        rng = self.np_random
        out[unbounded] = rng.normal(size=unbounded[unbounded].shape)
        out[below_only] = rng.exponential(size=below_only[below_only].shape) + self.low[below_only]
        out[above_only] = -rng.exponential(size=above_only[above_only].shape) + high[above_only]
        out[bounded] = rng.uniform(low=self.low[bounded], high=high[bounded],
                                   size=bounded[bounded].shape)
        if self.dtype.kind in "iub":
            out = np.floor(out)
        if np.issubdtype(self.dtype, np.signedinteger):
            out = out.clip(np.iinfo(self.dtype).min + 2, np.iinfo(self.dtype).max - 2)
        elif np.issubdtype(self.dtype, np.unsignedinteger):
            out = out.clip(np.iinfo(self.dtype).min, np.iinfo(self.dtype).max)
        out = out.astype(self.dtype)
        if self.dtype == np.int64:
            out = out.clip(self.low, self.high)
        return out

    def contains(self, x: Any) -> bool:
        if not isinstance(x, np.ndarray):
            try:
                x = np.asarray(x, dtype=self.dtype)
            except (ValueError, TypeError):
                return False
        return bool(np.can_cast(x.dtype, self.dtype) and x.shape == self._shape
                    and np.all(x >= self.low) and np.all(x <= self.high))

    def to_jsonable(self, sample_n: Sequence[np.ndarray]) -> list:
        return [np.asarray(s).tolist() for s in sample_n]

    def from_jsonable(self, sample_n: Sequence[Any]) -> list:
        return [np.asarray(s, dtype=self.dtype) for s in sample_n]

    def __repr__(self) -> str:
        return f"Box({self.low_repr}, {self.high_repr}, {self._shape}, {self.dtype})"

    def __eq__(self, other: Any) -> bool:
        return (isinstance(other, Box) and self._shape == other._shape
                and self.dtype == other.dtype and np.allclose(self.low, other.low)
                and np.allclose(self.high, other.high))


class Dict(Space, collections.abc.Mapping):
    """gymnasium.spaces.Dict: a mapping of names to spaces, keys sorted
    (unless given as an OrderedDict or a sequence of pairs); iterable,
    sized and comparable like a dict."""

    def __init__(self, spaces: Any = None, seed: Any = None, **spaces_kwargs: Space):
        if isinstance(spaces, collections.OrderedDict):
            items = dict(spaces.items())
        elif isinstance(spaces, collections.abc.Mapping):
            try:
                items = dict(sorted(spaces.items()))
            except TypeError:  # keys that do not compare: insertion order
                items = dict(spaces.items())
        elif isinstance(spaces, Sequence):
            items = dict(spaces)
        elif spaces is None:
            items = {}
        else:
            raise TypeError(f"Unexpected Dict space input, expecting dict, OrderedDict or "
                            f"Sequence, actual type: {type(spaces)}")
        for key, space in spaces_kwargs.items():
            if key in items:
                raise ValueError(f"Dict space keyword '{key}' already exists in the spaces "
                                 "dictionary.")
            items[key] = space
        for key, space in items.items():
            if not isinstance(space, Space):
                raise AssertionError(f"Dict space element is not an instance of Space: "
                                     f"key='{key}', space={space}")
        self.spaces = items
        super().__init__(None, None, seed)

    @property
    def is_np_flattenable(self) -> bool:
        return all(space.is_np_flattenable for space in self.spaces.values())

    def seed(self, seed: int | dict | None = None) -> dict:
        """None: every subspace from the OS; an int: this space's generator
        draws one seed per subspace (in key order); a dict: one seed per
        key. Returns the subspaces' seeds by key."""
        if seed is None:
            return {key: space.seed(None) for key, space in self.spaces.items()}
        if isinstance(seed, int) and not isinstance(seed, bool):
            super().seed(seed)
            seeds = self.np_random.integers(np.iinfo(np.int32).max, size=len(self.spaces))
            return {key: space.seed(int(s)) for (key, space), s in zip(self.spaces.items(), seeds)}
        if isinstance(seed, dict):
            if seed.keys() != self.spaces.keys():
                raise ValueError(f"The seed keys: {seed.keys()} are not identical to space keys: "
                                 f"{self.spaces.keys()}")
            return {key: self.spaces[key].seed(seed[key]) for key in seed}
        raise TypeError(f"Expected seed type: dict, int or None, actual type: {type(seed)}")

    def sample(self, mask: dict | None = None, probability: dict | None = None) -> dict:
        if mask is not None and probability is not None:
            raise ValueError("Only one of `mask` or `probability` can be provided")
        if mask is not None:
            if not isinstance(mask, dict) or mask.keys() != self.spaces.keys():
                raise AssertionError("Expected sample mask to be a dict with the space's keys")
            return {k: space.sample(mask=mask[k]) for k, space in self.spaces.items()}
        if probability is not None:
            if not isinstance(probability, dict) or probability.keys() != self.spaces.keys():
                raise AssertionError("Expected sample probability to be a dict with the space's "
                                     "keys")
            return {k: space.sample(probability=probability[k]) for k, space in self.spaces.items()}
        return {k: space.sample() for k, space in self.spaces.items()}

    def contains(self, x: Any) -> bool:
        return (isinstance(x, dict) and x.keys() == self.spaces.keys()
                and all(x[key] in self.spaces[key] for key in self.spaces))

    def __getitem__(self, key: str) -> Space:
        return self.spaces[key]

    def __setitem__(self, key: str, value: Space) -> None:
        if not isinstance(value, Space):
            raise AssertionError(f"Trying to set {key} to Dict space with value that is not a "
                                 f"space, actual type: {type(value)}")
        self.spaces[key] = value

    def __iter__(self) -> Iterator[str]:
        yield from self.spaces

    def __len__(self) -> int:
        return len(self.spaces)

    def __repr__(self) -> str:
        return "Dict(" + ", ".join(f"{k!r}: {s}" for k, s in self.spaces.items()) + ")"

    def __eq__(self, other: Any) -> bool:
        return isinstance(other, Dict) and self.spaces == other.spaces

    def to_jsonable(self, sample_n: Sequence[dict]) -> dict:
        return {key: space.to_jsonable([s[key] for s in sample_n])
                for key, space in self.spaces.items()}

    def from_jsonable(self, sample_n: dict) -> list:
        columns = {key: space.from_jsonable(sample_n[key]) for key, space in self.spaces.items()}
        count = len(next(iter(columns.values()))) if columns else 0
        return [{key: column[i] for key, column in columns.items()} for i in range(count)]


def batch_space(space: Space, n: int = 1) -> Space:
    """The space of n stacked samples of `space` (gymnasium.vector.utils.
    batch_space): bounds tiled along a new axis 0; the batch's generator is
    a copy of the single space's."""
    if isinstance(space, Box):
        repeats = (n,) + (1,) * space.low.ndim
        return Box(low=np.tile(space.low, repeats), high=np.tile(space.high, repeats),
                   dtype=space.dtype, seed=copy.deepcopy(space.np_random))
    if isinstance(space, Dict):
        return Dict({key: batch_space(s, n) for key, s in space.items()},
                    seed=copy.deepcopy(space.np_random))
    raise TypeError(f"batch_space: cannot batch {type(space).__name__}")


# ---- registration ----------------------------------------------------------

_ID = re.compile(r"^(?:(?P<namespace>[\w:.-]+)/)?(?P<name>[\w:.-]+?)(?:-v(?P<version>\d+))?$")


def _load(entry_point: str) -> Any:
    module, attribute = entry_point.split(":")
    return getattr(importlib.import_module(module), attribute)


class EnvSpec:
    """gymnasium.envs.registration.EnvSpec: how to make an environment (id,
    entry point, keyword arguments); make(**kwargs) makes one."""

    def __init__(self, id: str, entry_point: Any = None, reward_threshold: float | None = None,
                 nondeterministic: bool = False, max_episode_steps: int | None = None,
                 order_enforce: bool = True, disable_env_checker: bool = False,
                 kwargs: dict | None = None, additional_wrappers: tuple = (),
                 vector_entry_point: Any = None):
        self.id = id
        self.entry_point = entry_point
        self.reward_threshold = reward_threshold
        self.nondeterministic = nondeterministic
        self.max_episode_steps = max_episode_steps
        self.order_enforce = order_enforce
        self.disable_env_checker = disable_env_checker
        self.kwargs = dict(kwargs or {})
        self.additional_wrappers = tuple(additional_wrappers)
        self.vector_entry_point = vector_entry_point
        match = _ID.fullmatch(id)
        if match is None:
            raise Error(f"Malformed environment ID: {id}")
        self.namespace = match["namespace"]
        self.name = match["name"]
        self.version = None if match["version"] is None else int(match["version"])

    def make(self, **kwargs: Any) -> Any:
        creator = _load(self.entry_point) if isinstance(self.entry_point, str) else self.entry_point
        return creator(**{**self.kwargs, **kwargs})

    def __eq__(self, other: Any) -> bool:
        return isinstance(other, EnvSpec) and vars(self) == vars(other)

    def __repr__(self) -> str:
        return (f"EnvSpec(id={self.id!r}, entry_point={self.entry_point!r}, "
                f"max_episode_steps={self.max_episode_steps}, kwargs={self.kwargs!r})")


# ---- environments ----------------------------------------------------------


class Env:
    """gymnasium.Env's protocol: spaces, metadata, render_mode, spec, and a
    generator (np_random) that reset(seed=...) seeds."""

    metadata: dict = {"render_modes": []}
    render_mode: str | None = None
    spec: EnvSpec | None = None
    _np_random: np.random.Generator | None = None
    _np_random_seed: int | None = None

    def step(self, action: Any) -> tuple:
        raise NotImplementedError

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> Any:
        if seed is not None:
            self._np_random, self._np_random_seed = np_random(seed)

    def render(self) -> Any:
        raise NotImplementedError

    def close(self) -> None:
        pass

    @property
    def unwrapped(self) -> "Env":
        return self

    @property
    def np_random_seed(self) -> int:
        if self._np_random_seed is None:
            self._np_random, self._np_random_seed = np_random()
        return self._np_random_seed

    @property
    def np_random(self) -> np.random.Generator:
        if self._np_random is None:
            self._np_random, self._np_random_seed = np_random()
        return self._np_random

    @np_random.setter
    def np_random(self, value: np.random.Generator) -> None:
        self._np_random = value
        self._np_random_seed = -1

    def has_wrapper_attr(self, name: str) -> bool:
        return hasattr(self, name)

    def get_wrapper_attr(self, name: str) -> Any:
        return getattr(self, name)

    def set_wrapper_attr(self, name: str, value: Any, *, force: bool = True) -> bool:
        if force or hasattr(self, name):
            setattr(self, name, value)
            return True
        return False

    def __str__(self) -> str:
        if self.spec is None:
            return f"<{type(self).__name__} instance>"
        return f"<{type(self).__name__}<{self.spec.id}>>"

    def __enter__(self) -> "Env":
        return self

    def __exit__(self, *args: Any) -> bool:
        self.close()
        return False


class AutoresetMode(enum.Enum):
    """gymnasium.vector.AutoresetMode: when a vector environment resets an
    environment whose episode ended."""

    NEXT_STEP = "NextStep"
    SAME_STEP = "SameStep"
    DISABLED = "Disabled"


class VectorEnv:
    """gymnasium.vector.VectorEnv's protocol: num_envs, the single and
    batched spaces, metadata, spec, render_mode, closed, np_random; close()
    runs close_extras() once."""

    metadata: dict = {}
    spec: EnvSpec | None = None
    render_mode: str | None = None
    closed: bool = False
    num_envs: int
    _np_random: np.random.Generator | None = None
    _np_random_seed: int | None = None

    def reset(self, *, seed: Any = None, options: dict | None = None) -> Any:
        if seed is not None:
            self._np_random, self._np_random_seed = np_random(seed)

    def step(self, actions: Any) -> tuple:
        raise NotImplementedError

    def render(self) -> Any:
        raise NotImplementedError(f"{self} render function is not implemented.")

    def close(self, **kwargs: Any) -> None:
        if self.closed:
            return
        self.close_extras(**kwargs)
        self.closed = True

    def close_extras(self, **kwargs: Any) -> None:
        pass

    @property
    def unwrapped(self) -> "VectorEnv":
        return self

    def __del__(self) -> None:
        if not getattr(self, "closed", True):
            self.close()

    def __repr__(self) -> str:
        if self.spec is None:
            return f"{type(self).__name__}(num_envs={self.num_envs})"
        return f"{type(self).__name__}({self.spec.id}, num_envs={self.num_envs})"


def add_info(num_envs: int, infos: dict, info: Mapping[str, Any], index: int) -> dict:
    """Adds environment `index`'s info to the vector info `infos` as
    gymnasium's vector environments do: per key an array over the
    environments (numbers: zeros of the value's type; arrays: zeros of
    their shape and dtype; anything else: an object array of None), nested
    dicts alike, and ``_key``, a bool array of the environments that have
    the key."""
    for key, value in info.items():
        if isinstance(value, dict):
            array = add_info(num_envs, infos.get(key, {}), value, index)
        else:
            array = infos.get(key)
            if array is None:
                if type(value) in (int, float, bool) or issubclass(type(value), np.number):
                    array = np.zeros(num_envs, dtype=type(value))
                elif isinstance(value, np.ndarray):
                    array = np.zeros((num_envs, *value.shape), dtype=value.dtype)
                else:
                    array = np.full(num_envs, None, dtype=object)
            array[index] = value
        mask = infos.get("_" + key)
        if mask is None:
            mask = np.zeros(num_envs, dtype=np.bool_)
        mask[index] = True
        infos[key], infos["_" + key] = array, mask
    return infos
