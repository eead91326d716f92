"""Radio maps: received power per cell, the serving cell, SIR and SINR over the flight altitude.

[`build_radio_map()`][rainuav.radio.outputs.maps.build_radio_map] grids every cell
([`rainuav.radio.engines.grid`][rainuav.radio.engines.grid]), marches it
([`rainuav.radio.engines.pe_engine`][rainuav.radio.engines.pe_engine]), resamples its power onto the
map's pixel centres, and combines the cells
([`rainuav.radio.outputs.sinr`][rainuav.radio.outputs.sinr]). ``sir_db`` and ``sinr_db`` are clipped
to [-40, 60] dB: -40 where no cell reaches (and the serving cell is -1), 60 where only one cell
does. ``rss_dbm`` is -250 dBm where a cell does not reach. Cells are computed one after another,
each march using every core. Maps are cached on disk
([`rainuav.radio.outputs.cache`][rainuav.radio.outputs.cache])."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, overload

import numpy as np

from rainuav._checks import check_fits
from rainuav.errors import InvalidInputError
from rainuav.radio.engines import engine_of
from rainuav.radio.engines.hybrid import EngineParts, engine_parts
from rainuav.radio.engines.ray_engine import SOILS
from rainuav.radio.outputs.cache import map_path
from rainuav.radio.outputs.mapdata import FORMAT_VERSION, RadioMap, store
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM, sir_from_power
from rainuav.radio.scene.scenario import Scenario
from rainuav.radio.scene.terrain import map_mask

if TYPE_CHECKING:
    import numpy.typing as npt

    from rainuav.radio.outputs.timemap import RadioMapSeries

__all__ = ["FORMAT_VERSION", "RadioMap", "build_radio_map"]

MAP_ARRAYS = 10
"""(cells, H, W) float64 arrays a map build holds at its peak (its memory check)."""


def cached_map(scn: Scenario, path: Path | None = None) -> RadioMap | None:
    """The cached map of a scenario, or None.

    Args:
        scn: The scenario.
        path: The cache file; None: its digest's.

    Returns:
        The [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap], or None where none is cached (or
        the file is refused: it is then rebuilt).
    """
    digest = scn.digest()
    path = map_path(digest) if path is None else path
    if not path.exists():
        return None
    try:
        # The map carries ``scn``: a hit never reaches for the files the stored scenario named.
        rm = RadioMap.load(path, known=(digest, scn))
    except Exception:  # a corrupt or partial entry is rebuilt, never trusted
        return None
    if rm.scenario is not scn:  # an entry without its digest (or another's): rebuilt
        return None
    return rm


@overload
def build_radio_map(
    scn: Scenario, *, cache: bool = ..., progress: bool = ..., times_s: None = ...
) -> RadioMap: ...
@overload
def build_radio_map(
    scn: Scenario, *, cache: bool = ..., progress: bool = ..., times_s: npt.ArrayLike
) -> RadioMapSeries: ...
def build_radio_map(
    scn: Scenario,
    *,
    cache: bool = True,
    progress: bool = False,
    times_s: npt.ArrayLike | None = None,
) -> RadioMap | RadioMapSeries:
    """Builds the radio map of a scenario, or loads it from the cache.

    The scenario's engine makes it: ``"pe"`` marches each cell's pattern inside its cone;
    ``"ray"`` traces two rays per cell and pixel; ``"hybrid"`` lets the PE carry each pattern
    inside its cone and the rays the rest (the PE needs a ``pec`` ground or none: over a soil the
    hybrid is the ray engine; a cell whose cone carries under 1% of its power at every pixel is
    not marched). ``RadioMap.pe_share`` records, per cell and pixel, the share of the power the
    PE carried.

    Args:
        scn: The network, weather, ground and output grid
            ([`Scenario`][rainuav.radio.Scenario]; [`presets`][rainuav.radio.scene.presets]
            makes the shipped ones).
        cache: Read and write the map cache (``RAINUAV_CACHE_DIR``); the same scenario is then
            built once.
        progress: One line on standard error per cell marched.
        times_s: Instants (s from take-off) of a moving weather: the maps at each, by
            [`build_radio_map_series()`][rainuav.radio.outputs.timemap.build_radio_map_series].

    Returns:
        The [`RadioMap`][rainuav.radio.RadioMap] (every cell's received power ``rss_dbm``, the
        serving cell, SIR and SINR in dB), or with ``times_s`` a
        [`RadioMapSeries`][rainuav.radio.RadioMapSeries].

    Raises:
        InvalidInputError: The map would not fit in the memory available (the message names
            what sets its size and how to shrink it).

    Examples:
        ```python
        import numpy as np
        from rainuav.radio import build_radio_map, presets

        rm = build_radio_map(presets.uma(rain_rate_mm_h=25.0, engine="ray"))
        print(rm.sinr_db.shape, f"median SINR {np.median(rm.sinr_db):.1f} dB")
        ```
    """
    if times_s is not None:
        from rainuav.radio.outputs.timemap import build_radio_map_series

        return build_radio_map_series(scn, times_s, cache=cache, progress=progress)
    if cache and (hit := cached_map(scn)) is not None:
        return hit
    if not engine_of(scn).traces and scn.ground in SOILS:
        raise InvalidInputError(
            f"engine 'pe' needs ground 'pec' or 'none' (got {scn.ground!r}: the PE's ground "
            "is a perfect conductor); use engine 'ray' or 'hybrid'"
        )
    t0 = time.perf_counter()
    a = scn.area
    h, w = a.shape
    x_m, y_m = a.centres()
    jobs = [(i, site, cell) for i, site in enumerate(scn.sites) for cell in site.cells]
    # Every engine holds about ten (cells, H, W) float64 arrays at its peak (the rays' gains,
    # cone weights and powers, the PE's powers, the combination): refuse before the first.
    check_fits(
        f"the radio map ({len(jobs)} cells x {h} x {w} pixels)",
        MAP_ARRAYS * 8 * len(jobs) * h * w,
        "use a coarser area.resolution_m, a smaller area or fewer cells",
    )
    parts = engine_parts(scn, [(s, c) for _, s, c in jobs], x_m, y_m, progress)
    rm = map_from_parts(scn, parts, t0)
    if cache:
        store(rm, map_path(scn.digest()))
    return rm


def map_from_parts(scn: Scenario, parts: EngineParts, t0: float) -> RadioMap:
    """The map of a scenario from its engine's parts.

    Args:
        scn: The scenario.
        parts: The engine's parts.
        t0: When the build started (`time.perf_counter`), for its recorded time.

    Returns:
        The [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap].
    """
    a = scn.area
    x_m, y_m = a.centres()
    jobs = [(i, site, cell) for i, site in enumerate(scn.sites) for cell in site.cells]
    power, carried, pe_power, grids = parts.power, parts.carried, parts.pe_power, parts.grids
    timings = parts.timings
    if not engine_of(scn).traces:
        power = pe_power
        pe_share = (pe_power > 0).astype(np.float32)
    else:
        # The PE replaces the rays' account of the part of each pattern inside its cone:
        # P = P_ray(G) + P_pe(G w) - P_ray(G w). Where the two agree this is the ray map, so
        # the seam is continuous by construction; inside the cone (w = 1) it is the PE's map
        # (rain cells and buildings as the march sees them).
        with np.errstate(divide="ignore", invalid="ignore"):
            pe_share = np.clip(np.where(power > 0, carried / power, 0.0), 0, 1).astype(np.float32)
        power = np.maximum(power - carried + pe_power, pe_power)
    cones = np.array(
        [
            [0.0, 0.0]
            if g is None
            else [math.degrees(math.asin(g.sine_h)), math.degrees(math.asin(g.sine_v))]
            for g in grids
        ]
    ).reshape(-1, 2)
    serving, sir, sinr = sir_from_power(power, scn.noise_power_dbm)
    with np.errstate(divide="ignore"):
        rss = np.where(power > 0, 10 * np.log10(power), RSS_FLOOR_DBM)
    rm = RadioMap(
        x_m=x_m,
        y_m=y_m,
        extent_m=(a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m),
        altitude_m=a.altitude_m,
        rss_dbm=np.maximum(rss, RSS_FLOOR_DBM),
        serving_cell=serving,
        sir_db=sir,
        sinr_db=sinr,
        scenario=scn,
        cell_site=np.array([i for i, _, _ in jobs], dtype=np.int64),
        pe_share=pe_share,
        pe_cone_deg=cones,
        build_seconds=time.perf_counter() - t0,
        timings=timings,
        not_flyable=map_mask(scn),
    )
    return rm
