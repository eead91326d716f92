"""The map where the log was measured: each logged row's power in the prior.

A map is one flight level; a log is wherever the UAV flew.
[`prior_at()`][rainuav.radio.measured.levels.prior_at] reads each cell's power at every logged
point: bilinear in the map's pixels, and linear in height between maps built at levels
``level_step_m`` apart that bracket the point (the map itself where every point lies within half
a step of its altitude). A log spanning more than
[`MAX_LEVEL_MAPS`][rainuav.radio.measured.levels.MAX_LEVEL_MAPS] levels is refused, naming the
step it needs."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from rainuav._sampling import bilinear
from rainuav.errors import InvalidInputError
from rainuav.radio.measured.log import MeasurementLog
from rainuav.radio.outputs.mapdata import RadioMap
from rainuav.radio.scene.scenario import Scenario

__all__ = ["MAX_LEVEL_MAPS", "prior_at"]

MAX_LEVEL_MAPS = 40
"""The most maps [`prior_at()`][rainuav.radio.measured.levels.prior_at] builds at a log's
heights (a 400 m span at the default 10 m step); a log spanning more is refused, naming a coarser
``level_step_m``."""


def _level_coordinate(scn: Scenario, log: MeasurementLog) -> np.ndarray:
    return log.z_m if scn.area.msl else log.alt_m


def prior_at(
    rm: RadioMap,
    log: MeasurementLog,
    level_step_m: float = 10.0,
    build: Any = None,
    progress: bool = False,
) -> np.ndarray:
    """Each logged row's cell power in the prior, dBm (the module's docstring).

    Args:
        rm: The prior map.
        log: The log.
        level_step_m: The height between the maps built at the log's heights, m.
        build: The function that builds a map of a scenario (default
            [`build_radio_map`][rainuav.radio.outputs.maps.build_radio_map], cached).
        progress: A line on standard error per map built.

    Returns:
        (N,) dBm.

    Raises:
        InvalidInputError: A log whose heights need more than
            [`MAX_LEVEL_MAPS`][rainuav.radio.measured.levels.MAX_LEVEL_MAPS] maps.
    """
    scn = rm.scenario
    at = _level_coordinate(scn, log)
    if np.all(np.abs(at - rm.altitude_m) <= level_step_m / 2):
        return _bilinear(rm, log)
    if build is None:
        from rainuav.radio.outputs.maps import build_radio_map as build
    from rainuav.radio.outputs.levelmaps import level_scenario

    low = np.floor(at / level_step_m) * level_step_m
    frac = (at - low) / level_step_m
    high = low + level_step_m
    low = np.maximum(low, 0.5)  # the lowest map flies 0.5 m up (an area's least altitude)
    out = np.zeros(len(log))
    levels = sorted({*low.tolist(), *high[frac > 0].tolist()})
    if len(levels) > MAX_LEVEL_MAPS:
        raise InvalidInputError(
            f"{log.source or 'the log'}: its alt_m spans {float(at.min()):g}..{float(at.max()):g} "
            f"m, {len(levels)} maps {level_step_m:g} m apart; at most {MAX_LEVEL_MAPS} (a level "
            f"step of {np.ceil(float(np.ptp(at)) / (MAX_LEVEL_MAPS - 2)):g} m or more, radiomap "
            "--level-step-m, or the log cut to the heights that matter)"
        )
    maps: dict[float, RadioMap] = {}
    for k, lev in enumerate(levels):
        if progress:
            print(f"the log's heights: map {k + 1}/{len(levels)} at {lev:g} m", file=sys.stderr,
                  flush=True)  # fmt: skip
        maps[lev] = rm if abs(lev - rm.altitude_m) < 1e-9 else build(level_scenario(scn, lev))
    for lev, m in maps.items():
        v = _bilinear(m, log)
        out += np.where(low == lev, (1 - frac) * v, 0.0) + np.where(high == lev, frac * v, 0.0)
    return out


def _bilinear(rm: RadioMap, log: MeasurementLog) -> np.ndarray:
    """Each row's cell in ``rm``, bilinear between pixel centres (the navigation's sampler)."""
    return bilinear(np.asarray(rm.rss_dbm, dtype=np.float64), rm.extent_m, log.x_m, log.y_m,
                    log.cell)  # fmt: skip
