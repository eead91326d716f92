"""Radio maps at several flight altitudes (``area.altitudes_m``): one map per level, stacked on an
altitude axis, so a flight can choose its height
([`rainuav.nav.planner.optimal_levels()`][rainuav.nav.planner.optimal_levels]).

Each level is the scenario's map at that altitude, built by its engine (and cached as any map): the
ray engine traces every level; the hybrid engine over flat ground marches each cell once and reads
every level from that march (its grid the highest level's, so its cone may be narrower than a lower
level's own: the rays carry the rest); the PE engine, and the hybrid over terrain, march once per
level. Memory is checked for the whole stack before the first level is built. Weather that moves:
[`build_radio_level_series()`][rainuav.radio.outputs.levelmaps.build_radio_level_series], the maps
in time of every level, (time, altitude, H, W) (the hybrid's clear-air march once a cell for every
level, likewise)."""

from __future__ import annotations

import dataclasses
import functools
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._checks import check_fits
from rainuav._sampling import bilinear
from rainuav.errors import InvalidInputError
from rainuav.radio.engines import engine_of
from rainuav.radio.outputs.levelsignal import LevelsAsSignal
from rainuav.radio.outputs.mapdata import RadioMap, read_npz, write_npz
from rainuav.radio.scene.scenario import Scenario

__all__ = [
    "LevelStack",
    "RadioLevelSeries",
    "RadioLevels",
    "build_radio_level_series",
    "build_radio_levels",
    "level_scenario",
    "sample_levels",
    "shares_a_march",
]


@dataclass(frozen=True)
class RadioLevels(LevelsAsSignal):
    """A scenario's maps at each flight altitude, lowest first."""

    altitudes_m: np.ndarray
    """The levels (L,), m, in the area's altitude reference."""
    maps: tuple[RadioMap, ...]
    """One map a level."""

    @property
    def scenario(self) -> Scenario:
        """The scenario the maps were built from (the lowest level's)."""
        return self.maps[0].scenario

    def _serving_and_scenario(self) -> tuple[Any, Any]:  # the maps' own arrays
        return np.stack([m.serving_cell for m in self.maps]), self.scenario

    @property
    def sinr_db(self) -> np.ndarray:
        """SINR (L, H, W), dB."""
        return np.stack([m.sinr_db for m in self.maps])

    @property
    def not_flyable(self) -> np.ndarray:
        """The pixels a UAV may not enter at each level (L, H, W), bool (all flyable where a
        map carries no mask)."""
        return np.stack(
            [
                np.zeros(m.sinr_db.shape, bool) if m.not_flyable is None else m.not_flyable
                for m in self.maps
            ]
        )

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max), m."""
        return self.maps[0].extent_m


def level_scenario(scn: Scenario, altitude_m: float) -> Scenario:
    """A scenario flying at one altitude alone.

    Args:
        scn: The scenario.
        altitude_m: The altitude, m.

    Returns:
        `scn` with `area.altitude_m` that altitude and no flight levels.
    """
    area = dataclasses.replace(scn.area, altitude_m=float(altitude_m), altitudes_m=None)
    return scn.replace(area=area)


def build_radio_levels(
    scn: Scenario, *, cache: bool = True, progress: bool = False, one_march: bool = True
) -> RadioLevels:
    """The maps of a scenario at each of its flight levels (the module's docstring has how).

    Args:
        scn: A scenario whose `area.altitudes_m` lists the levels.
        cache: Read and keep the maps in the map cache.
        progress: A line on standard error per map built.
        one_march: The hybrid engine over flat ground marches each cell once for every level
            ([`engine_parts_levels()`][rainuav.radio.engines.hybrid.engine_parts_levels],
            [`shares_a_march()`][rainuav.radio.outputs.levelmaps.shares_a_march]); False: once per
            level.

    Returns:
        The levels' maps, lowest first.
    """
    from rainuav.radio.outputs.maps import build_radio_map

    levels = scn.area.levels
    h, w = scn.area.shape
    cells = sum(len(s.cells) for s in scn.sites)
    # Each map: rss (M, H, W) float32, SINR, SIR, serving, mask.
    check_fits(
        f"area.altitudes_m ({len(levels)} levels of {cells} cells x {h} x {w} pixels)",
        len(levels) * (cells + 4) * h * w * 4.0,
        "use fewer levels or a coarser resolution_m",
    )
    if one_march and shares_a_march(scn):
        return _levels_from_one_march(scn, cache=cache, progress=progress)
    maps = []
    for k, a in enumerate(levels):
        if progress:
            print(f"level {k + 1}/{len(levels)}: {a:g} m", flush=True)
        maps.append(build_radio_map(level_scenario(scn, a), cache=cache))
    return RadioLevels(np.asarray(levels, dtype=float), tuple(maps))


def shares_a_march(scn: Scenario) -> bool:
    """Whether one march per cell serves every flight level of a scenario.

    It does with several levels, the hybrid engine over a perfect conductor or no ground, and flat
    ground. Over terrain each level's receiver surface follows the ground and marches apart; the
    'pe' engine marches each level on its own grid, whose cone is its own (a grid tall enough for
    the highest level fits the budget with a narrower cone, and the PE alone has no rays for the
    rest).

    Args:
        scn: The scenario.

    Returns:
        True where one march serves.
    """
    from rainuav.radio.engines.ray_engine import SOILS

    return (
        len(scn.area.levels) > 1
        and engine_of(scn).combines
        and scn.ground not in SOILS
        and scn.terrain is None
    )


def _levels_from_one_march(scn: Scenario, *, cache: bool, progress: bool) -> RadioLevels:
    """Every level's map with each cell marched once (cached apart from the maps each level
    would get on its own: the cone is the highest level's)."""
    import time

    from rainuav.radio.engines.hybrid import engine_parts_levels
    from rainuav.radio.outputs.cache import map_path
    from rainuav.radio.outputs.mapdata import store
    from rainuav.radio.outputs.maps import cached_map, map_from_parts

    levels = scn.area.levels
    scns = [level_scenario(scn, a) for a in levels]
    paths = [map_path(f"{scn.digest()}|one march|{k}") for k in range(len(levels))]
    if cache:
        hits = [cached_map(s, p) for s, p in zip(scns, paths, strict=True)]
        if all(m is not None for m in hits):
            return RadioLevels(np.asarray(levels, dtype=float), tuple(hits))  # type: ignore[arg-type]
    t0 = time.perf_counter()
    x_m, y_m = scn.area.centres()
    cells = [(s, c) for s in scn.sites for c in s.cells]
    parts = engine_parts_levels(scns, cells, x_m, y_m, progress)
    maps = tuple(map_from_parts(s, p, t0) for s, p in zip(scns, parts, strict=True))
    if cache:
        for m, p in zip(maps, paths, strict=True):
            store(m, p)
    return RadioLevels(np.asarray(levels, dtype=float), maps)


@dataclass(frozen=True)
class RadioLevelSeries(LevelsAsSignal):
    """A scenario's maps in time at each flight altitude: what a flight among levels through
    weather that moves reads."""

    altitudes_m: np.ndarray
    """The levels (L,), m, lowest first."""
    t_s: np.ndarray
    """(T,) instants, s."""
    sinr_db: np.ndarray
    """(T, L, H, W) SINR, dB, float32."""
    serving_cell: np.ndarray
    """(T, L, H, W) serving cell (-1: none), int16."""
    not_flyable: np.ndarray
    """(L, H, W) the pixels a UAV may not enter at each level (the weather moves nothing on
    the ground)."""
    extent: tuple[float, float, float, float]
    """(x_min, x_max, y_min, y_max), m."""
    at_take_off: tuple[RadioMap, ...] = ()
    """Each level's map at the first instant (a static map: for a figure or a GeoTIFF)."""


_CLEAR_LOCK = threading.Lock()
_CLEAR_PARTS: dict[str, Any] = {}
"""The last clear-air march of every level (its scenarios' digests, and the parts): the
hybrid's PE part does not depend on the weather, so the storms of one network (a storm pool
maps one after another) march their cells once. Read only (the series add to copies)."""


def build_radio_level_series(
    scn: Scenario,
    times_s: object,
    *,
    cache: bool = True,
    progress: bool = False,
    one_march: bool = True,
) -> RadioLevelSeries:
    """The maps in time of a scenario at each of its flight levels, memory checked first.

    [`build_radio_map_series()`][rainuav.radio.outputs.timemap.build_radio_map_series] per level.

    Args:
        scn: A scenario whose `area.altitudes_m` lists the levels, in a weather that moves.
        times_s: The instants, s.
        cache: Read and keep the maps in the map cache.
        progress: A line on standard error per map built.
        one_march: The hybrid over flat ground marches each cell once in clear air for every level
            ([`shares_a_march()`][rainuav.radio.outputs.levelmaps.shares_a_march]), as
            [`build_radio_levels()`][rainuav.radio.outputs.levelmaps.build_radio_levels] does.

    Returns:
        Each level's series, lowest first.

    Raises:
        InvalidInputError: A stack that would not fit in memory (the sizes named).
    """
    from rainuav._checks import as_real_array
    from rainuav.radio.outputs.timemap import build_radio_map_series
    from rainuav.radio.scene.terrain import map_mask

    levels = scn.area.levels
    t = as_real_array("times_s", times_s).reshape(-1)
    h, w = scn.area.shape
    cells = sum(len(s.cells) for s in scn.sites)
    # Per level a series (its rss (T, M, H, W) float32 and SINR, SIR, serving), and the stack.
    check_fits(
        f"area.altitudes_m ({len(levels)} levels x {t.size} instants of {cells} cells x "
        f"{h} x {w} pixels)",
        (len(levels) + 1) * t.size * (cells + 4) * h * w * 4.0,
        "use fewer levels or instants, or a coarser resolution_m",
    )
    sinr = np.empty((t.size, len(levels), h, w), dtype=np.float32)
    serving = np.empty((t.size, len(levels), h, w), dtype=np.int16)
    masks = np.zeros((len(levels), h, w), dtype=bool)
    first: list[RadioMap] = []
    extent = (scn.area.x_min_m, scn.area.x_max_m, scn.area.y_min_m, scn.area.y_max_m)
    shared: Callable[[int], Any] | None = None
    tag = ""
    if one_march and shares_a_march(scn):
        # The hybrid's clear-air march: every level from one march a cell, marched only if a
        # level's series is not in the cache.
        from rainuav.radio.engines.hybrid import engine_parts_levels
        from rainuav.radio.scene.presets import with_rain

        tag = f"|one march|{scn.digest()}"
        parts: list = []

        def from_one_march(k: int) -> Any:
            if not parts:
                clear = [with_rain(level_scenario(scn, a), 0.0) for a in levels]
                key = tuple(c.digest() for c in clear)
                with _CLEAR_LOCK:  # storms of one network share their clear-air march
                    if _CLEAR_PARTS.get("key") != key:
                        jobs = [(s, c) for s in scn.sites for c in s.cells]
                        x_m, y_m = scn.area.centres()
                        got = engine_parts_levels(clear, jobs, x_m, y_m, progress)
                        _CLEAR_PARTS.update(key=key, parts=got)
                    parts.extend(_CLEAR_PARTS["parts"])
            return parts[k]

        shared = from_one_march

    for k, a in enumerate(levels):
        if progress:
            print(f"level {k + 1}/{len(levels)}: {a:g} m", flush=True)
        one = level_scenario(scn, a)
        clear_parts = None if shared is None else functools.partial(shared, k)
        series = build_radio_map_series(one, t, cache=cache, clear_parts=clear_parts, cache_tag=tag)
        sinr[:, k] = series.sinr_db
        serving[:, k] = series.serving_cell
        mask = map_mask(one)
        if mask is not None:
            masks[k] = mask
        first.append(dataclasses.replace(series.at(float(t[0])), not_flyable=mask))
    return RadioLevelSeries(
        np.asarray(levels, dtype=float), t, sinr, serving, masks, extent, tuple(first)
    )


def sample_levels(
    values: np.ndarray,
    extent: tuple[float, float, float, float],
    x: np.ndarray,
    y: np.ndarray,
    levels: np.ndarray,
) -> np.ndarray:
    """A stack of maps read at points, each on its own level, as the navigation task reads a map.

    Args:
        values: The maps (L, H, W).
        extent: `(x_min, x_max, y_min, y_max)`, m.
        x: East, m (N,).
        y: North, m (N,).
        levels: Each point's level index (N,).

    Returns:
        (N,) values, bilinear between pixel centres.
    """
    x, y, levels = np.asarray(x, float), np.asarray(y, float), np.asarray(levels)
    out = np.empty(x.shape)
    for k in np.unique(levels):
        on = levels == k
        out[on] = bilinear(values[int(k)], extent, x[on], y[on])
    return out


STACK_VERSION = 1
"""Format of a saved [`LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack]."""


@dataclass(frozen=True)
class LevelStack(LevelsAsSignal):
    """What a flight among levels reads, and what a training run among levels saves
    (``radiolevels.npz``): every level's SINR and serving cell (static (L, H, W), or in time
    (T, L, H, W) at ``t_s``), the not-flyable pixels (L, H, W), the levels and the area,
    with the scenario they were built from."""

    scenario: Scenario
    altitudes_m: np.ndarray
    sinr_db: np.ndarray
    serving_cell: np.ndarray
    not_flyable: np.ndarray
    extent: tuple[float, float, float, float]
    t_s: np.ndarray | None = None
    """(T,) instants, s, of a stack in time; None: static."""

    @classmethod
    def of(cls, source: RadioLevels | RadioLevelSeries, scn: Scenario) -> LevelStack:
        """The stack of built levels of a scenario.

        Args:
            source: What
                [`build_radio_levels()`][rainuav.radio.outputs.levelmaps.build_radio_levels] or
                [`build_radio_level_series()`][rainuav.radio.outputs.levelmaps.build_radio_level_series]
                gave.
            scn: The scenario.

        Returns:
            The [`LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack].
        """
        if isinstance(source, RadioLevels):
            serving = np.stack([m.serving_cell for m in source.maps]).astype(np.int16)
            sinr = source.sinr_db.astype(np.float32)
            return cls(scn, source.altitudes_m, sinr, serving, source.not_flyable, source.extent)
        return cls(scn, source.altitudes_m, source.sinr_db, source.serving_cell,
                   source.not_flyable, source.extent, source.t_s)  # fmt: skip

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Writes the stack as an .npz (the scenario as TOML inside; no pickles), atomically.

        Args:
            path: The file.

        Returns:
            The path written.
        """
        arrays = {
            "altitudes_m": np.asarray(self.altitudes_m, np.float64),
            "sinr_db": self.sinr_db,
            "serving_cell": self.serving_cell,
            "not_flyable": self.not_flyable,
            "extent_m": np.asarray(self.extent, np.float64),
        }
        if self.t_s is not None:
            arrays["t_s"] = np.asarray(self.t_s, np.float64)
        return write_npz(path, arrays, self.scenario, STACK_VERSION)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> LevelStack:
        """Reads a stack written by [`save()`][rainuav.radio.outputs.levelmaps.LevelStack.save],
        checked.

        Shapes, finite values, and its scenario's area and levels are checked; the round trip is
        bit-exact.

        Args:
            path: The file.

        Returns:
            The [`LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack].

        Raises:
            InvalidInputError: A file that is not a stack of its scenario's levels (named).
        """
        need = ("altitudes_m", "sinr_db", "serving_cell", "not_flyable", "extent_m")
        d, scn = read_npz(path, "stack of level maps", need, STACK_VERSION)
        alts, sinr, t = d["altitudes_m"], d["sinr_db"], d.get("t_s")
        want = (len(scn.area.levels), *scn.area.shape)
        lead = () if t is None else (t.size,)
        ok = (
            alts.tolist() == scn.area.levels
            and sinr.shape == (*lead, *want) and sinr.dtype.kind == "f"
            and bool(np.all(np.isfinite(sinr)))
            and d["serving_cell"].shape == sinr.shape and d["serving_cell"].dtype.kind == "i"
            and d["not_flyable"].shape == want and d["not_flyable"].dtype == bool
            and d["extent_m"].shape == (4,)
            and (t is None or (t.ndim == 1 and bool(np.all(np.diff(t) > 0))))
        )  # fmt: skip
        if not ok:
            raise InvalidInputError(
                f"{path}: not a stack of level maps of its scenario (levels {scn.area.levels}, "
                f"pixels {scn.area.shape}; finite SINR, a mask and serving cells of that shape)"
            )
        ext = tuple(float(v) for v in d["extent_m"])
        return cls(scn, alts, sinr, d["serving_cell"], d["not_flyable"], ext, t)  # type: ignore[arg-type]
