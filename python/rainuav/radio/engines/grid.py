"""The grid of one cell's PE march and the cone it carries ([physics reference, section
4][4-the-split-step-parabolic-equation]).

The cone: the widest directions (as direction cosines across range and in height) where the
cell's pattern is within ``pe.dynamic_range_db`` of its peak, narrowed until the march fits
``pe.budget_gpoints``. The transverse steps resolve it, ``d = lambda / (2 sin theta_max)``;
the PE carries the pattern fully inside ``CONE_FULL`` of the cone and tapers it to zero at
the edge ([`cone_weight()`][rainuav.radio.engines.grid.cone_weight]); the rays carry the rest in the
hybrid engine.

The domain spans the beam's spread over the longest range that reaches the area (or the area's own
cross-range extent, if smaller), plus the absorbing taper; in height, the ground (or a margin below)
up to ``max(altitude, site) + top_margin_m``, plus the taper. Over terrain
([`rainuav.radio.scene.terrain`][rainuav.radio.scene.terrain]) heights count from the lowest ground
of the area: the grid's PEC floor lies there, the terrain above it is a staircase of obstacles, and
the top clears the highest flight height over the area. Sizes are rounded up to products of 2, 3 and
5 for the FFTs. Energy that leaves through the top never returns over flat ground, so the top only
needs to clear the flight altitude."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.radio.scene.cell import Cell, pattern_by_key
from rainuav.radio.scene.scenario import Scenario, Site
from rainuav.radio.scene.terrain import flight_heights, floor_m, site_height_above_floor

__all__ = ["C0_M_S", "CONE_FULL", "MarchGrid", "cone_weight", "march_grid"]

C0_M_S = 299_792_458.0
"""Speed of light, m/s."""


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
class MarchGrid:
    """How one cell's PE march is gridded and where its results land on the map."""

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
    sine_h: float
    """Sine of the cone's half-width across range (the grid's Nyquist angle)."""
    sine_v: float
    """Sine of the cone's half-width in height."""
    gpoints: float
    """Size of the march, 1e9 grid-point steps (nx x ny x steps)."""
    x_absorber_every: int = 1
    """Steps between applications of the lateral window where the medium is uniform
    (``pwe.march``'s ``x_absorber_every``): the most that keep the widest angle the grid
    carries within an eighth of an absorbing strip between windows (at most 16)."""


CONE_FULL = 0.6
"""The PE carries a pattern fully out to this fraction of its cone's sine and tapers it (cos^2) to
zero at the cone's edge; the rays carry the rest
([`cone_weight()`][rainuav.radio.engines.grid.cone_weight])."""
_MIN_SINE = math.sin(math.radians(0.5))


@functools.lru_cache(maxsize=64)
def _dynamic_range_cone(key: tuple[Any, ...], tilt_deg: float, dr_db: float) -> tuple[float, float]:
    """(cross-range, height) sines of the widest directions where the pattern is within
    ``dr_db`` of its peak, sampled on a grid of direction cosines (forward half-space)."""
    pattern = pattern_by_key(key)
    s = np.linspace(-0.98, 0.98, 981)
    sx, sy = np.meshgrid(s, s, indexing="ij")
    el = np.degrees(np.arcsin(sy))
    az = np.degrees(np.arcsin(np.clip(sx / np.sqrt(1 - sy**2), -1, 1)))
    g = pattern.gain_dbi(az, np.clip(el - tilt_deg, -90, 90))
    # A flat sidelobe floor (the pattern's minimum) is never part of the cone; a pattern flat
    # over the whole half-space (isotropic) is all peak: the widest cone.
    if g.max() - g.min() < 1e-3:
        return 0.95, 0.95
    keep = g > max(g.max() - dr_db, g.min() + 1e-3)
    # One sample of margin: the edge sample still lies inside the range.
    step = s[1] - s[0]
    sh = float(np.abs(sx[keep]).max()) + step
    sv = float(np.abs(sy[keep]).max()) + step
    return min(max(sh, _MIN_SINE), 0.95), min(max(sv, _MIN_SINE), 0.95)


def cone_weight(sine_h: float, sine_v: float, sx: npt.ArrayLike, sy: npt.ArrayLike) -> Any:
    """The share of a pattern the PE carries at direction cosines.

    1 inside `CONE_FULL` of the cone, cos^2 down to 0 at its edge, 0 beyond; separable.

    Args:
        sine_h: The cone's half width across, as a sine.
        sine_v: Its half height, as a sine.
        sx: Direction cosines across.
        sy: Direction cosines up.

    Returns:
        The share, of the broadcast shape.
    """

    def one(t: npt.ArrayLike) -> Any:
        u = np.clip((np.abs(t) - CONE_FULL) / (1 - CONE_FULL), 0.0, 1.0)
        return np.cos(0.5 * np.pi * u) ** 2

    return one(np.asarray(sx) / sine_h) * one(np.asarray(sy) / sine_v)


def march_grid(scn: Scenario, site: Site, cell: Cell) -> MarchGrid | None:
    """The march grid of one cell, or None if the cell points away from the whole area.

    The cone is the pattern's `pe.dynamic_range_db` cone, narrowed in steps of 15% until the march
    fits `pe.budget_gpoints`.

    Args:
        scn: The scenario.
        site: The cell's site.
        cell: The cell.

    Returns:
        The grid, or None.

    Raises:
        InvalidInputError: A budget too small for a 0.5 degree cone.
    """
    sh, sv = _dynamic_range_cone(cell.key(), cell.tilt_deg, scn.pe.dynamic_range_db)
    while True:
        grid = _grid(scn, site, cell, sh, sv)
        if grid is None or grid.gpoints <= scn.pe.budget_gpoints:
            return grid
        if max(sh, sv) <= _MIN_SINE:
            raise InvalidInputError(
                f"pe.budget_gpoints = {scn.pe.budget_gpoints:g} is too small to carry any "
                f"cone (a 0.5 degree cone needs {grid.gpoints:.3g}); raise it "
                "(allowed 0.001..1000) or use engine = 'ray'"
            )
        sh, sv = max(sh * 0.85, _MIN_SINE), max(sv * 0.85, _MIN_SINE)


def _grid(scn: Scenario, site: Site, cell: Cell, sh: float, sv: float) -> MarchGrid | None:
    a = scn.area
    lam = C0_M_S / scn.freq_hz
    ah = math.asin(sh)
    dx = lam / (2 * sh)
    dy = lam / (2 * sv)
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
    # The aperture is about half a wavelength over the cone's sine wide.
    w0 = lam / sh
    reach = r_max * math.tan(ah) + 3 * w0
    x_half = min(float(np.abs(x_c).max()), reach) + 4 * dx
    ab = scn.pe.absorber
    nx = _good_size(math.ceil(2 * x_half / (1 - 2 * ab) / dx))
    margin = scn.pe.top_margin_m or max(50.0, a.altitude_m / 2)
    # Heights above the lowest ground of the area (0 over flat ground): the site's antenna
    # and the highest flight height over the area.
    floor = floor_m(scn)
    site_h = site_height_above_floor(scn, site.x_m, site.y_m, site.height_m)
    fly_top = float(flight_heights(scn).max()) - floor
    top = max(fly_top, site_h) + margin
    if scn.ground != "none":
        ny = _good_size(math.ceil(top / (1 - ab) / dy))
        y0 = 0.0
    else:
        bottom = min(a.altitude_m, site_h) - margin
        ny = _good_size(math.ceil((top - bottom) / (1 - 2 * ab) / dy))
        y0 = (top + bottom) / 2 - (ny // 2) * dy
    fy = (a.altitude_m - y0) / dy
    alt_row = min(math.floor(fy), ny - 2)
    # The widest angle the grid carries (its Nyquist sine, sh) crosses at most an eighth of
    # a lateral absorbing strip between windows.
    strip = ab * nx * dx
    every = int(min(16, max(1, strip / (8 * dz * math.tan(ah)))))
    nbytes = int(
        8 * nx * ny * 3  # field, propagator table (<= 1/2), handed-over aperture
        + (8 * (nx // 2 + 1) * (ny + 1) if every > 1 else 0)  # the uniform path's table
        + 2 * steps * nx * 8  # the two recorded rows
        + (steps * nx * 16 if scn.medium.varies else 0)
        + (steps * nx * 8 if scn.buildings or scn.footprints or scn.height_map_m is not None else 0)
        + (steps * nx * 24 if scn.terrain is not None else 0)  # ground, rows and weights
    )
    return MarchGrid(
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
        sine_h=sh,
        sine_v=sv,
        gpoints=nx * ny * steps / 1e9,
        x_absorber_every=every,
    )
