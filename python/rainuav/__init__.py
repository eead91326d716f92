"""rainuav: flight paths for cellular-connected drones in rain.

Layers, bottom up (each imports only the ones below it):

- [`rainuav.medium`][rainuav.medium]: what rain does to a radio wave (effective permittivity,
  specific attenuation, ITU-R P.838).
- [`rainuav.antenna`][rainuav.antenna]: antenna gain patterns (3GPP TR 38.901 element and arrays,
  the paper's Gaussian beam, tables).
- [`rainuav.pwe`][rainuav.pwe]: the 3-D split-step parabolic-equation march.
- [`rainuav.radio`][rainuav.radio]: scenarios, presets and radio maps (received power per cell,
  serving cell, SIR, SINR).
- [`rainuav.nav`][rainuav.nav]: the navigation task on any map or maps in time, the Gymnasium
  environment, the exact planner (in space-time), the baselines and the shield (no torch).
- [`rainuav.world`][rainuav.world]: a world, a signal in time joined to a task, built from one spec
  for every entry point (``gym.make("rainuav/UAVNav-v0")``, train, evaluate, studies).
- [`rainuav.rl`][rainuav.rl]: the dueling double DQN and its training loop (torch), given a world.

Entry points: ``python -m rainuav.train``, ``rainuav.evaluate``, ``rainuav.radiomap``,
``rainuav.validate``, ``rainuav.study``. Physics conventions: the
[physics reference][0-conventions] (time dependence ``exp(+j w t)``, lossy media have
``Im eps <= 0``)."""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
from typing import Any

from rainuav import medium
from rainuav._core import __version__
from rainuav.errors import InvalidInputError, RainuavError


def _register() -> None:
    """Registers ``rainuav/UAVNav-v0`` and ``rainuav/UAVLevels-v0`` with Gymnasium (once)."""
    import gymnasium as gym

    if "rainuav/UAVNav-v0" not in gym.registry:
        gym.register(
            id="rainuav/UAVNav-v0",
            entry_point="rainuav.envs:make_nav_env",
            vector_entry_point="rainuav.envs:make_nav_vector_env",
        )
    if "rainuav/UAVLevels-v0" not in gym.registry:
        gym.register(id="rainuav/UAVLevels-v0", entry_point="rainuav.envs:make_levels_env")


class _RegisterWithGymnasium(importlib.abc.MetaPathFinder):
    """Registers the environment right after Gymnasium is first imported, so that importing
    rainuav (or ``rainuav.medium``) does not import Gymnasium, yet ``gym.make`` finds the
    environment whichever of the two was imported first."""

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> Any:
        if name != "gymnasium":
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None:
            return spec
        run = spec.loader.exec_module

        def exec_module(module: Any) -> None:
            run(module)
            _register()

        spec.loader.exec_module = exec_module  # type: ignore[method-assign]
        return spec


if "gymnasium" in sys.modules:
    _register()
elif not any(isinstance(f, _RegisterWithGymnasium) for f in sys.meta_path):
    sys.meta_path.insert(0, _RegisterWithGymnasium())

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
    "world",
]

_LAZY = ("antenna", "nav", "pwe", "radio", "rl", "world")


def __getattr__(name: str) -> Any:
    """``rainuav.radio`` and the other layers load on first use (``rl`` imports torch)."""
    if name in _LAZY:
        return importlib.import_module(f"rainuav.{name}")
    raise AttributeError(f"module 'rainuav' has no attribute {name!r}")
