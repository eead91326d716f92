"""The ray engine: every cell's received power at every pixel from two rays (PHYSICS.md
section 8), the per-pixel work in Rust (``rainuav_core::rays``).

For each cell and pixel: the line-of-sight ray and the ray reflected by the ground, each with
the cell's antenna gain in its own departure direction (:mod:`rainuav.radio.cell`) and
free-space spreading; the ground is PEC, absent, or an ITU-R P.527 soil (Fresnel
coefficients for the scenario's polarisation); rain attenuation is integrated along each ray
through the scenario's rain field (homogeneous: ``gamma d``; rain cells and rate maps: a
raster of ``gamma`` nodes integrated along the ray); buildings and the height map add the
P.526 knife-edge loss of the dominant edge. Each pixel holds the mean power over its area
(ground-reflection fringes finer than a pixel are averaged, not aliased).

``weights`` let the hybrid engine hand the rays only the part of each pattern the PE does not
carry (:func:`rainuav.radio.radiomap.build_radio_map`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from rainuav import _core
from rainuav.radio.cell import Cell, gain_linear
from rainuav.radio.grid import C0_M_S
from rainuav.radio.pe_engine import rain_rate_at
from rainuav.radio.scenario import Scenario, Site

__all__ = ["SOILS", "gamma_field", "ground_permittivity", "ray_power"]

SOILS: dict[str, tuple[float, float, float, float]] = {
    "very-dry": (3.0, 0.0, 0.00015, 2.52),
    "medium-dry": (15.0, -0.1, 0.035, 1.63),
    "wet": (30.0, -0.4, 0.15, 1.30),
}
"""ITU-R P.527 soils as the curve fits of ITU-R P.2040 Table 3: ``eps_r = a f^b``,
``sigma = c f^d`` S/m with f in GHz (fitted over 1-10 GHz; held as they are above)."""

#: A weight on a pattern: direction cosines (cross-range, height, range) in the cell's frame
#: -> factor in 0..1.
Weight = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def ground_permittivity(kind: str, freq_hz: float) -> complex:
    """Complex relative permittivity ``eps_r - j 60 lambda sigma`` of a P.527 soil."""
    a, b, c, d = SOILS[kind]
    f_ghz = freq_hz / 1e9
    lam = C0_M_S / freq_hz
    return complex(a * f_ghz**b, -60.0 * lam * c * f_ghz**d)


def gamma_field(
    scn: Scenario, spacing_m: float | None = None
) -> tuple[float, np.ndarray | None, tuple[float, float, float, float]]:
    """The rain's specific attenuation for the rays: (uniform dB/m, raster of nodes in dB/m
    or None, (x0, dx, y0, dy) of the raster). Rain cells and rate maps are sampled at nodes
    ``spacing_m`` apart (default: the pixel, at most 10 m) over the area."""
    m = scn.medium
    if m.kind == "clear":
        return 0.0, None, (0.0, 1.0, 0.0, 1.0)
    rm = m.rain_medium(scn.freq_hz, scn.polarization)
    if m.kind == "homogeneous":
        return float(rm.specific_attenuation(m.rain_rate_mm_h)) / 1000.0, None, (0, 1, 0, 1)
    a = scn.area
    step = spacing_m or min(a.resolution_m, 10.0)
    nx = math.ceil((a.x_max_m - a.x_min_m) / step) + 1
    ny = math.ceil((a.y_max_m - a.y_min_m) / step) + 1
    xs = a.x_min_m + np.arange(nx) * step
    ys = a.y_min_m + np.arange(ny) * step
    rates = rain_rate_at(scn, xs[None, :], ys[:, None])
    # gamma against rain rate, tabulated once (smooth in the rate: 513 points interpolate to
    # far below 1e-4 relative) and interpolated.
    table_r = np.linspace(0.0, max(float(rates.max()), 1e-3), 513)
    table_g = np.asarray(rm.specific_attenuation(table_r), dtype=float)
    gamma = np.interp(rates, table_r, table_g) / 1000.0
    return 0.0, np.ascontiguousarray(gamma), (a.x_min_m, step, a.y_min_m, step)


def _heights(scn: Scenario) -> tuple[np.ndarray | None, tuple[float, float, float, float]]:
    if scn.height_map_m is None:
        return None, (0.0, 1.0, 0.0, 1.0)
    hm = np.ascontiguousarray(np.asarray(scn.height_map_m, dtype=float))
    a = scn.area
    rows, cols = hm.shape
    return hm, (
        a.x_min_m,
        (a.x_max_m - a.x_min_m) / cols,
        a.y_min_m,
        (a.y_max_m - a.y_min_m) / rows,
    )


def ray_gains(
    scn: Scenario, site: Site, cell: Cell, x_m: np.ndarray, y_m: np.ndarray, weight: Weight | None
) -> tuple[np.ndarray, np.ndarray]:
    """Linear gains (H, W) of ``cell`` toward every pixel along the direct and the reflected
    ray, times ``weight`` of each departure direction if given."""
    ex = x_m[None, :] - site.x_m
    ey = y_m[:, None] - site.y_m
    rho = np.hypot(ex, ey)
    az = np.degrees(np.arctan2(ey, ex))
    h_s, h_q = site.height_m, scn.area.altitude_m
    el_direct = np.degrees(np.arctan2(h_q - h_s, rho))
    el_reflect = np.degrees(-np.arctan2(h_q + h_s, rho))
    out = []
    for el in (el_direct, el_reflect):
        g = gain_linear(cell, az, el)
        if weight is not None:
            e = np.radians(el)
            a = np.radians(az - cell.azimuth_deg)
            g = g * weight(np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a))
        out.append(np.ascontiguousarray(g, dtype=np.float64))
    return out[0], out[1]


def ray_power(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    weights: Sequence[Weight | None] | None = None,
) -> np.ndarray:
    """Received power (mW, isotropic receiver) of every (site, cell) at every pixel centre,
    (M, H, W), each the mean over its pixel; ``weights[m]`` (if given) scales cell m's
    pattern."""
    a = scn.area
    gd = np.empty((len(jobs), y_m.size, x_m.size))
    gr = np.empty_like(gd)
    for m, (site, cell) in enumerate(jobs):
        gd[m], gr[m] = ray_gains(scn, site, cell, x_m, y_m, None if weights is None else weights[m])
    tx = np.array([[s.x_m, s.y_m, s.height_m] for s, _ in jobs], dtype=float).reshape(-1, 3)
    pw = np.array([10 ** (c.tx_power_dbm / 10) for _, c in jobs], dtype=float)
    g_uniform, g_raster, g_os = gamma_field(scn)
    heights, h_os = _heights(scn)
    if scn.ground in SOILS:
        ground, eps = "dielectric", ground_permittivity(scn.ground, scn.freq_hz)
    else:
        ground, eps = scn.ground, 1.0 + 0j
    boxes = np.array(
        [[b.x0_m, b.x1_m, b.y0_m, b.y1_m, b.height_m] for b in scn.buildings], dtype=float
    ).reshape(-1, 5)
    px = ((a.x_max_m - a.x_min_m) / x_m.size, (a.y_max_m - a.y_min_m) / y_m.size)
    return _core.ray_power(
        tx,
        pw,
        gd,
        gr,
        np.ascontiguousarray(x_m, dtype=float),
        np.ascontiguousarray(y_m, dtype=float),
        altitude_m=a.altitude_m,
        pixel_m=px,
        freq_hz=scn.freq_hz,
        ground=ground,
        eps_ground=(eps.real, eps.imag),
        polarization=scn.polarization,
        gamma_db_per_m=g_uniform,
        gamma_raster=g_raster,
        gamma_origin_step=g_os,
        buildings=boxes,
        heights=heights,
        heights_origin_step=h_os,
    )
