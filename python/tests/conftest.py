# The tests import the package from the build tree (ctest sets PYTHONPATH to
# build/python) and load the build tree's real plugins.
import numpy as np
import pytest


def assert_same_obs(a, b):
    """Bit-identical observations (arrays or dicts of arrays)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            assert_same_obs(a[key], b[key])
        return
    assert a.dtype == b.dtype and a.shape == b.shape
    assert a.tobytes() == b.tobytes()


def assert_same_info(a, b):
    """Equal vector info dicts: the same keys, arrays of the same dtype,
    shape and values (byte for byte; object arrays element by element)."""
    assert a.keys() == b.keys()
    for key in a:
        if isinstance(a[key], dict):
            assert_same_info(a[key], b[key])
            continue
        assert a[key].dtype == b[key].dtype and a[key].shape == b[key].shape, key
        if a[key].dtype == object:
            assert list(a[key]) == list(b[key]), key
        else:
            assert a[key].tobytes() == b[key].tobytes(), key


@pytest.fixture
def actions():
    """A fixed sequence of Reach-v0 actions (2 joints), in [-1, 1]."""
    return np.random.default_rng(1234).uniform(-1, 1, size=(40, 2))
