"""The PE engine: one split-step march per cell, recorded at the flight altitude.

Each cell runs one march in its own frame (range along its azimuth, cross-range horizontal, height
up; gridded by [`rainuav.radio.engines.grid`][rainuav.radio.engines.grid]), records the field at the
flight altitude after every step, and is resampled onto the map grid:

- **Source**: the aperture whose angular spectrum radiates the cell's pattern (any antenna,
  [`rainuav.radio.scene.cell`][rainuav.radio.scene.cell]) times the cone weight of its grid
  ([`cone_weight()`][rainuav.radio.engines.grid.cone_weight]): the PE carries the pattern inside its
  cone, the rays the rest.
- **Power**: a cell radiating ``tx_power_dbm`` puts ``P s |u|^2 / integral |u0|^2 dx dy``
  W/m^2 where the march field is ``u`` (power conservation of the march) and ``s`` the share
  of the power inside the cone; an isotropic receiver collects that times
  ``lambda^2 / 4 pi``. A map pixel gets the mean over a pixel-sized box of the march.
- **Weather**: homogeneous rain is one complex index; rain cells and rate maps become
  cross-range index profiles per step (``n`` tabulated against rain rate once per frequency
  and interpolated); buildings become obstacle heights per step.
- **Terrain** ([`rainuav.radio.scene.terrain`][rainuav.radio.scene.terrain]): the grid's floor is
  the area's lowest ground (a PEC plane, by images); the terrain above it zeroes the field below its
  surface at every step (staircase masking: exact for horizontal polarisation, whose field vanishes
  on a conductor; for vertical polarisation the surface should be an impedance boundary, which the
  mask approximates), obstacles stand on it, and each column records the two rows around the UAV's
  own height over the ground there.
- **Reach**: pixels behind a cell, beyond its march, or in its absorbing taper get no signal
  from it.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import _core, pwe
from rainuav._sampling import bilinear
from rainuav.errors import InvalidInputError
from rainuav.radio.engines.grid import C0_M_S, MarchGrid, cone_weight
from rainuav.radio.scene.buildings import scenario_buildings
from rainuav.radio.scene.cell import Cell, gain_linear
from rainuav.radio.scene.scenario import Scenario, Site
from rainuav.radio.scene.stochastic import field_rates
from rainuav.radio.scene.terrain import (
    flight_heights_at,
    floor_m,
    site_height_above_floor,
    surface_at,
)

__all__ = ["level_rows", "march_cell", "march_cell_levels", "rain_rate_at", "resample"]


def _aperture(scn: Scenario, site: Site, cell: Cell, grid: MarchGrid) -> tuple[np.ndarray, float]:
    """The cell's aperture carrying ``pattern x cone_weight`` and the share of the transmitted
    power it carries (``(1 / 4 pi) integral G w dOmega``).

    The angular spectrum at direction cosines ``(s_x, s_y)`` is ``sqrt(G w) / s_z`` (``s_z``
    along range): a plane-wave spectrum ``U`` radiates ``k0^2 s_z^2 |U|^2 / (2 pi r)^2`` in
    its direction, so this radiates ``G w`` up to one constant, and
    ``integral |U|^2 dk = k0^2 integral G w / s_z dOmega`` fixes the constant."""
    h = site_height_above_floor(scn, site.x_m, site.y_m, site.height_m) - grid.y0_m
    k0 = 2 * math.pi * scn.freq_hz / C0_M_S
    kx = 2 * math.pi * np.fft.fftfreq(grid.nx, grid.dx_m)
    ky = 2 * math.pi * np.fft.fftfreq(grid.ny, grid.dy_m)
    # A wave leaving at positive angles is exp(-j k0 sin(angle) y) (docs/physics.md convention):
    # the inverse FFT holds direction s at wavenumber -k0 s.
    sx = (-kx / k0)[:, None]
    sy = (-ky / k0)[None, :]
    cz2 = 1.0 - sx**2 - sy**2
    ok = cz2 > 1e-6
    cz = np.sqrt(np.where(ok, cz2, 1.0))
    el = np.degrees(np.arcsin(np.clip(sy, -1, 1)))
    az = np.degrees(np.arctan2(sx, cz))
    g = gain_linear(cell, az + cell.azimuth_deg, el)
    power = np.where(ok, g * cone_weight(grid.sine_h, grid.sine_v, sx, sy) / cz2, 0.0)
    dk = (2 * math.pi) ** 2 / (grid.nx * grid.dx_m * grid.ny * grid.dy_m)
    share = float(power.sum() * dk / (4 * math.pi * k0**2))
    shift = np.exp(-1j * kx[:, None] * (grid.nx // 2) * grid.dx_m) * np.exp(-1j * ky[None, :] * h)
    u = np.fft.ifft2(np.sqrt(power) * shift)
    peak = float(np.abs(u).max())
    if peak == 0 or share == 0:
        return np.zeros((grid.nx, grid.ny), np.complex64), 0.0
    return np.ascontiguousarray((u / peak).astype(np.complex64)), share


def _step_points(site: Site, grid: MarchGrid) -> tuple[np.ndarray, np.ndarray]:
    """Global (X, Y) of every (step, ix) sample of the march, each (steps, nx)."""
    z = (np.arange(grid.steps) + 1.0) * grid.dz_m
    x = (np.arange(grid.nx) - grid.nx // 2) * grid.dx_m
    c, s = math.cos(grid.azimuth_rad), math.sin(grid.azimuth_rad)
    gx = site.x_m + z[:, None] * c - x[None, :] * s
    gy = site.y_m + z[:, None] * s + x[None, :] * c
    return gx, gy


def rain_rate_at(scn: Scenario, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The rain rate of the scenario's weather at global points, mm/h.

    A weather in time is read at its time 0, as for moving rain cells.

    Args:
        scn: The scenario.
        x: East, m.
        y: North, m.

    Returns:
        Rates, mm/h.
    """
    m = scn.medium
    if m.kind == "map" and m.rate_times_s is not None:
        m = m.at(0.0)
    if m.kind == "clear":
        return np.zeros(np.shape(x))
    if m.kind == "homogeneous":
        return np.full(np.shape(x), m.rain_rate_mm_h)
    if m.kind == "field" and m.field is not None:
        return field_rates(m.field, x, y)
    if m.kind == "cells":
        r = np.full(np.shape(x), m.rain_rate_mm_h)
        for cell in m.cells:
            r = r + cell.rate(x, y)
        return np.minimum(r, 500.0)
    table = np.asarray(m.rate_map_mm_h, dtype=float)
    # Rates sit at pixel centres of the area and hold beyond the outermost centres: the same
    # interpolation as the SIR map the UAV flies through.
    a = scn.area
    return bilinear(table, (a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m), x, y)


def _medium_kwargs(scn: Scenario, site: Site, grid: MarchGrid) -> dict[str, Any]:
    m = scn.medium
    if m.kind == "clear":
        return {}
    rm = m.rain_medium(scn.freq_hz, scn.polarization)
    if m.kind == "homogeneous":
        return {"n": complex(rm.refractive_index(m.rain_rate_mm_h))}
    gx, gy = _step_points(site, grid)
    rates = rain_rate_at(scn, gx, gy)
    # n against rain rate, tabulated once for this frequency and interpolated (the index is
    # smooth in the rate; 513 points keep the interpolation error below 1e-6 relative).
    table_r = np.linspace(0.0, max(float(rates.max()), 1e-3), 513)
    table_n = rm.refractive_index(table_r)
    n = np.interp(rates, table_r, table_n.real) + 1j * np.interp(rates, table_r, table_n.imag)
    return {"n_cross_range": n}


def _obstacles(scn: Scenario, site: Site, grid: MarchGrid) -> np.ndarray | None:
    """The heights (steps, nx) under which each step zeroes the field: obstacles, and over
    terrain the ground above the grid's floor (a staircase; -1: nothing)."""
    if (
        not scn.buildings
        and scn.footprints is None
        and scn.height_map_m is None
        and scn.terrain is None
    ):
        return None
    gx, gy = _step_points(site, grid)
    h = np.full(gx.shape, -1.0)
    base = np.zeros(gx.shape)
    if scn.terrain is not None:
        base = surface_at(scn, gx, gy) - floor_m(scn)
        # Ground within half a row of the floor is the floor itself (the PEC plane).
        h = np.where(base >= 0.5 * grid.dy_m, base - grid.y0_m, h)
    if scn.height_map_m is not None:
        a = scn.area
        hm = np.asarray(scn.height_map_m, dtype=float)
        rows, cols = hm.shape
        j = np.floor((gx - a.x_min_m) / (a.x_max_m - a.x_min_m) * cols).astype(int)
        i = np.floor((gy - a.y_min_m) / (a.y_max_m - a.y_min_m) * rows).astype(int)
        inside = (i >= 0) & (i < rows) & (j >= 0) & (j < cols)
        val = hm[np.clip(i, 0, rows - 1), np.clip(j, 0, cols - 1)]
        h = np.where(inside & (val > 0), np.maximum(h, base + val - grid.y0_m), h)
    bld = scenario_buildings(scn)
    if bld is not None:
        top = bld.prisms.height_at(
            np.ascontiguousarray(gx, dtype=float).ravel(),
            np.ascontiguousarray(gy, dtype=float).ravel(),
        ).reshape(gx.shape)
        h = np.where(top > 0, np.maximum(h, base + top - grid.y0_m), h)
    return None if h.max() < 0 else h


def _receiver_rows(scn: Scenario, site: Site, grid: MarchGrid) -> tuple[np.ndarray, np.ndarray]:
    """Over terrain: per (step, ix) the row below the UAV's height and the fraction to the
    next (the receiver surface follows the ground, or sits at a height above sea level)."""
    gx, gy = _step_points(site, grid)
    fy = (flight_heights_at(scn, gx, gy) - floor_m(scn) - grid.y0_m) / grid.dy_m
    row = np.clip(np.floor(fy), 0, grid.ny - 2)
    return row.astype(np.int64), np.clip(fy - row, 0.0, 1.0)


def march_cell(
    scn: Scenario, site: Site, cell: Cell, grid: MarchGrid, timings: dict[str, float] | None = None
) -> np.ndarray:
    """The received power at the flight altitude of one cell's march (mW, isotropic receiver).

    Args:
        scn: The scenario.
        site: The cell's site.
        cell: The cell.
        grid: Its march grid.
        timings: Seconds added by part (the source, the medium and obstacle screens, the march).

    Returns:
        (steps, nx) mW.
    """
    rows, frac, offsets = [grid.alt_row, grid.alt_row + 1], grid.alt_frac, None
    if scn.terrain is not None:
        offsets, frac_rows = _receiver_rows(scn, site, grid)
        if np.all(offsets == offsets.flat[0]) and np.ptp(frac_rows) < 1e-9:
            # A flat receiver surface: the two rows of every column, as over flat ground.
            rows, frac = [int(offsets.flat[0]), int(offsets.flat[0]) + 1], float(frac_rows.flat[0])
            offsets = None
        else:
            rows, frac = [0, 1], frac_rows
    return _marched_power(scn, site, cell, grid, rows, [frac], offsets, timings)[0]


def level_rows(grid: MarchGrid, heights_m: npt.ArrayLike) -> tuple[list[int], list[float]]:
    """The rows around each height above the grid's floor, and the fraction to the upper one.

    Flat ground: two rows a height.

    Args:
        grid: The march grid.
        heights_m: The heights, m.

    Returns:
        `(rows, fracs)`.

    Raises:
        InvalidInputError: A height below the grid.
    """
    rows, fracs = [], []
    for z in np.asarray(heights_m, dtype=float).reshape(-1):
        fy = (z - grid.y0_m) / grid.dy_m
        r = min(math.floor(fy), grid.ny - 2)
        if r < 0:
            raise InvalidInputError(f"height {z:g} m lies below the march grid of a cell")
        rows += [r, r + 1]
        fracs.append(fy - r)
    return rows, fracs


def march_cell_levels(
    scn: Scenario,
    site: Site,
    cell: Cell,
    grid: MarchGrid,
    heights_m: npt.ArrayLike,
    timings: dict[str, float] | None = None,
) -> np.ndarray:
    """The received power at several heights over flat ground from one march.

    The rows around every height are recorded after each step; the grid must reach the highest.

    Args:
        scn: The scenario.
        site: The cell's site.
        cell: The cell.
        grid: Its march grid.
        heights_m: The heights, m.
        timings: Seconds added by part.

    Returns:
        (L, steps, nx) mW.

    Raises:
        InvalidInputError: Terrain under the march (one march for several heights needs flat
            ground).
    """
    if scn.terrain is not None:
        raise InvalidInputError("one march for several heights needs flat ground (no terrain)")
    rows, fracs = level_rows(grid, heights_m)
    return _marched_power(scn, site, cell, grid, rows, fracs, None, timings)


def _marched_power(
    scn: Scenario,
    site: Site,
    cell: Cell,
    grid: MarchGrid,
    rows: list[int],
    fracs: list[Any],
    offsets: np.ndarray | None,
    timings: dict[str, float] | None,
) -> np.ndarray:
    """The march of one cell recording ``rows`` (pairs, one a receiver height, each with the
    fraction to its upper row; ``offsets``: per (step, ix) row offsets of a receiver surface
    over terrain): received power (mW), (pairs, steps, nx)."""
    t = {} if timings is None else timings
    _core.check_memory(grid.bytes + 2 * len(fracs) * grid.steps * grid.nx * 8)
    t0 = time.perf_counter()
    u0, share = _aperture(scn, site, cell, grid)
    if share == 0.0:
        return np.zeros((len(fracs), grid.steps, grid.nx))
    p0 = float(np.sum(np.abs(u0.astype(np.complex128)) ** 2)) * grid.dx_m * grid.dy_m
    ground = None if scn.ground == "none" else f"pec-{scn.polarization}"
    t1 = time.perf_counter()
    screens = {**_medium_kwargs(scn, site, grid), "obstacles": _obstacles(scn, site, grid)}
    if offsets is not None:
        screens["record_offsets"] = offsets
    t2 = time.perf_counter()
    out = pwe.march(
        u0,
        dx_m=grid.dx_m,
        dy_m=grid.dy_m,
        dz_m=grid.dz_m,
        steps=grid.steps,
        freq_hz=scn.freq_hz,
        propagator=scn.pe.propagator,
        ground=ground,
        absorber=scn.pe.absorber,
        x_absorber_every=grid.x_absorber_every,
        record_rows=rows,
        **screens,
    )
    t3 = time.perf_counter()
    for k, v in (("source", t1 - t0), ("screens", t2 - t1), ("march", t3 - t2)):
        t[k] = t.get(k, 0.0) + v
    del u0
    lam = C0_M_S / scn.freq_hz
    pt_mw = 10 ** (cell.tx_power_dbm / 10)
    out_p = np.empty((len(fracs), grid.steps, grid.nx))
    for k, frac in enumerate(fracs):
        # Interpolate power, not the complex field, between the two rows around the
        # altitude: near the cone's edge the phase turns by up to pi per row, and a complex
        # average would cancel (it cost 1.6 dB at 4 degrees of elevation in an 8 degree cone).
        lo, hi = out.rows[2 * k], out.rows[2 * k + 1]
        u2 = (1 - frac) * np.abs(lo.astype(np.complex128)) ** 2 + frac * np.abs(
            hi.astype(np.complex128)
        ) ** 2
        out_p[k] = pt_mw * share * u2 / p0 * lam**2 / (4 * math.pi)
    return out_p


def _box(p: np.ndarray, n: int, axis: int) -> np.ndarray:
    """Moving mean of ``n`` samples along ``axis`` (the window shrinks at the ends)."""
    if n <= 1:
        return p
    c = np.cumsum(np.moveaxis(p, axis, 0), axis=0)
    c = np.concatenate([np.zeros((1, *c.shape[1:])), c])
    m = c.shape[0] - 1
    i = np.arange(m)
    lo = np.clip(i - n // 2, 0, m)
    hi = np.clip(i - n // 2 + n, 0, m)
    out = (c[hi] - c[lo]) / (hi - lo)[(...,) + (None,) * (c.ndim - 1)]
    return np.moveaxis(out, 0, axis)


def resample(
    scn: Scenario,
    site: Site,
    grid: MarchGrid,
    power: np.ndarray,
    x_m: np.ndarray,
    y_m: np.ndarray,
) -> np.ndarray:
    """A cell's march power onto the map's pixels.

    The mean over a pixel's length along range (the ground-reflection fringes run across range: they
    are averaged, not aliased), sampled bilinearly at the pixel centres; zero where the cell's march
    does not reach. Across range the pattern is sampled at the centre, as the rays do (a box there
    would raise the steep flanks of a beam by up to 1.5 dB over the rays' point value).

    Args:
        scn: The scenario.
        site: The cell's site.
        grid: Its march grid.
        power: The march's power (steps, nx), mW.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.

    Returns:
        (H, W) mW.
    """
    power = _box(power, round(scn.area.resolution_m / grid.dz_m), 0)
    gx, gy = np.meshgrid(x_m - site.x_m, y_m - site.y_m)
    c, s = math.cos(grid.azimuth_rad), math.sin(grid.azimuth_rad)
    z = gx * c + gy * s
    xc = -gx * s + gy * c
    fz = np.clip(z / grid.dz_m - 1.0, 0.0, None)
    fx = xc / grid.dx_m + grid.nx // 2
    ok = (z >= 0) & (fz <= grid.steps - 1) & (np.abs(xc) <= grid.x_half_m)
    fz = np.clip(fz, 0, grid.steps - 1)
    fx = np.clip(fx, 0, grid.nx - 1)
    k0 = np.minimum(np.floor(fz).astype(int), max(grid.steps - 2, 0))
    i0 = np.minimum(np.floor(fx).astype(int), grid.nx - 2)
    tz, tx = fz - k0, fx - i0
    k1 = np.minimum(k0 + 1, grid.steps - 1)
    v = (
        power[k0, i0] * (1 - tz) * (1 - tx)
        + power[k0, i0 + 1] * (1 - tz) * tx
        + power[k1, i0] * tz * (1 - tx)
        + power[k1, i0 + 1] * tz * tx
    )
    return np.where(ok, v, 0.0)
