"""The spaces follow gymnasium 1.x's documented protocol with and without
gymnasium: the stand-ins (manibench._standin, used where gymnasium is not
importable) are checked against the documented behaviour always, and
against gymnasium's own classes where it is installed."""
import collections
import copy

import numpy as np
import pytest

import manibench
from manibench import _gym, _standin
from manibench._standin import Box, Dict

try:
    import gymnasium
except ImportError:
    gymnasium = None


def test_np_random_is_pcg64_over_the_seed_sequence():
    rng, seed = _standin.np_random(7)
    assert seed == 7
    expected = np.random.Generator(np.random.PCG64(np.random.SeedSequence(7)))
    assert rng.bit_generator.state == expected.bit_generator.state
    rng, seed = _standin.np_random()
    assert isinstance(seed, int) and seed > 0  # the OS's entropy, returned
    again, _ = _standin.np_random(seed)
    assert again.bit_generator.state == rng.bit_generator.state
    for bad in (-1, 1.5, "3", np.int64(3)):
        with pytest.raises(_standin.Error):
            _standin.np_random(bad)


def test_box_attributes_and_bounds():
    box = Box(-1.0, 1.0, shape=(3,))
    assert box.shape == (3,) and box.dtype == np.float32  # gymnasium's default dtype
    assert box.low.dtype == box.high.dtype == np.float32
    assert np.all(box.low == -1) and np.all(box.high == 1)
    assert box.is_bounded() and box.is_bounded("below") and box.is_np_flattenable
    free = Box(-np.inf, np.inf, shape=(2,), dtype=np.float64)
    assert not free.is_bounded("below") and not free.is_bounded("above")
    half = Box(low=np.array([0.0, -np.inf]), high=np.array([np.inf, 2.0]), dtype=np.float64)
    assert list(half.bounded_below) == [True, False] and list(half.bounded_above) == [False, True]
    assert Box(0, 1, shape=(2,)).shape == (2,)
    assert Box(low=np.zeros((2, 3)), high=np.ones((2, 3))).shape == (2, 3)
    assert repr(Box(-1.0, 1.0, (3,), np.float32)) == "Box(-1.0, 1.0, (3,), float32)"
    with pytest.raises(ValueError):
        Box(1.0, -1.0, shape=(2,))
    with pytest.raises(ValueError):
        Box(0, np.inf, shape=(2,), dtype=np.uint8)
    with pytest.raises(ValueError):
        Box(0, 1, shape=(2,), dtype=np.complex64)
    with pytest.raises(ValueError):
        Box(0, 1, shape=(2,), dtype=None)
    big = Box(-np.inf, np.inf, shape=(1,), dtype=np.int32)  # integer infinities: the dtype's limits
    assert big.low[0] == np.iinfo(np.int32).min and big.high[0] == np.iinfo(np.int32).max


def test_box_seed_returns_the_seed_used():
    box = Box(-1.0, 1.0, shape=(4,))
    assert box.seed(5) == [5]
    first = box.sample()
    assert box.seed(5) == [5]
    assert np.array_equal(box.sample(), first)
    used = box.seed()
    assert isinstance(used, list) and len(used) == 1 and isinstance(used[0], int)
    box.seed(used[0])
    again = box.sample()
    box.seed(used[0])
    assert np.array_equal(box.sample(), again)
    seeded = Box(-1.0, 1.0, shape=(4,), seed=5)
    assert np.array_equal(seeded.sample(), first)


def rng(seed):
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed)))


def test_box_sample_draws_the_documented_distributions():
    # Bounded: uniform on [low, high]; unbounded: normal; [a, inf): a +
    # exponential; (-inf, b]: b - exponential; drawn in that order:
    # unbounded, below-bounded, above-bounded, bounded.
    box = Box(-1.0, 1.0, shape=(5,), seed=3)
    sample = box.sample()
    assert sample.dtype == np.float32 and sample.shape == (5,)
    assert np.array_equal(sample, rng(3).uniform(-1.0, 1.0, size=5).astype(np.float32))
    assert sample in box
    mixed = Box(low=np.array([-np.inf, 0.0, -np.inf, -2.0]), high=np.array([np.inf, np.inf, 1.0, 2.0]),
                dtype=np.float64, seed=4)
    r = rng(4)
    expected = np.empty(4)
    expected[0] = r.normal(size=1)[0]
    expected[1] = r.exponential(size=1)[0] + 0.0
    expected[2] = -r.exponential(size=1)[0] + 1.0
    expected[3] = r.uniform(-2.0, 2.0, size=1)[0]
    assert np.array_equal(mixed.sample(), expected)
    # Integers: the floor of a uniform draw over [low, high + 1).
    image = Box(0, 255, shape=(4, 5, 3), dtype=np.uint8, seed=6)
    pixels = image.sample()
    assert pixels.dtype == np.uint8 and pixels in image
    assert np.array_equal(pixels, np.floor(rng(6).uniform(0, 256, size=(4, 5, 3))).astype(np.uint8))
    flags = Box(0, 1, shape=(50,), dtype=np.bool_, seed=8).sample()
    assert flags.dtype == np.bool_ and 0 < flags.sum() < 50
    with pytest.raises(_standin.Error, match="mask"):
        box.sample(mask=np.zeros(5, np.int8))
    with pytest.raises(_standin.Error, match="probability"):
        box.sample(probability=np.zeros(5))
    assert box.sample(mask=None).shape == (5,)


def test_box_contains_and_equality():
    box = Box(-1.0, 1.0, shape=(2,))
    assert np.zeros(2, np.float32) in box
    assert box.contains([0.5, -0.5])  # a list is cast
    assert not box.contains(np.zeros(2, np.float64))  # float64 does not cast safely to float32
    assert not box.contains(np.zeros(3, np.float32))
    assert not box.contains(np.full(2, 2.0, np.float32))
    assert box == Box(-1.0, 1.0, shape=(2,))
    assert box != Box(-1.0, 1.0, shape=(2,), dtype=np.float64)
    assert box != Box(-1.0, 2.0, shape=(2,))
    assert box != Box(-1.0, 1.0, shape=(3,))


def test_dict_is_a_sorted_mapping_of_spaces():
    space = Dict({"rgb": Box(0, 255, (2, 2, 3), np.uint8), "agent": Box(-1.0, 1.0, (4,))})
    assert list(space) == ["agent", "rgb"]  # sorted, as gymnasium sorts a plain dict
    assert list(space.keys()) == ["agent", "rgb"]
    assert len(space) == 2 and "rgb" in space.spaces
    assert dict(space)["rgb"] is space["rgb"]
    assert [k for k, _ in space.items()] == ["agent", "rgb"]
    assert space.shape is None and space.dtype is None
    ordered = Dict(collections.OrderedDict([("z", Box(0, 1, (1,))), ("a", Box(0, 1, (1,)))]))
    assert list(ordered) == ["z", "a"]
    assert list(Dict([("z", Box(0, 1, (1,))), ("a", Box(0, 1, (1,)))])) == ["z", "a"]
    assert list(Dict(b=Box(0, 1, (1,)), a=Box(0, 1, (1,)))) == ["b", "a"]
    same = Dict({"agent": Box(-1.0, 1.0, (4,)), "rgb": Box(0, 255, (2, 2, 3), np.uint8)})
    assert space == same
    assert space != Dict({"agent": Box(-1.0, 1.0, (4,))})
    assert repr(space).startswith("Dict('agent': Box(")
    with pytest.raises(AssertionError):
        Dict({"a": "not a space"})


def test_dict_seed_sample_and_contains():
    space = Dict({"b": Box(-1.0, 1.0, (3,)), "a": Box(0, 255, (2,), np.uint8)})
    seeds = space.seed(9)
    # An int seeds the Dict's own generator, which draws one int32 seed per key.
    expected = rng(9).integers(np.iinfo(np.int32).max, size=2)
    assert seeds == {"a": [int(expected[0])], "b": [int(expected[1])]}
    first = space.sample()
    assert list(first) == ["a", "b"] and first in space
    space.seed(9)
    second = space.sample(mask=None)
    assert all(np.array_equal(first[k], second[k]) for k in first)
    assert space.seed({"a": 1, "b": 2}) == {"a": [1], "b": [2]}
    unseeded = space.seed()
    assert set(unseeded) == {"a", "b"} and all(isinstance(v[0], int) for v in unseeded.values())
    with pytest.raises(ValueError):
        space.seed({"a": 1})
    assert not space.contains({"a": first["a"]})
    assert not space.contains([first["a"], first["b"]])
    assert not space.contains({"a": first["a"], "b": np.full(3, 5.0, np.float32)})


def test_batch_space_tiles_the_bounds():
    box = Box(low=np.array([-1.0, 0.0]), high=np.array([1.0, 2.0]), dtype=np.float64)
    batch = _standin.batch_space(box, 3)
    assert batch.shape == (3, 2) and batch.dtype == np.float64
    assert np.array_equal(batch.low, np.tile(box.low, (3, 1)))
    batch_dict = _standin.batch_space(Dict({"x": box, "m": Box(0, 1, (4,), np.bool_)}), 2)
    assert list(batch_dict) == ["m", "x"]
    assert batch_dict["x"].shape == (2, 2) and batch_dict["m"].dtype == np.bool_


def test_spaces_of_an_environment_are_the_active_classes():
    with manibench.make("Reach-v0", obs_mode="pointcloud") as env:
        assert isinstance(env.observation_space, _gym.Dict)
        assert isinstance(env.action_space, _gym.Box)
        assert list(env.observation_space) == sorted(env.observation_space)
        assert env.action_space.seed(1) == [1]


# ---- against gymnasium itself, where it is installed ------------------------

needs_gymnasium = pytest.mark.skipif(gymnasium is None, reason="gymnasium is not installed")


@needs_gymnasium
@pytest.mark.parametrize("args", [
    dict(low=-1.0, high=1.0, shape=(7,), dtype=np.float32),
    dict(low=-np.inf, high=np.inf, shape=(3, 2), dtype=np.float64),
    dict(low=np.array([0.0, -np.inf, -3.0]), high=np.array([np.inf, 4.0, 3.0]), dtype=np.float64),
    dict(low=0, high=255, shape=(4, 4, 3), dtype=np.uint8),
    dict(low=0, high=1, shape=(9,), dtype=np.bool_),
])
def test_standin_box_samples_what_gymnasium_samples(args):
    ours = Box(**copy.deepcopy(args))
    theirs = gymnasium.spaces.Box(**copy.deepcopy(args))
    assert ours.seed(11) == theirs.seed(11)
    for _ in range(3):
        a, b = ours.sample(), theirs.sample()
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes()
    assert repr(ours) == repr(theirs)
    assert ours.contains(a) and theirs.contains(a)


@needs_gymnasium
def test_standin_dict_seeds_and_samples_as_gymnasium():
    def make(module):
        return module.Dict({"b": module.Box(-1.0, 1.0, (3,)), "a": module.Box(0, 9, (2,), np.int64)})
    ours, theirs = make(_standin), make(gymnasium.spaces)
    assert list(ours) == list(theirs)
    assert ours.seed(5) == theirs.seed(5)
    a, b = ours.sample(), theirs.sample()
    assert a.keys() == b.keys() and all(a[k].tobytes() == b[k].tobytes() for k in a)
    batched_ours = _standin.batch_space(ours, 3)
    batched_theirs = gymnasium.vector.utils.batch_space(theirs, 3)
    assert all(np.array_equal(batched_ours[k].low, batched_theirs[k].low) for k in ours)
