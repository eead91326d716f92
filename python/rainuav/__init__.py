"""rainuav: flight paths for cellular-connected drones in rain.

Layers, bottom up: :mod:`rainuav.medium` (what rain does to a radio wave) and, in later
releases, propagation, radio maps and trajectory design. Physics conventions:
``shared/PHYSICS.md`` (time dependence ``exp(+j w t)``, lossy media have ``Im eps <= 0``).
"""

from __future__ import annotations

import gymnasium as _gym

from rainuav import medium
from rainuav._core import __version__
from rainuav.errors import InvalidInputError, RainuavError

if "rainuav/UAVNav-v0" not in _gym.registry:
    _gym.register(id="rainuav/UAVNav-v0", entry_point="rainuav.env:UAVNavEnv")

__all__ = ["InvalidInputError", "RainuavError", "__version__", "medium"]
