"""Radio maps in time: a scenario whose weather moves
([`rainuav.radio.scene.weather.Medium.at()`][rainuav.radio.scene.weather.Medium.at]) mapped at many
instants, and the static map of any instant between them.

What does not move is computed once: every cell's rays traced in clear air, their power split into
direct, reflected and interference parts
([`rainuav.radio.engines.ray_engine.ray_terms()`][rainuav.radio.engines.ray_engine.ray_terms]). Each
slice then integrates the rain of its instant once per site, from the site to every pixel at once
(cumulative integrals along lines fanning out from the site, read between lines:
``rainuav_core::propagation::raytime``), shared by the site's cells and by both rays (the reflection
point lies on the same horizontal line, and rain fills every column below the flight altitude), and
attenuates the parts with it. A slice is the static ray-engine map of the frozen weather at its
instant to within 0.05 dB (tested: the fan of lines replaces a line per pixel).

**The hybrid engine in time.** Where the PE carries part of a cell's pattern, it is marched
once, in clear air, and its power at each pixel is attenuated at every instant like the direct
ray's: by the rain along the horizontal line from the site, over the direct path's length (the
PE's energy inside its cone travels outward from the site along that line; the march's own
account of the rain, phase and scattering included, is what this replaces). The rays keep the
rest of the pattern as in the static hybrid. Measured against a static hybrid build, whose PE
marches through the frozen rain, in ``tests/test_timemap.py``. Engine 'pe' (a march per cell
and instant) is refused.

**The next storm over the same network.** What no weather changes is kept in memory for the next
series of the same scenario in other weather (a storm pool's next storm, the next held-out storm
of an evaluation): the last two scenarios' parts, each up to 256 MB, found by the scenario in
clear air. A series built from them is the same bit for bit.
"""

from __future__ import annotations

import hashlib
import math
import os
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._checks import as_real_array, as_real_scalar, check_fits, check_number
from rainuav.errors import InvalidInputError
from rainuav.radio.engines import engine_of
from rainuav.radio.engines.hybrid import EngineParts, engine_parts
from rainuav.radio.engines.ray_engine import gamma_table, rain_args, ray_slicer, ray_terms
from rainuav.radio.outputs.cache import map_path
from rainuav.radio.outputs.mapchecks import check_arrays, map_ranges
from rainuav.radio.outputs.mapdata import RadioMap, read_npz, store, write_npz
from rainuav.radio.outputs.sinr import RSS_FLOOR_DBM, sir_from_power
from rainuav.radio.scene.presets import with_rain
from rainuav.radio.scene.scenario import Scenario
from rainuav.radio.scene.terrain import map_mask
from rainuav.signals import Signal, signal_name, toml_of

__all__ = ["MAX_SLICES", "RadioMapSeries", "build_radio_map_series", "series_times"]

MAX_SLICES = 10_000
"""The most instants one series may hold."""
FORMAT_VERSION = 1
"""Version of the .npz layout
[`RadioMapSeries.save()`][rainuav.radio.outputs.timemap.RadioMapSeries.save] writes."""
_ARRAYS = ("t_s", "rss_dbm", "sinr_db", "sir_db", "serving_cell", "x_m", "y_m", "cell_site")


def series_times(duration_s: float, slice_s: float) -> npt.NDArray[np.float64]:
    """The instants 0, `slice_s`, ..., `duration_s` of a map series.

    Args:
        duration_s: The duration, s.
        slice_s: The step, s: it must divide the duration (to 1e-9 of it).

    Returns:
        The instants, s: 2 to [`MAX_SLICES`][rainuav.radio.outputs.timemap.MAX_SLICES] of them.

    Raises:
        InvalidInputError: A step that does not divide the duration, or too many slices.
    """
    d = check_number("duration_s", duration_s, 1e-3, 1e6, " s")
    step = check_number("slice_s", slice_s, 1e-3, d, f" s (at most duration_s = {d:g})")
    n = round(d / step)
    if abs(n * step - d) > 1e-9 * d:
        raise InvalidInputError(
            f"slice_s = {step:g} s must divide duration_s = {d:g} s (e.g. {d / max(n, 1):g})"
        )
    if n + 1 > MAX_SLICES:
        raise InvalidInputError(f"duration_s / slice_s gives {n + 1} slices, at most {MAX_SLICES}")
    return np.linspace(0.0, d, n + 1)


@dataclass
class RadioMapSeries:
    """Maps of one scenario at the instants ``t_s`` (s after its weather's time 0)."""

    t_s: npt.NDArray[np.float64]
    """(T,) instants, strictly increasing."""
    rss_dbm: npt.NDArray[np.float32]
    """(T, M, H, W) received power of each cell, dBm (float32: half the memory; 1e-5 dB)."""
    sinr_db: npt.NDArray[np.float64]
    """(T, H, W) SINR, dB."""
    sir_db: npt.NDArray[np.float64]
    """(T, H, W) SIR, dB."""
    serving_cell: npt.NDArray[np.int64]
    """(T, H, W) serving cell (-1: none)."""
    scenario: Scenario
    """The scenario, its weather at time 0 (``scenario.medium.at(t)`` is the weather at t)."""
    x_m: npt.NDArray[np.float64]
    y_m: npt.NDArray[np.float64]
    cell_site: npt.NDArray[np.int64]
    build_seconds: float = 0.0
    timings: dict[str, float] = field(default_factory=dict)

    def as_signal(self, signal: str = "sinr", *, scenario_toml: bool = True) -> Signal:
        """The maps in time as one [`Signal`][rainuav.signals.Signal] (a time axis at ``t_s``), bit
        for bit, with the serving cells and the ground's not-flyable pixels.

        Args:
            signal: "sinr" or "sir".
            scenario_toml: Carry the scenario as TOML.

        Returns:
            The signal.
        """
        name = signal_name(signal)
        a = self.scenario.area
        mask = map_mask(self.scenario)  # the ground's, the same at every instant
        return Signal.from_axes(getattr(self, name), ("time", "north", "east"),
                                (a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m), t_s=self.t_s,
                                altitudes_m=[a.altitude_m], serving_cell=self.serving_cell,
                                name=name, not_flyable=None if mask is None else mask[None],
                                scenario_toml=toml_of(self.scenario, scenario_toml))  # fmt: skip

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Writes the series as an .npz file, atomically (the scenario as TOML inside; no pickles).

        Args:
            path: The file to write.

        Returns:
            The path written.
        """
        return _save(self, path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> RadioMapSeries:
        """Reads a series written by [`save()`][rainuav.radio.outputs.timemap.RadioMapSeries.save].

        The file is checked (shapes, ranges, its scenario); the round trip is bit-exact.

        Args:
            path: The .npz file.

        Returns:
            The [`RadioMapSeries`][rainuav.radio.outputs.timemap.RadioMapSeries].

        Raises:
            InvalidInputError: A file that is missing or not a series, or whose arrays are
                inconsistent.
        """
        return _load(path)

    def at(self, t_s: float) -> RadioMap:
        """The map of one instant, interpolated between the slices around it.

        Each cell's received power is interpolated linearly in dB between the two slices around
        `t_s` (held beyond the first and the last), then the serving cell, SIR and SINR are computed
        from those powers. At a slice's own instant it is that slice.

        Args:
            t_s: Time, s.

        Returns:
            A [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap].

        Raises:
            InvalidInputError: `t_s` is not finite.
        """
        t = as_real_scalar("t_s", t_s)
        if not math.isfinite(t):
            raise InvalidInputError(f"t_s must be finite (got {t_s!r})")
        k = int(np.searchsorted(self.t_s, t))
        if k < len(self.t_s) and self.t_s[k] == t:
            rss = self.rss_dbm[k].astype(np.float64)
            serving, sir, sinr = self.serving_cell[k], self.sir_db[k], self.sinr_db[k]
        else:
            if k == 0 or k == len(self.t_s):
                rss = self.rss_dbm[min(k, len(self.t_s) - 1)].astype(np.float64)
            else:
                w = (t - self.t_s[k - 1]) / (self.t_s[k] - self.t_s[k - 1])
                a, b = self.rss_dbm[k - 1].astype(np.float64), self.rss_dbm[k].astype(np.float64)
                rss = (1.0 - w) * a + w * b
            power = np.where(rss > RSS_FLOOR_DBM, 10.0 ** (rss / 10.0), 0.0)
            serving, sir, sinr = sir_from_power(power, self.scenario.noise_power_dbm)
        a = self.scenario.area
        return RadioMap(
            x_m=self.x_m,
            y_m=self.y_m,
            extent_m=(a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m),
            altitude_m=a.altitude_m,
            rss_dbm=rss,
            serving_cell=serving,
            sir_db=sir,
            sinr_db=sinr,
            scenario=self.scenario.replace(medium=self.scenario.medium.at(t)),
            cell_site=self.cell_site,
        )


def _save(series: RadioMapSeries, path: str | os.PathLike[str]) -> Path:
    arrays = {k: getattr(series, k) for k in _ARRAYS}
    return write_npz(path, arrays, series.scenario, FORMAT_VERSION)


def _load(
    path: str | os.PathLike[str], known: tuple[str, Scenario] | None = None
) -> RadioMapSeries:
    data, scn = read_npz(path, "radio-map series", _ARRAYS, FORMAT_VERSION, known)
    _check_series_arrays(path, data, scn)
    return RadioMapSeries(scenario=scn, **{k: data[k] for k in _ARRAYS})


def _check_series_arrays(path: Any, data: dict[str, np.ndarray], scn: Scenario) -> None:
    """The arrays of a saved series as
    [`build_radio_map_series()`][rainuav.radio.outputs.timemap.build_radio_map_series] writes them,
    or one line naming the file and the array (instants, shapes, types, finite, physical ranges)."""
    t = data["t_s"]
    if t.ndim != 1 or not 1 <= t.size <= MAX_SLICES or t.dtype.kind != "f":
        raise InvalidInputError(f"{path}: t_s must be 1 to {MAX_SLICES} instants")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InvalidInputError(f"{path}: t_s must be finite and strictly increasing")
    n, (h, w) = t.size, scn.area.shape
    m = data["cell_site"].shape[0] if data["cell_site"].ndim == 1 else -1
    shapes = {
        "rss_dbm": (n, m, h, w), "sinr_db": (n, h, w), "sir_db": (n, h, w),
        "serving_cell": (n, h, w), "x_m": (w,), "y_m": (h,), "cell_site": (m,),
    }  # fmt: skip
    check_arrays(path, data, scn, shapes, map_ranges(m, scn))


def _cache_key(digest: str, t: np.ndarray) -> str:
    return f"{digest}|series|{hashlib.sha256(t.tobytes()).hexdigest()[:16]}"


def _peak_rate(scn: Scenario, t: np.ndarray) -> float:
    """An upper bound of the rain rate anywhere at any of the instants ``t``, mm/h."""
    med = scn.medium
    if med.kind == "map":
        return float(np.max(med.rate_map_mm_h))
    if med.kind == "field":
        return 500.0  # log-normal: the cap
    if med.kind != "cells":
        return med.rain_rate_mm_h
    return max(
        min(500.0, med.rain_rate_mm_h + sum(c.at(float(tk)).peak_rate_mm_h for c in med.cells))
        for tk in (t[0], t[-1])
    )


def _hybrid_terms(
    scn: Scenario,
    jobs: list[tuple[Any, Any]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    progress: bool,
    clear_parts: Callable[[], EngineParts] | None = None,
) -> np.ndarray | None:
    """The hybrid's terms for the slicer (None where it is the ray engine: engine 'ray', a
    soil, or no cell marched): the rays' terms less the part inside each PE cone, plus the
    PE's power marched once in clear air as a direct ray's (module docstring).
    ``clear_parts``: the engine's parts in clear air where the caller has them (every level
    from one march, [`rainuav.radio.outputs.levelmaps`][rainuav.radio.outputs.levelmaps])."""
    if not engine_of(scn).combines:
        return None
    if clear_parts is not None:
        parts = clear_parts()
    else:
        parts = engine_parts(with_rain(scn, 0.0), jobs, x_m, y_m, progress)
    if all(g is None for g in parts.grids):
        return None
    terms = ray_terms(scn, jobs, x_m, y_m, parts.weights)
    terms[..., 0] += parts.pe_power
    return terms


_STATIC_KEEP = 2
_STATIC_MAX_BYTES = 256 * 2**20
_static: OrderedDict[str, np.ndarray] = OrderedDict()
_static_lock = threading.Lock()  # a storm pool maps its next storm on a thread of its own


def _static_terms(
    scn: Scenario,
    jobs: list[tuple[Any, Any]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    progress: bool,
    clear_parts: Callable[[], EngineParts] | None,
) -> np.ndarray:
    """What no weather changes, for the slicer: the hybrid's terms, or the rays' alone (module
    docstring: kept for the next series of ``scn`` in clear air; not where the caller hands in
    its own clear-air parts)."""
    key = with_rain(scn, 0.0).digest() if clear_parts is None else None
    if key is not None:
        with _static_lock:
            if key in _static:
                _static.move_to_end(key)
                return _static[key]
    terms = _hybrid_terms(scn, jobs, x_m, y_m, progress, clear_parts)
    if terms is None:
        terms = ray_terms(scn, jobs, x_m, y_m)
    if key is not None and terms.nbytes <= _STATIC_MAX_BYTES:
        terms.setflags(write=False)
        with _static_lock:
            _static[key] = terms
            while len(_static) > _STATIC_KEEP:
                _static.popitem(last=False)
    return terms


def build_radio_map_series(
    scn: Scenario,
    times_s: npt.ArrayLike,
    *,
    cache: bool = True,
    progress: bool = False,
    clear_parts: Callable[[], EngineParts] | None = None,
    cache_tag: str = "",
) -> RadioMapSeries:
    """Builds the radio maps of a scenario's moving weather at several instants.

    The module docstring gives the method. Memory is checked before anything is allocated.

    Args:
        scn: The scenario, its weather at time 0 (``scn.medium.at(t)`` the weather at ``t``).
        times_s: The instants, strictly increasing, s.
        cache: Read a series of the same scenario, instants and engine code from the map cache
            ([`rainuav.radio.outputs.cache`][rainuav.radio.outputs.cache]), and keep a new one.
        progress: A line on standard error per instant.
        clear_parts: The hybrid's parts in clear air from elsewhere (called only if the series
            is built).
        cache_tag: The cache's name for a series built from ``clear_parts``, apart from one
            built alone.

    Returns:
        The [`RadioMapSeries`][rainuav.radio.RadioMapSeries].

    Raises:
        InvalidInputError: Instants that are not strictly increasing or finite, or a series
            that would not fit in memory.
    """
    if not engine_of(scn).traces:
        raise InvalidInputError(
            f"maps in time need engine 'ray' or 'hybrid' (got {scn.engine!r}: a PE march per "
            "cell and instant); use scn.replace(engine='hybrid')"
        )
    t = as_real_array("times_s", times_s)
    if t.ndim != 1 or not 1 <= t.size <= MAX_SLICES:
        raise InvalidInputError(f"times_s must be 1 to {MAX_SLICES} instants (got shape {t.shape})")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise InvalidInputError("times_s must be finite and strictly increasing")
    t0 = time.perf_counter()
    digest = scn.digest() if cache else ""
    if cache:
        path = map_path(_cache_key(digest, t) + cache_tag)
        if path.exists():
            try:
                return _load(path, (digest, scn))
            except InvalidInputError:
                pass  # a corrupt or partial entry is rebuilt, never trusted
    a = scn.area
    h, w = a.shape
    jobs = [(site, cell) for site in scn.sites for cell in site.cells]
    m = len(jobs)
    sites = len({(s.x_m, s.y_m) for s in scn.sites})
    check_fits(
        f"the map series ({t.size} slices x {m} cells x {h} x {w} pixels)",
        t.size * (4 * m + 24) * h * w + (6 * m + 3 * sites) * 8 * h * w,
        "use fewer slices, a coarser area.resolution_m or a smaller area",
    )
    x_m, y_m = a.centres()
    terms = _static_terms(scn, jobs, x_m, y_m, progress, clear_parts)
    slicer = ray_slicer(scn, jobs, x_m, y_m, terms)
    table = gamma_table(scn, _peak_rate(scn, t))
    timings = {"static": time.perf_counter() - t0}
    rss = np.empty((t.size, m, h, w), np.float32)
    sinr, sir = np.empty((t.size, h, w)), np.empty((t.size, h, w))
    serving = np.empty((t.size, h, w), np.int64)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=t.size, desc="radio map slices", unit="slice")
    t1 = time.perf_counter()
    try:
        weather_at = scn.medium.clock()
        for k, tk in enumerate(t):
            rain = rain_args(scn.replace(medium=weather_at(tk)), table)
            power = slicer.power(**rain, rss_dbm_out=rss[k], rss_floor_dbm=RSS_FLOOR_DBM)
            serving[k], sir[k], sinr[k] = sir_from_power(power, scn.noise_power_dbm)
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    timings["slices"] = time.perf_counter() - t1
    series = RadioMapSeries(
        t_s=t.copy(),
        rss_dbm=rss,
        sinr_db=sinr,
        sir_db=sir,
        serving_cell=serving,
        scenario=scn,
        x_m=x_m,
        y_m=y_m,
        cell_site=np.array([i for i, s in enumerate(scn.sites) for _ in s.cells], dtype=np.int64),
        build_seconds=time.perf_counter() - t0,
        timings=timings,
    )
    if cache:
        store(series, map_path(_cache_key(digest, t) + cache_tag))
    return series
