"""gymnasium's classes where gymnasium 1.x is importable, manibench._standin's
otherwise: the one place the package decides (docs/python.md)."""

from __future__ import annotations

from . import _standin

try:  # pragma: no cover - depends on the machine
    import gymnasium
    if int(gymnasium.__version__.split(".")[0]) < 1:
        gymnasium = None  # 0.x: another vector API; the stand-ins keep the protocol
except ImportError:  # pragma: no cover
    gymnasium = None

if gymnasium is not None:  # pragma: no cover
    import gymnasium.envs.registration
    import gymnasium.error
    import gymnasium.spaces
    import gymnasium.vector
    import gymnasium.vector.utils

    Env = gymnasium.Env
    Space = gymnasium.spaces.Space
    Box = gymnasium.spaces.Box
    Dict = gymnasium.spaces.Dict
    EnvSpec = gymnasium.envs.registration.EnvSpec
    VectorEnv = gymnasium.vector.VectorEnv
    # AutoresetMode came with gymnasium 1.1; 1.0 always resets on the next step.
    AutoresetMode = getattr(gymnasium.vector, "AutoresetMode", _standin.AutoresetMode)
    batch_space = gymnasium.vector.utils.batch_space
    Error = gymnasium.error.Error
else:
    Env = _standin.Env
    Space = _standin.Space
    Box = _standin.Box
    Dict = _standin.Dict
    EnvSpec = _standin.EnvSpec
    VectorEnv = _standin.VectorEnv
    AutoresetMode = _standin.AutoresetMode
    batch_space = _standin.batch_space
    Error = _standin.Error

np_random = _standin.np_random  # gymnasium.utils.seeding.np_random's numbers
add_info = _standin.add_info    # VectorEnv._add_info's stacking, for both


def is_available() -> bool:
    """Whether gymnasium (1.x) is importable and in use."""
    return gymnasium is not None
