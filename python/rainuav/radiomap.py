"""Radio maps: received power per cell, the serving cell, SIR and SINR over the flight altitude.

For each cell (a beam of a site) the engine runs one PE march in the cell's own frame (range
along its azimuth, cross-range horizontal, height up), records the field at the flight
altitude after every step, and resamples it onto the map grid:

- **Grid** (PHYSICS.md section 4): the transverse steps resolve the largest angle at which the
  beam is within ``pe.dynamic_range_db`` of its peak, ``d <= lambda / (2 sin theta_max)``,
  separately across range and in height (where the tilt adds to the spread). The domain spans
  the beam's spread over the longest range that reaches the area (or the area's own
  cross-range extent, if smaller), plus the absorbing taper; in height, the ground (or a margin
  below) up to ``max(altitude, site) + top_margin_m``, plus the taper. Sizes are rounded up to
  products of 2, 3 and 5 for the FFTs. Energy that leaves through the top never returns over
  flat ground, so the top only needs to clear the flight altitude.
- **Power**: a cell radiating ``tx_power_dbm`` puts ``P |u|^2 / integral |u0|^2 dx dy`` W/m^2
  where the march field is ``u`` (power conservation of the march); an isotropic receiver
  collects that times ``lambda^2 / 4 pi``.
- **Weather**: homogeneous rain is one complex index; rain cells and rate maps become
  cross-range index profiles per step (``n`` tabulated against rain rate once per frequency
  and interpolated); buildings become obstacle heights per step.
- **Reach**: pixels behind a cell, beyond its march, or in its absorbing taper get no signal
  from it.

``sir_db`` and ``sinr_db`` are clipped to [-40, 60] dB: -40 where no cell reaches (and the
serving cell is -1), 60 where only one cell does. ``rss_dbm`` is -250 dBm where a cell does not
reach. Cells are computed one after another, each march using every core.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import math
import os
import sys
import time
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import _core, medium, pwe
from rainuav._io import write_atomic
from rainuav.env import SirField
from rainuav.errors import InvalidInputError
from rainuav.scenario import Cell, Scenario, Site

__all__ = ["RadioMap", "build_radio_map", "cache_dir", "main", "plan_cell", "sir_from_power"]

C0_M_S = 299_792_458.0
SIR_FLOOR_DB = -40.0
SIR_CEIL_DB = 60.0
RSS_FLOOR_DBM = -250.0
FORMAT_VERSION = 1


# --------------------------------------------------------------------------------------------
# SIR
# --------------------------------------------------------------------------------------------
def sir_from_power(
    power_mw: npt.NDArray[np.float64], noise_dbm: float
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Serving cell (argmax), SIR and SINR in dB from received powers (M, H, W) in mW
    (PHYSICS.md section 5), clipped to [SIR_FLOOR_DB, SIR_CEIL_DB]."""
    p = np.asarray(power_mw, dtype=np.float64)
    serving = np.argmax(p, axis=0)
    s = np.take_along_axis(p, serving[None], axis=0)[0]
    interference = p.sum(axis=0) - s
    # Sums of powers spanning many decades: recompute the rest exactly where it is tiny.
    interference = np.maximum(interference, 0.0)
    noise = 10.0 ** (noise_dbm / 10.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        sir = 10 * np.log10(s / interference)
        sinr = 10 * np.log10(s / (interference + noise))
    none = s <= 0
    sir = np.where(none, SIR_FLOOR_DB, np.where(interference <= 0, SIR_CEIL_DB, sir))
    sinr = np.where(none, SIR_FLOOR_DB, sinr)
    serving = np.where(none, -1, serving)
    return (
        serving.astype(np.int64),
        np.clip(sir, SIR_FLOOR_DB, SIR_CEIL_DB),
        np.clip(sinr, SIR_FLOOR_DB, SIR_CEIL_DB),
    )


# --------------------------------------------------------------------------------------------
# Per-cell grid
# --------------------------------------------------------------------------------------------
def _good_size(n: int) -> int:
    """Smallest even m >= n whose only prime factors are 2, 3 and 5."""
    m = max(8, int(n) + (int(n) % 2))
    while True:
        k = m
        for p in (2, 3, 5):
            while k % p == 0:
                k //= p
        if k == 1 and m % 2 == 0:
            return m
        m += 2 if m % 2 == 0 else 1


@dataclass(frozen=True)
class CellPlan:
    """How one cell's march is gridded and where its results land."""

    nx: int
    ny: int
    dx_m: float
    dy_m: float
    dz_m: float
    steps: int
    y0_m: float
    """Height of row 0 (0 with a ground)."""
    x_half_m: float
    """Half-width of the domain inside the absorber: pixels beyond get no signal."""
    azimuth_rad: float
    alt_row: int
    alt_frac: float
    """The flight altitude sits between rows alt_row and alt_row + 1 at this fraction."""
    bytes: int


def _angles(scn: Scenario, cell: Cell) -> tuple[float, float]:
    """(cross-range, height) largest angles present within the dynamic range, radians."""
    t = scn.pe.dynamic_range_db
    if cell.pattern is not None:
        g = np.asarray(cell.pattern.gain_db, dtype=float)
        keep = g >= -t
        az = np.abs(np.asarray(cell.pattern.azimuth_deg))[keep.any(axis=1)]
        el = np.asarray(cell.pattern.elevation_deg)[keep.any(axis=0)]
        ah = math.radians(max(float(az.max()), 0.5))
        av = math.radians(max(float(np.abs(el + cell.tilt_deg).max()), 0.5))
        return ah, min(av, math.radians(80))
    # Gaussian beam: power falls as exp(-ln2 (sin th / sin(bw/2))^2) (PHYSICS.md section 4).
    spread = math.sqrt(t * math.log(10) / (10 * math.log(2)))
    bh, bv = cell.beamwidths_deg
    sh = min(0.95, math.sin(math.radians(bh / 2)) * spread)
    sv = min(0.95, math.sin(math.radians(bv / 2)) * spread)
    ah = math.asin(sh)
    av = min(math.radians(80), math.asin(sv) + math.radians(abs(cell.tilt_deg)))
    return ah, av


def plan_cell(scn: Scenario, site: Site, cell: Cell) -> CellPlan | None:
    """The march grid of one cell, or None if the cell points away from the whole area."""
    a = scn.area
    lam = C0_M_S / scn.freq_hz
    ah, av = _angles(scn, cell)
    dx = lam / (2 * math.sin(ah))
    dy = lam / (2 * math.sin(av))
    dz = scn.pe.dz_m if scn.pe.dz_m is not None else min(a.resolution_m, 10.0)
    phi = math.radians(cell.azimuth_deg)
    cx = np.array([a.x_min_m, a.x_max_m, a.x_min_m, a.x_max_m]) - site.x_m
    cy = np.array([a.y_min_m, a.y_min_m, a.y_max_m, a.y_max_m]) - site.y_m
    z_c = cx * math.cos(phi) + cy * math.sin(phi)
    x_c = -cx * math.sin(phi) + cy * math.cos(phi)
    r_max = float(z_c.max())
    if r_max <= 0:
        return None
    steps = max(1, math.ceil(r_max / dz))
    r_max = steps * dz
    bh, _ = cell.beamwidths_deg
    w0 = math.sqrt(2 * math.log(2)) / (2 * math.pi / lam * math.sin(math.radians(bh / 2)))
    reach = r_max * math.tan(ah) + 3 * w0
    x_half = min(float(np.abs(x_c).max()), reach) + 4 * dx
    ab = scn.pe.absorber
    nx = _good_size(math.ceil(2 * x_half / (1 - 2 * ab) / dx))
    margin = scn.pe.top_margin_m or max(50.0, a.altitude_m / 2)
    top = max(a.altitude_m, site.height_m) + margin
    if scn.ground == "pec":
        ny = _good_size(math.ceil(top / (1 - ab) / dy))
        y0 = 0.0
    else:
        bottom = min(a.altitude_m, site.height_m) - margin
        ny = _good_size(math.ceil((top - bottom) / (1 - 2 * ab) / dy))
        y0 = (top + bottom) / 2 - (ny // 2) * dy
    fy = (a.altitude_m - y0) / dy
    alt_row = min(math.floor(fy), ny - 2)
    nbytes = int(
        8 * nx * ny * 3  # field, propagator table (<= 1/2), handed-over aperture
        + 2 * steps * nx * 8  # the two recorded rows
        + (steps * nx * 16 if scn.medium.kind in ("cells", "map") else 0)
        + (steps * nx * 8 if scn.buildings or scn.height_map_m is not None else 0)
    )
    return CellPlan(
        nx=nx,
        ny=ny,
        dx_m=dx,
        dy_m=dy,
        dz_m=dz,
        steps=steps,
        y0_m=y0,
        x_half_m=x_half,
        azimuth_rad=phi,
        alt_row=alt_row,
        alt_frac=fy - alt_row,
        bytes=nbytes,
    )


def _aperture(scn: Scenario, site: Site, cell: Cell, plan: CellPlan) -> np.ndarray:
    h = site.height_m - plan.y0_m
    if cell.pattern is not None:
        p = cell.pattern
        return pwe.pattern_source(
            plan.nx,
            plan.ny,
            plan.dx_m,
            plan.dy_m,
            freq_hz=scn.freq_hz,
            height_m=h,
            azimuth_deg=p.azimuth_deg,
            elevation_deg=p.elevation_deg,
            gain_db=p.gain_db,
            tilt_deg=cell.tilt_deg,
        )
    # Gaussian beam with separate horizontal and vertical beamwidths (PHYSICS.md section 4).
    k0 = 2 * math.pi * scn.freq_hz / C0_M_S
    bh, bv = cell.beamwidths_deg
    ax = k0 * math.sin(math.radians(bh / 2))
    ay = k0 * math.sin(math.radians(bv / 2))
    x = (np.arange(plan.nx) - plan.nx // 2) * plan.dx_m
    y = np.arange(plan.ny) * plan.dy_m - h
    gx = np.exp(-(ax**2) * x**2 / (2 * math.log(2)))
    gy = np.exp(-(ay**2) * y**2 / (2 * math.log(2))) * np.exp(
        -1j * k0 * math.sin(math.radians(cell.tilt_deg)) * y
    )
    return np.outer(gx, gy).astype(np.complex64)


def _step_points(site: Site, plan: CellPlan) -> tuple[np.ndarray, np.ndarray]:
    """Global (X, Y) of every (step, ix) sample of the march, each (steps, nx)."""
    z = (np.arange(plan.steps) + 1.0) * plan.dz_m
    x = (np.arange(plan.nx) - plan.nx // 2) * plan.dx_m
    c, s = math.cos(plan.azimuth_rad), math.sin(plan.azimuth_rad)
    gx = site.x_m + z[:, None] * c - x[None, :] * s
    gy = site.y_m + z[:, None] * s + x[None, :] * c
    return gx, gy


def rain_rate_at(scn: Scenario, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Rain rate (mm/h) of the scenario's medium at global points."""
    m = scn.medium
    if m.kind == "clear":
        return np.zeros(np.shape(x))
    if m.kind == "homogeneous":
        return np.full(np.shape(x), m.rain_rate_mm_h)
    if m.kind == "cells":
        r = np.full(np.shape(x), m.rain_rate_mm_h)
        for cell in m.cells:
            r = r + cell.rate(x, y)
        return np.minimum(r, 500.0)
    table = np.asarray(m.rate_map_mm_h, dtype=float)
    # Rates sit at pixel centres of the area and hold beyond the outermost centres: the same
    # interpolation as the SIR map the UAV flies through.
    a = scn.area
    return SirField(table, (a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m))(x, y)


def _medium_kwargs(scn: Scenario, site: Site, plan: CellPlan) -> dict[str, Any]:
    m = scn.medium
    opts = {
        "model": m.model,
        "polarization": scn.polarization,
        "shape": m.shape,
        "temperature_c": m.temperature_c,
        "wind_speed_m_s": m.wind_speed_m_s,
        "dsd": m.dsd,
    }
    if m.kind == "clear":
        return {}
    if m.kind == "homogeneous":
        return {"n": complex(medium.effective_index(scn.freq_hz, m.rain_rate_mm_h, **opts))}
    gx, gy = _step_points(site, plan)
    rates = rain_rate_at(scn, gx, gy)
    # n against rain rate, tabulated once for this frequency and interpolated (the index is
    # smooth in the rate; 513 points keep the interpolation error below 1e-6 relative).
    table_r = np.linspace(0.0, max(float(rates.max()), 1e-3), 513)
    table_n = medium.RainMedium(scn.freq_hz, **opts).refractive_index(table_r)
    n = np.interp(rates, table_r, table_n.real) + 1j * np.interp(rates, table_r, table_n.imag)
    return {"n_cross_range": n}


def _obstacles(scn: Scenario, site: Site, plan: CellPlan) -> np.ndarray | None:
    if not scn.buildings and scn.height_map_m is None:
        return None
    gx, gy = _step_points(site, plan)
    h = np.full(gx.shape, -1.0)
    if scn.height_map_m is not None:
        a = scn.area
        hm = np.asarray(scn.height_map_m, dtype=float)
        rows, cols = hm.shape
        j = np.floor((gx - a.x_min_m) / (a.x_max_m - a.x_min_m) * cols).astype(int)
        i = np.floor((gy - a.y_min_m) / (a.y_max_m - a.y_min_m) * rows).astype(int)
        inside = (i >= 0) & (i < rows) & (j >= 0) & (j < cols)
        val = hm[np.clip(i, 0, rows - 1), np.clip(j, 0, cols - 1)]
        h = np.where(inside & (val > 0), val - plan.y0_m, h)
    for b in scn.buildings:
        inside = (gx >= b.x0_m) & (gx <= b.x1_m) & (gy >= b.y0_m) & (gy <= b.y1_m)
        h = np.where(inside, np.maximum(h, b.height_m - plan.y0_m), h)
    return h


def march_cell(
    scn: Scenario, site: Site, cell: Cell, plan: CellPlan, timings: dict[str, float] | None = None
) -> np.ndarray:
    """Received power (mW, isotropic receiver) at the flight altitude, (steps, nx). Adds the
    seconds spent on the source, the medium and obstacle screens, and the march to
    ``timings``."""
    t = {} if timings is None else timings
    _core.check_memory(plan.bytes)
    t0 = time.perf_counter()
    u0 = _aperture(scn, site, cell, plan)
    p0 = float(np.sum(np.abs(u0.astype(np.complex128)) ** 2)) * plan.dx_m * plan.dy_m
    ground = None if scn.ground == "none" else f"pec-{scn.polarization}"
    t1 = time.perf_counter()
    screens = {**_medium_kwargs(scn, site, plan), "obstacles": _obstacles(scn, site, plan)}
    t2 = time.perf_counter()
    out = pwe.march(
        u0,
        dx_m=plan.dx_m,
        dy_m=plan.dy_m,
        dz_m=plan.dz_m,
        steps=plan.steps,
        freq_hz=scn.freq_hz,
        propagator=scn.pe.propagator,
        ground=ground,
        absorber=scn.pe.absorber,
        record_rows=[plan.alt_row, plan.alt_row + 1],
        **screens,
    )
    t3 = time.perf_counter()
    for k, v in (("source", t1 - t0), ("screens", t2 - t1), ("march", t3 - t2)):
        t[k] = t.get(k, 0.0) + v
    del u0
    frac = plan.alt_frac
    u = (1 - frac) * out.rows[0].astype(np.complex128) + frac * out.rows[1]
    lam = C0_M_S / scn.freq_hz
    pt_mw = 10 ** (cell.tx_power_dbm / 10)
    return pt_mw * np.abs(u) ** 2 / p0 * lam**2 / (4 * math.pi)


def resample(
    scn: Scenario,
    site: Site,
    plan: CellPlan,
    power: np.ndarray,
    x_m: np.ndarray,
    y_m: np.ndarray,
) -> np.ndarray:
    """Bilinear resampling of a cell's (steps, nx) power onto the map grid (H, W); zero where
    the cell's march does not reach."""
    gx, gy = np.meshgrid(x_m - site.x_m, y_m - site.y_m)
    c, s = math.cos(plan.azimuth_rad), math.sin(plan.azimuth_rad)
    z = gx * c + gy * s
    xc = -gx * s + gy * c
    fz = np.clip(z / plan.dz_m - 1.0, 0.0, None)
    fx = xc / plan.dx_m + plan.nx // 2
    ok = (z >= 0) & (fz <= plan.steps - 1) & (np.abs(xc) <= plan.x_half_m)
    fz = np.clip(fz, 0, plan.steps - 1)
    fx = np.clip(fx, 0, plan.nx - 1)
    k0 = np.minimum(np.floor(fz).astype(int), max(plan.steps - 2, 0))
    i0 = np.minimum(np.floor(fx).astype(int), plan.nx - 2)
    tz, tx = fz - k0, fx - i0
    k1 = np.minimum(k0 + 1, plan.steps - 1)
    v = (
        power[k0, i0] * (1 - tz) * (1 - tx)
        + power[k0, i0 + 1] * (1 - tz) * tx
        + power[k1, i0] * tz * (1 - tx)
        + power[k1, i0 + 1] * tz * tx
    )
    return np.where(ok, v, 0.0)


# --------------------------------------------------------------------------------------------
# The map
# --------------------------------------------------------------------------------------------
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
    build_seconds: float = 0.0
    """Wall time of the build (0 when loaded from the cache)."""
    timings: dict[str, float] = dataclasses.field(default_factory=dict)
    """Seconds per phase of the build: source, screens, march, resample (empty if cached)."""

    _ARRAYS = ("x_m", "y_m", "rss_dbm", "serving_cell", "sir_db", "sinr_db", "cell_site")

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
        if missing or int(data.get("format_version", -1)) != FORMAT_VERSION:
            raise InvalidInputError(f"{path}: not a rainuav radio map (missing {missing})")
        scn = Scenario.from_toml_string(str(data["scenario_toml"]))
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
        )
        h, w = scn.area.shape
        if out.rss_dbm.shape[1:] != (h, w) or out.sir_db.shape != (h, w):
            raise InvalidInputError(f"{path}: array shapes do not match its scenario")
        return out

    def plot(self, kind: str = "sir", cell: int | None = None, ax: Any = None) -> Any:
        """Draws the map in dB (``kind`` 'sir', 'sinr' or 'rss'; ``cell`` selects one cell's
        RSS, default the strongest) with the sites marked; returns the matplotlib Axes."""
        import matplotlib.pyplot as plt

        if kind not in ("sir", "sinr", "rss"):
            raise InvalidInputError(f"kind must be 'sir', 'sinr' or 'rss' (got {kind!r})")
        if ax is None:
            _, ax = plt.subplots(figsize=(6, 5))
        if kind == "rss":
            if cell is None:
                data, label = self.rss_dbm.max(axis=0), "RSS of the strongest cell [dBm]"
            else:
                if not 0 <= cell < len(self.rss_dbm):
                    raise InvalidInputError(f"cell must be within 0..{len(self.rss_dbm) - 1}")
                data, label = self.rss_dbm[cell], f"RSS of cell {cell} [dBm]"
            finite = data[data > RSS_FLOOR_DBM]
            vmin = float(np.percentile(finite, 2)) if finite.size else None
            im = ax.imshow(data, origin="lower", extent=self.extent_m, cmap="viridis", vmin=vmin)
        else:
            data = self.sir_db if kind == "sir" else self.sinr_db
            label = f"{kind.upper()} [dB]"
            im = ax.imshow(
                data, origin="lower", extent=self.extent_m, cmap="RdYlGn", vmin=-10, vmax=30
            )
        plt.colorbar(im, ax=ax, label=label)
        xs = [s.x_m for s in self.scenario.sites]
        ys = [s.y_m for s in self.scenario.sites]
        ax.plot(xs, ys, "k^", markersize=7, markerfacecolor="white", label="sites")
        for s in self.scenario.sites:
            for c in s.cells:
                phi = math.radians(c.azimuth_deg)
                ax.annotate(
                    "",
                    xy=(s.x_m + 120 * math.cos(phi), s.y_m + 120 * math.sin(phi)),
                    xytext=(s.x_m, s.y_m),
                    arrowprops={"arrowstyle": "->", "lw": 1},
                )
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(f"{self.scenario.name}: {label}, {self.altitude_m:g} m")
        return ax

    def coverage(self, sir_min_db: float = 10.0) -> float:
        """Share of the area with SIR >= sir_min_db."""
        return float(np.mean(self.sir_db >= sir_min_db))


def cache_dir() -> Path:
    """Where maps are cached: $RAINUAV_CACHE_DIR, else $XDG_CACHE_HOME/rainuav, else
    ~/.cache/rainuav; maps live in its radiomaps/ folder."""
    env = os.environ.get("RAINUAV_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "rainuav"


def _cached(scn: Scenario) -> RadioMap | None:
    path = cache_dir() / "radiomaps" / f"{scn.digest()}.npz"
    if not path.exists():
        return None
    try:
        rm = RadioMap.load(path)
    except Exception:  # a corrupt or partial entry is rebuilt, never trusted
        return None
    if rm.scenario.digest() != scn.digest():
        return None
    return rm


def build_radio_map(scn: Scenario, *, cache: bool = True, progress: bool = False) -> RadioMap:
    """Builds (or loads from the cache) the radio map of ``scn``."""
    if cache and (hit := _cached(scn)) is not None:
        return hit
    t0 = time.perf_counter()
    a = scn.area
    h, w = a.shape
    x_m = a.x_min_m + (np.arange(w) + 0.5) * (a.x_max_m - a.x_min_m) / w
    y_m = a.y_min_m + (np.arange(h) + 0.5) * (a.y_max_m - a.y_min_m) / h
    jobs = [(i, site, cell) for i, site in enumerate(scn.sites) for cell in site.cells]
    plans = [plan_cell(scn, site, cell) for _, site, cell in jobs]
    for plan in plans:
        if plan is not None:
            _core.check_memory(plan.bytes)
    power = np.zeros((len(jobs), h, w))
    timings: dict[str, float] = {}
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(jobs), desc="radio map", unit="cell")
    try:
        for m, ((_, site, cell), plan) in enumerate(zip(jobs, plans, strict=True)):
            if plan is not None:
                p = march_cell(scn, site, cell, plan, timings)
                t_r = time.perf_counter()
                power[m] = resample(scn, site, plan, p, x_m, y_m)
                timings["resample"] = timings.get("resample", 0.0) + time.perf_counter() - t_r
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    serving, sir, sinr = sir_from_power(power, scn.noise_dbm)
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
        build_seconds=time.perf_counter() - t0,
        timings=timings,
    )
    if cache:
        rm.save(cache_dir() / "radiomaps" / f"{scn.digest()}.npz")
    return rm


# --------------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------------
def main(argv: Sequence[str] | None = None) -> int:
    """``python -m rainuav.radiomap --scenario paper --rain-rate 25 --out maps/``."""
    from rainuav import scenarios

    ap = argparse.ArgumentParser(
        prog="python -m rainuav.radiomap", description="Build a radio map and write npz + PNGs."
    )
    ap.add_argument("--scenario", choices=sorted(scenarios.PRESETS), default="paper")
    ap.add_argument("--config", type=Path, help="a scenario TOML file (overrides --scenario)")
    ap.add_argument("--rain-rate", type=float, default=None, help="homogeneous rain, mm/h")
    ap.add_argument("--out", type=Path, default=Path("maps"))
    ap.add_argument("--no-cache", action="store_true")
    args = ap.parse_args(argv)
    try:
        if args.config is not None:
            scn = Scenario.from_toml(args.config)
            if args.rain_rate is not None:
                scn = scenarios.with_rain(scn, args.rain_rate)
        else:
            kw = {} if args.rain_rate is None else {"rain_rate_mm_h": args.rain_rate}
            scn = scenarios.PRESETS[args.scenario](**kw)
        rm = scn.radio_map(cache=not args.no_cache, progress=True)
    except InvalidInputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    npz = rm.save(args.out / "radiomap.npz")
    pngs = []
    for kind in ("rss", "sir"):
        fig, ax = plt.subplots(figsize=(6.5, 5.2))
        rm.plot(kind, ax=ax)
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, dpi=110, format="png")
        plt.close(fig)
        pngs.append(
            write_atomic(args.out / f"{kind}.png", lambda t, b=buf: t.write_bytes(b.getvalue()))
        )
    split = ", ".join(f"{k} {v:.1f} s" for k, v in rm.timings.items()) or "from the cache"
    print(
        f"{scn.name}: {len(rm.rss_dbm)} cells, SIR >= 10 dB on {100 * rm.coverage():.1f}% "
        f"of the area; built in {rm.build_seconds:.1f} s ({split})"
    )
    print(f"wrote {npz}, {pngs[0]}, {pngs[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
