"""The on-disk cache of radio maps.

A map is stored under ``cache_dir()/radiomaps/<key>.npz`` where the key hashes the scenario
([`rainuav.radio.scene.scenario.Scenario.digest()`][rainuav.radio.scene.scenario.Scenario.digest])
together with the fingerprint of the code that built it
([`engine_fingerprint()`][rainuav.radio.outputs.cache.engine_fingerprint]): a map built by other
engine code is never reused. Clear the cache with ``python -m rainuav.radiomap --clear-cache`` (or
delete the folder)."""

from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

from rainuav import _core

__all__ = ["ENGINE_VERSION", "cache_dir", "clear_cache", "engine_fingerprint", "map_path"]

ENGINE_VERSION = 8
"""Bumped by hand with every change meant to change maps (a reminder in the changelog); the
fingerprint also hashes the engine's code, so a forgotten bump still misses the cache."""

_ENGINE_MODULES = (
    "rainuav._sampling",
    "rainuav.antenna",
    "rainuav.medium",
    "rainuav.pwe",
    "rainuav.radio.scene.cell",
    "rainuav.radio.engines.grid",
    "rainuav.radio.engines.hybrid",
    "rainuav.radio.outputs.mapdata",
    "rainuav.radio.outputs.maps",
    "rainuav.radio.engines.pe_engine",
    "rainuav.radio.engines.ray_engine",
    "rainuav.radio.scene.scenario",
    "rainuav.radio.outputs.sinr",
    "rainuav.radio.scene.stochastic",
    "rainuav.radio.outputs.timemap",
    "rainuav.radio.scene.weather",
)


def cache_dir() -> Path:
    """Where maps are cached.

    Returns:
        `$RAINUAV_CACHE_DIR`, else `$XDG_CACHE_HOME/rainuav`, else `~/.cache/rainuav`; the maps live
        in its `radiomaps/` folder.
    """
    env = os.environ.get("RAINUAV_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "rainuav"


@functools.cache
def engine_fingerprint() -> str:
    """A hash of what produces a map:
    [`ENGINE_VERSION`][rainuav.radio.outputs.cache.ENGINE_VERSION], the source of the Python engine
    modules and the compiled core (``rainuav._core``, which holds the PE march and the rain
    medium)."""
    import importlib

    h = hashlib.sha256(f"engine {ENGINE_VERSION}".encode())
    for name in _ENGINE_MODULES:
        mod = importlib.import_module(name)
        h.update(name.encode())
        h.update(Path(mod.__file__ or "").read_bytes())
    h.update(Path(_core.__file__ or "").read_bytes())
    return h.hexdigest()[:16]


def map_path(scenario_digest: str) -> Path:
    """The cache file of the map of a scenario with this digest, built by this engine.

    Args:
        scenario_digest: The scenario's digest.

    Returns:
        The path (under [`cache_dir()`][rainuav.radio.outputs.cache.cache_dir]).
    """
    key = hashlib.sha256(f"{scenario_digest}|{engine_fingerprint()}".encode()).hexdigest()[:32]
    return cache_dir() / "radiomaps" / f"{key}.npz"


def clear_cache() -> int:
    """Deletes every cached map, and any temporary file left over.

    Returns:
        How many files were deleted.
    """
    folder = cache_dir() / "radiomaps"
    n = 0
    if folder.is_dir():
        for f in folder.iterdir():
            if f.is_file() and (f.suffix == ".npz" or f.name.endswith(".tmp")):
                f.unlink(missing_ok=True)
                n += 1
    return n
