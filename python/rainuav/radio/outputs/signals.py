"""The radio maps as one [`Signal`][rainuav.signals.Signal] (axes ``world, time, level, north,
east``): [`signal_of()`][rainuav.radio.outputs.signals.signal_of] for a built map, maps in time or
the maps of every level, and [`load_signal()`][rainuav.radio.outputs.signals.load_signal] for a
file of any of them: the signal file (``signal.npz``) and the three files the maps are saved in
(``radiomap.npz``, ``radiomap_series.npz``, ``radiolevels.npz``), which keep loading as they
are."""

from __future__ import annotations

import os
from typing import Any

from rainuav.errors import InvalidInputError
from rainuav.radio.outputs.levelmaps import LevelStack
from rainuav.radio.outputs.mapdata import RadioMap
from rainuav.radio.outputs.timemap import RadioMapSeries
from rainuav.signals import Signal, array_names, read_arrays, signal_name

__all__ = ["load_signal", "signal_of"]


def signal_of(source: Any, signal: str = "sinr", *, scenario_toml: bool = True) -> Signal:
    """A built map, maps in time, maps of every level or a signal as one signal, bit for bit.

    Each kind says how it is one signal (its `as_signal()`); the maps of every level
    ([`RadioLevels`][rainuav.radio.outputs.levelmaps.RadioLevels],
    [`RadioLevelSeries`][rainuav.radio.outputs.levelmaps.RadioLevelSeries],
    [`LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack]) hold SINR alone. The signal carries
    the source's serving cells and not-flyable pixels.

    Args:
        source: A [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap], a
            [`RadioMapSeries`][rainuav.radio.outputs.timemap.RadioMapSeries], the maps of every
            level or a [`Signal`][rainuav.signals.Signal].
        signal: "sinr" or "sir".
        scenario_toml: Carry the source's scenario as TOML (for a file; a radar weather's TOML takes
            seconds to write: False leaves it out).

    Returns:
        The [`Signal`][rainuav.signals.Signal].

    Raises:
        InvalidInputError: Another source, an unknown signal, or SIR from the maps of every level.
    """
    signal_name(signal)
    as_signal = getattr(source, "as_signal", None)
    if not callable(as_signal):
        raise InvalidInputError(
            "source must be a RadioMap, RadioMapSeries, RadioLevels, RadioLevelSeries, LevelStack "
            f"or Signal (got {type(source).__name__})"
        )
    return as_signal(signal, scenario_toml=scenario_toml)


def load_signal(path: str | os.PathLike[str], signal: str = "sinr") -> Signal:
    """The signal a file holds, whichever of rainuav's map files it is.

    A signal file ([`Signal.save()`][rainuav.signals.Signal.save]), or a map, maps in time or the
    maps of every level as the radio maps save them (read and checked by their own loaders, then
    [`signal_of()`][rainuav.radio.outputs.signals.signal_of]). The kind is told by the arrays'
    names, and the file read once.

    Args:
        path: The file.
        signal: "sinr" or "sir", where the file holds both.

    Returns:
        The [`Signal`][rainuav.signals.Signal].

    Raises:
        InvalidInputError: A file that is none of them, or that its loader refuses (named).
    """
    what = "signal or radio map file"
    keys = array_names(path, what)
    if "meta_json" in keys:
        return Signal.load(path)
    if {"altitudes_m", "sinr_db", "not_flyable"} <= keys:
        return signal_of(LevelStack.load(path), signal)
    if {"t_s", "rss_dbm", "sinr_db"} <= keys:
        return signal_of(RadioMapSeries.load(path), signal)
    if {"rss_dbm", "sinr_db", "altitude_m"} <= keys:
        return signal_of(RadioMap.load(path), signal)
    read_arrays(path, what)  # an array that cannot be read is the better reason
    raise InvalidInputError(
        f"{path}: neither a signal file nor a radio map, maps in time or maps of every level "
        "(rainuav's signal.npz, radiomap.npz, radiomap_series.npz or radiolevels.npz)"
    )
