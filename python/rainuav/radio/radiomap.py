"""Radio maps: received power per cell, the serving cell, SIR and SINR over the flight altitude.

:func:`build_radio_map` grids every cell (:mod:`rainuav.radio.grid`), marches it
(:mod:`rainuav.radio.pe_engine`), resamples its power onto the map's pixel centres, and
combines the cells (:mod:`rainuav.radio.sinr`). ``sir_db`` and ``sinr_db`` are clipped to
[-40, 60] dB: -40 where no cell reaches (and the serving cell is -1), 60 where only one cell
does. ``rss_dbm`` is -250 dBm where a cell does not reach. Cells are computed one after
another, each march using every core. Maps are cached on disk (:mod:`rainuav.radio.cache`).
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
import warnings
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import _core
from rainuav._checks import check_fits
from rainuav._io import write_atomic
from rainuav.errors import CacheWarning, InvalidInputError
from rainuav.radio.cache import cache_dir, map_path
from rainuav.radio.grid import MarchGrid, cone_weight, march_grid
from rainuav.radio.pe_engine import march_cell, resample
from rainuav.radio.plot import plot_map
from rainuav.radio.presets import DEFAULT_MIN_DB, SINR_THRESHOLDS_DB
from rainuav.radio.ray_engine import SOILS, Weight, ray_power
from rainuav.radio.scenario import Scenario
from rainuav.radio.sinr import RSS_FLOOR_DBM, SIR_CEIL_DB, SIR_FLOOR_DB, sir_from_power

__all__ = ["FORMAT_VERSION", "RadioMap", "build_radio_map"]

FORMAT_VERSION = 2
"""Version of the .npz layout written by :meth:`RadioMap.save`."""


@dataclass
class RadioMap:
    """Received power per cell, serving cell, SIR and SINR at the flight altitude."""

    x_m: npt.NDArray[np.float64]
    """(W,) pixel-centre east coordinates."""
    y_m: npt.NDArray[np.float64]
    """(H,) pixel-centre north coordinates."""
    extent_m: tuple[float, float, float, float]
    """(x_min, x_max, y_min, y_max) of the area."""
    altitude_m: float
    """Flight altitude, m."""
    rss_dbm: npt.NDArray[np.float64]
    """(M, H, W) received power per cell, isotropic receiver, dBm (-250 where unreached)."""
    serving_cell: npt.NDArray[np.int64]
    """(H, W) the strongest cell (-1 where none reaches)."""
    sir_db: npt.NDArray[np.float64]
    """(H, W) SIR in dB, clipped to [-40, 60]."""
    sinr_db: npt.NDArray[np.float64]
    """(H, W) SINR in dB, clipped to [-40, 60]."""
    scenario: Scenario
    """The scenario the map was built from."""
    cell_site: npt.NDArray[np.int64]
    """(M,) the site index of each cell."""
    pe_share: npt.NDArray[np.float32] = None  # type: ignore[assignment]
    """(M, H, W) which engine produced each cell's power at each pixel: the PE's share of
    it (0: rays alone, 1: the PE alone; all 0 if not given)."""
    pe_cone_deg: npt.NDArray[np.float64] = None  # type: ignore[assignment]
    """(M, 2) each cell's PE cone, half-widths across range and in height, degrees (0: no
    PE for that cell, or not given)."""
    build_seconds: float = 0.0
    """Wall time of the build (0 when loaded from the cache)."""
    timings: dict[str, float] = dataclasses.field(default_factory=dict)
    """Seconds per phase of the build: source, screens, march, resample (empty if cached)."""

    _ARRAYS = (
        "x_m",
        "y_m",
        "rss_dbm",
        "serving_cell",
        "sir_db",
        "sinr_db",
        "cell_site",
        "pe_share",
        "pe_cone_deg",
    )

    def __post_init__(self) -> None:
        if self.pe_share is None:
            self.pe_share = np.zeros(np.shape(self.rss_dbm), np.float32)
        if self.pe_cone_deg is None:
            self.pe_cone_deg = np.zeros((len(self.rss_dbm), 2))

    def default_min_db(self, signal: str = "sinr") -> float:
        """The outage threshold a navigation task on this map uses unless told otherwise: for
        SINR the preset's documented one (``presets.SINR_THRESHOLDS_DB``, by the scenario's
        name); for SIR, and for scenarios of no preset, 10 dB (the paper's minimum SIR)."""
        if signal == "sinr":
            return SINR_THRESHOLDS_DB.get(self.scenario.name, DEFAULT_MIN_DB)
        return DEFAULT_MIN_DB

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Writes an .npz with the scenario as TOML metadata, atomically."""
        meta = {
            "format_version": np.int64(FORMAT_VERSION),
            "extent_m": np.asarray(self.extent_m, dtype=np.float64),
            "altitude_m": np.float64(self.altitude_m),
            "scenario_toml": np.asarray(self.scenario.to_toml_string()),
            "digest": np.asarray(self.scenario.digest()),
        }
        arrays = {k: getattr(self, k) for k in self._ARRAYS}

        def write(tmp: Path) -> None:
            with tmp.open("wb") as fh:
                np.savez(fh, **arrays, **meta)

        return write_atomic(path, write)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> RadioMap:
        """Reads a map written by :meth:`save` (bit-exact round trip)."""
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except (OSError, ValueError, zipfile.BadZipFile, EOFError) as err:
            raise InvalidInputError(f"{path}: not a readable radio map ({err})") from err
        missing = {*cls._ARRAYS, "extent_m", "altitude_m", "scenario_toml"} - set(data)
        if missing:
            raise InvalidInputError(f"{path}: not a rainuav radio map (missing {sorted(missing)})")
        version = data.get("format_version", np.array(-1))
        if version.shape != () or not np.issubdtype(version.dtype, np.integer):
            raise InvalidInputError(f"{path}: not a rainuav radio map (no format_version)")
        if int(version) != FORMAT_VERSION:
            raise InvalidInputError(
                f"{path}: radio map format {int(version)}, this rainuav reads {FORMAT_VERSION}"
            )
        if data["scenario_toml"].dtype.kind != "U" or data["extent_m"].shape != (4,):
            raise InvalidInputError(f"{path}: not a rainuav radio map (bad metadata)")
        try:
            scn = Scenario.from_toml_string(str(data["scenario_toml"]))
        except InvalidInputError as err:
            raise InvalidInputError(f"{path}: its scenario is not valid ({err})") from err
        check_map_arrays(path, data, scn)
        ext = tuple(float(v) for v in data["extent_m"])
        out = cls(
            x_m=data["x_m"],
            y_m=data["y_m"],
            extent_m=ext,  # type: ignore[arg-type]
            altitude_m=float(data["altitude_m"]),
            rss_dbm=data["rss_dbm"],
            serving_cell=data["serving_cell"],
            sir_db=data["sir_db"],
            sinr_db=data["sinr_db"],
            scenario=scn,
            cell_site=data["cell_site"],
            pe_share=data["pe_share"],
            pe_cone_deg=data["pe_cone_deg"],
        )
        return out

    def plot(self, kind: str = "sir", cell: int | None = None, ax: Any = None) -> Any:
        """Draws the map in dB (``kind`` 'sir', 'sinr' or 'rss'; ``cell`` selects one cell's
        RSS, default the strongest) with the sites marked; returns the matplotlib Axes
        (:func:`rainuav.radio.plot.plot_map`)."""
        return plot_map(self, kind, cell, ax)

    def coverage(self, sir_min_db: float = 10.0) -> float:
        """Share of the area with SIR >= sir_min_db."""
        return float(np.mean(self.sir_db >= sir_min_db))


def check_map_arrays(path: Any, data: dict[str, np.ndarray], scn: Scenario) -> None:
    """A map's arrays as :func:`build_radio_map` writes them, or :class:`InvalidInputError`
    naming the file and the array: shapes from the scenario, types, and values finite and in
    their physical ranges (SIR and SINR within [SIR_FLOOR_DB, SIR_CEIL_DB], RSS within
    [RSS_FLOOR_DBM, 100] dBm, serving cells and sites that exist, PE shares in [0, 1], pixel
    centres where the area puts them)."""
    h, w = scn.area.shape
    m = len(data["cell_site"]) if data["cell_site"].ndim == 1 else -1  # the map's own cells
    shapes = {
        "x_m": (w,), "y_m": (h,), "rss_dbm": (m, h, w), "serving_cell": (h, w),
        "sir_db": (h, w), "sinr_db": (h, w), "cell_site": (m,), "pe_share": (m, h, w),
        "pe_cone_deg": (m, 2),
    }  # fmt: skip
    for k, shape in shapes.items():
        a = data[k]
        if a.shape != shape or a.dtype.kind not in "fiu":
            raise InvalidInputError(
                f"{path}: {k} must be a numeric array of shape {shape} for its scenario "
                f"(got {a.dtype} {a.shape})"
            )
        if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
            raise InvalidInputError(f"{path}: {k} holds NaN or infinite values")
    ranges = {
        "sir_db": (SIR_FLOOR_DB, SIR_CEIL_DB),
        "sinr_db": (SIR_FLOOR_DB, SIR_CEIL_DB),
        "rss_dbm": (RSS_FLOOR_DBM, 100.0),
        "serving_cell": (-1, m - 1),
        "cell_site": (0, len(scn.sites) - 1),
        "pe_share": (0.0, 1.0),
        "pe_cone_deg": (0.0, 90.0),
    }
    for k, (lo, hi) in ranges.items():
        a = data[k]
        if a.size and (a.min() < lo or a.max() > hi):
            raise InvalidInputError(
                f"{path}: {k} must lie in [{lo:g}, {hi:g}] (holds {a.min():g} to {a.max():g})"
            )
    for k, want in zip(("x_m", "y_m"), scn.area.centres(), strict=True):
        if not np.allclose(data[k], want, rtol=0, atol=1e-6 * max(1.0, float(np.ptp(want)))):
            raise InvalidInputError(f"{path}: {k} is not the pixel centres of its area")


MAP_ARRAYS = 10
"""(cells, H, W) float64 arrays a map build holds at its peak (its memory check)."""


def _cached(scn: Scenario) -> RadioMap | None:
    path = map_path(scn.digest())
    if not path.exists():
        return None
    try:
        rm = RadioMap.load(path)
    except Exception:  # a corrupt or partial entry is rebuilt, never trusted
        return None
    if rm.scenario.digest() != scn.digest():
        return None
    return rm


def _inside_cone(grid: MarchGrid) -> Weight:
    """The PE's share of a pattern: the cone weight in front of the antenna, 0 behind."""

    def weight(sx: np.ndarray, sy: np.ndarray, sz: np.ndarray) -> np.ndarray:
        return np.asarray(np.where(sz > 0, cone_weight(grid.sine_h, grid.sine_v, sx, sy), 0.0))

    return weight


def build_radio_map(scn: Scenario, *, cache: bool = True, progress: bool = False) -> RadioMap:
    """Builds (or loads from the cache) the radio map of ``scn`` with its engine:
    ``"pe"`` marches each cell's pattern inside its cone; ``"ray"`` traces two rays per
    cell and pixel; ``"hybrid"`` lets the PE carry each pattern inside its cone and the rays
    the rest (the PE needs a ``pec`` ground or none: over a soil the hybrid is
    the ray engine; a cell whose cone carries under 1% of its power at every pixel is not
    marched). ``RadioMap.pe_share`` records, per cell and pixel, the share of the
    power the PE carried."""
    if cache and (hit := _cached(scn)) is not None:
        return hit
    if scn.engine == "pe" and scn.ground in SOILS:
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
    use_pe = scn.engine in ("pe", "hybrid") and scn.ground not in SOILS
    grids = [march_grid(scn, site, cell) if use_pe else None for _, site, cell in jobs]
    cells = [(s, c) for _, s, c in jobs]
    timings: dict[str, float] = {}
    power = np.zeros((len(jobs), h, w))
    carried = np.zeros_like(power)
    if scn.engine != "pe":
        t_r = time.perf_counter()
        # What the PE would carry, by the rays: a cell whose cone carries under 1% of its
        # power at every pixel (the UAV above a down-tilted sector's cone) is not marched.
        weights = [None if g is None else _inside_cone(g) for g in grids]
        power, in_cone = ray_power(scn, cells, x_m, y_m, weights if use_pe else None)
        if in_cone is not None:
            carried = in_cone
            with np.errstate(divide="ignore", invalid="ignore"):
                frac = np.where(power > 0, carried / power, 0.0)
            for m in range(len(grids)):
                if grids[m] is None or float(frac[m].max()) < 0.01:
                    grids[m] = None
                    carried[m] = 0.0
        timings["rays"] = time.perf_counter() - t_r
    for grid in grids:
        if grid is not None:
            _core.check_memory(grid.bytes)
    pe_power = np.zeros_like(power)
    bar = None
    marches = sum(g is not None for g in grids)
    if progress and marches:
        from tqdm.auto import tqdm

        bar = tqdm(total=marches, desc="radio map (PE)", unit="cell")
    try:
        for m, ((_, site, cell), grid) in enumerate(zip(jobs, grids, strict=True)):
            if grid is not None:
                p = march_cell(scn, site, cell, grid, timings)
                t_r = time.perf_counter()
                pe_power[m] = resample(scn, site, grid, p, x_m, y_m)
                timings["resample"] = timings.get("resample", 0.0) + time.perf_counter() - t_r
                if bar is not None:
                    bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    if scn.engine == "pe":
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
    )
    if cache:
        store(rm, scn)
    return rm


def store(rm: RadioMap, scn: Scenario) -> None:
    """Keeps ``rm`` in the cache; a cache that cannot be written is a :class:`CacheWarning`
    (the map is the caller's all the same)."""
    try:
        path = map_path(scn.digest())
        rm.save(path)
    except OSError as err:
        warnings.warn(
            f"radio-map cache {cache_dir()} cannot be written ({err.strerror or err}); the map "
            "is not kept for next time (set RAINUAV_CACHE_DIR to a writable folder)",
            CacheWarning,
            stacklevel=3,
        )
