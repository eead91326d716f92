"""The grid of one cell's PE march (PHYSICS.md section 4).

The transverse steps resolve the largest angle at which the beam is within
``pe.dynamic_range_db`` of its peak, ``d <= lambda / (2 sin theta_max)``, separately across
range and in height (where the tilt adds to the spread). The domain spans the beam's spread
over the longest range that reaches the area (or the area's own cross-range extent, if
smaller), plus the absorbing taper; in height, the ground (or a margin below) up to
``max(altitude, site) + top_margin_m``, plus the taper. Sizes are rounded up to products of 2,
3 and 5 for the FFTs. Energy that leaves through the top never returns over flat ground, so
the top only needs to clear the flight altitude.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rainuav.radio.scenario import Cell, Scenario, Site

__all__ = ["C0_M_S", "MarchGrid", "march_grid"]

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


def march_grid(scn: Scenario, site: Site, cell: Cell) -> MarchGrid | None:
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
    )
