"""rainuav: flight paths for cellular-connected drones in rain.

Layers, bottom up (each imports only the ones below it):

- :mod:`rainuav.medium`: what rain does to a radio wave (effective permittivity, specific
  attenuation, ITU-R P.838).
- :mod:`rainuav.antenna`: antenna gain patterns (3GPP TR 38.901 element and arrays, the
  paper's Gaussian beam, tables).
- :mod:`rainuav.pwe`: the 3-D split-step parabolic-equation march.
- :mod:`rainuav.radio`: scenarios, presets and radio maps (received power per cell, serving
  cell, SIR, SINR).
- :mod:`rainuav.nav`: the navigation task on any map, the Gymnasium environment
  ``rainuav/UAVNav-v0``, the exact planner and the shield (no torch).
- :mod:`rainuav.rl`: the dueling double DQN and its training loop (torch).

Entry points: ``python -m rainuav.train``, ``rainuav.evaluate``, ``rainuav.radiomap``,
``rainuav.validate``. Physics conventions: ``shared/PHYSICS.md`` (time dependence
``exp(+j w t)``, lossy media have ``Im eps <= 0``).
"""

from __future__ import annotations

import importlib
from typing import Any

import gymnasium as _gym

from rainuav import medium
from rainuav._core import __version__
from rainuav.errors import InvalidInputError, RainuavError

if "rainuav/UAVNav-v0" not in _gym.registry:
    _gym.register(
        id="rainuav/UAVNav-v0",
        entry_point="rainuav.envs:make_nav_env",
        vector_entry_point="rainuav.envs:make_nav_vector_env",
    )

__all__ = [
    "InvalidInputError",
    "RainuavError",
    "__version__",
    "antenna",
    "medium",
    "nav",
    "pwe",
    "radio",
    "rl",
]

_LAZY = ("antenna", "nav", "pwe", "radio", "rl")


def __getattr__(name: str) -> Any:
    """``rainuav.radio`` and the other layers load on first use (``rl`` imports torch)."""
    if name in _LAZY:
        return importlib.import_module(f"rainuav.{name}")
    raise AttributeError(f"module 'rainuav' has no attribute {name!r}")
