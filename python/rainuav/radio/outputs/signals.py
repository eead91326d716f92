"""The radio maps as one [`Signal`][rainuav.signals.Signal] (axes ``world, time, level, north,
east``): [`signal_of()`][rainuav.radio.outputs.signals.signal_of] for a built map, maps in time or
the maps of every level, and [`load_signal()`][rainuav.radio.outputs.signals.load_signal] for a
file of any of them: the signal file (``signal.npz``) and the three files the maps are saved in
(``radiomap.npz``, ``radiomap_series.npz``, ``radiolevels.npz``), which keep loading as they
are."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.radio.outputs.levelmaps import LevelStack, RadioLevels, RadioLevelSeries
from rainuav.radio.outputs.mapdata import RadioMap
from rainuav.radio.outputs.timemap import RadioMapSeries
from rainuav.radio.scene.terrain import map_mask
from rainuav.signals import Signal, array_names, read_arrays

__all__ = ["load_signal", "signal_of"]

SIGNALS = ("sinr", "sir")


def signal_of(source: Any, signal: str = "sinr", *, scenario_toml: bool = True) -> Signal:
    """A built map, maps in time or maps of every level as one signal, bit for bit.

    The maps of every level ([`RadioLevels`][rainuav.radio.outputs.levelmaps.RadioLevels],
    [`RadioLevelSeries`][rainuav.radio.outputs.levelmaps.RadioLevelSeries],
    [`LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack]) hold SINR alone. The signal carries
    the source's serving cells and not-flyable pixels.

    Args:
        source: A [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap], a
            [`RadioMapSeries`][rainuav.radio.outputs.timemap.RadioMapSeries] or the maps of every
            level.
        signal: "sinr" or "sir".
        scenario_toml: Carry the source's scenario as TOML (for a file; a radar weather's TOML takes
            seconds to write: False leaves it out).

    Returns:
        The [`Signal`][rainuav.signals.Signal].

    Raises:
        InvalidInputError: Another source, an unknown signal, or SIR from the maps of every level.
    """

    def toml(scn: Any) -> str:
        return scn.to_toml_string() if scenario_toml and scn is not None else ""

    if signal not in SIGNALS:
        raise InvalidInputError(f"signal must be one of {SIGNALS} (got {signal!r})")
    name = f"{signal}_db"
    if isinstance(source, RadioMap):
        nf = None if source.not_flyable is None else source.not_flyable[None]
        return Signal.from_axes(getattr(source, name), ("north", "east"), source.extent_m,
                                altitudes_m=[source.altitude_m], serving_cell=source.serving_cell,
                                name=name, not_flyable=nf,
                                scenario_toml=toml(source.scenario))  # fmt: skip
    if isinstance(source, RadioMapSeries):
        a = source.scenario.area
        extent = (a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m)
        mask = map_mask(source.scenario)  # the ground's, the same at every instant
        nf = None if mask is None else mask[None]
        return Signal.from_axes(getattr(source, name), ("time", "north", "east"), extent,
                                t_s=source.t_s, altitudes_m=[source.scenario.area.altitude_m],
                                serving_cell=source.serving_cell, name=name, not_flyable=nf,
                                scenario_toml=toml(source.scenario))  # fmt: skip
    if isinstance(source, RadioLevels | RadioLevelSeries | LevelStack):
        if signal != "sinr":
            raise InvalidInputError("the maps of every level hold SINR alone (signal='sinr')")
        if isinstance(source, RadioLevels):  # the maps' own arrays (a LevelStack's are narrowed)
            serving = np.stack([m.serving_cell for m in source.maps])
            scn = source.maps[0].scenario
        else:
            serving, scn = source.serving_cell, getattr(source, "scenario", None)
        t = getattr(source, "t_s", None)
        dims = ("level", "north", "east") if t is None else ("time", "level", "north", "east")
        return Signal.from_axes(source.sinr_db, dims, source.extent,
                                t_s=(0.0,) if t is None else t, altitudes_m=source.altitudes_m,
                                serving_cell=serving, name=name,
                                not_flyable=np.asarray(source.not_flyable, bool),
                                scenario_toml=toml(scn))  # fmt: skip
    raise InvalidInputError(
        "source must be a RadioMap, RadioMapSeries, RadioLevels, RadioLevelSeries or LevelStack "
        f"(got {type(source).__name__})"
    )


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
