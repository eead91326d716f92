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

With ``weights``, :func:`ray_power` also returns the power of the part of each pattern the
weights select: what the PE would carry in the hybrid engine
(:func:`rainuav.radio.radiomap.build_radio_map`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from rainuav import _core
from rainuav.radio.cell import Cell, gain_linear
from rainuav.radio.grid import C0_M_S
from rainuav.radio.pe_engine import rain_rate_at
from rainuav.radio.scenario import Scenario, Site

__all__ = [
    "SOILS",
    "gamma_field",
    "ground_permittivity",
    "ray_gains",
    "ray_power",
    "ray_power_in_time",
]

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


def _directions(
    scn: Scenario, site: Site, x_m: np.ndarray, y_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Global azimuth (H, W) and the elevations of the direct and the reflected ray, degrees,
    from ``site`` toward every pixel."""
    ex = x_m[None, :] - site.x_m
    ey = y_m[:, None] - site.y_m
    rho = np.hypot(ex, ey)
    h_s, h_q = site.height_m, scn.area.altitude_m
    az = np.degrees(np.arctan2(ey, ex))
    return az, np.degrees(np.arctan2(h_q - h_s, rho)), np.degrees(-np.arctan2(h_q + h_s, rho))


def _weight_at(weight: Weight, cell: Cell, az: np.ndarray, el: np.ndarray) -> np.ndarray:
    e = np.radians(el)
    a = np.radians(az - cell.azimuth_deg)
    return weight(np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a))


def _trace(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    gains: tuple[np.ndarray, np.ndarray],
    medium_args: dict[str, Any],
) -> np.ndarray:
    a = scn.area
    tx = np.array([[s.x_m, s.y_m, s.height_m] for s, _ in jobs], dtype=float).reshape(-1, 3)
    pw = np.array([10 ** (c.tx_power_dbm / 10) for _, c in jobs], dtype=float)
    px = ((a.x_max_m - a.x_min_m) / x_m.size, (a.y_max_m - a.y_min_m) / y_m.size)
    return _core.ray_power(
        tx,
        pw,
        np.ascontiguousarray(gains[0]),
        np.ascontiguousarray(gains[1]),
        np.ascontiguousarray(x_m, dtype=float),
        np.ascontiguousarray(y_m, dtype=float),
        altitude_m=a.altitude_m,
        pixel_m=px,
        freq_hz=scn.freq_hz,
        polarization=scn.polarization,
        **medium_args,
    )


def _medium_args(scn: Scenario) -> dict[str, Any]:
    """The ground, rain and obstacles of ``scn`` as the core takes them."""
    g_uniform, g_raster, g_os = gamma_field(scn)
    heights, h_os = _heights(scn)
    if scn.ground in SOILS:
        ground, eps = "dielectric", ground_permittivity(scn.ground, scn.freq_hz)
    else:
        ground, eps = scn.ground, 1.0 + 0j
    boxes = np.array(
        [[b.x0_m, b.x1_m, b.y0_m, b.y1_m, b.height_m] for b in scn.buildings], dtype=float
    ).reshape(-1, 5)
    return {
        "ground": ground,
        "eps_ground": (eps.real, eps.imag),
        "gamma_db_per_m": g_uniform,
        "gamma_raster": g_raster,
        "gamma_origin_step": g_os,
        "buildings": boxes,
        "heights": heights,
        "heights_origin_step": h_os,
    }


def ray_gains(
    scn: Scenario, jobs: Sequence[tuple[Site, Cell]], x_m: np.ndarray, y_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The linear antenna gain of every (site, cell) toward every pixel along the direct and
    the reflected ray, two (M, H, W) arrays: the part of a ray map that no weather changes."""
    shape = (len(jobs), y_m.size, x_m.size)
    gd, gr = np.empty(shape), np.empty(shape)
    for m, (site, cell) in enumerate(jobs):
        az, el_d, el_r = _directions(scn, site, x_m, y_m)
        gd[m], gr[m] = gain_linear(cell, az, el_d), gain_linear(cell, az, el_r)
    return gd, gr


def ray_power_in_time(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    gains: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """Received power (M, H, W) of ``scn`` (its weather at one instant) from gains computed
    once (:func:`ray_gains`): the rain is integrated once per site along the horizontal line
    to every pixel (``_core.ray_mean_gamma``), shared by the site's cells and by both rays,
    which makes it the same power as :func:`ray_power` to the last bit."""
    args = _medium_args(scn)
    places: dict[tuple[float, float], int] = {}  # the integral depends on the position only
    index = [places.setdefault((s.x_m, s.y_m), len(places)) for s, _ in jobs]
    per_site = _core.ray_mean_gamma(
        np.array(list(places), dtype=float).reshape(-1, 2),
        np.ascontiguousarray(x_m, dtype=float),
        np.ascontiguousarray(y_m, dtype=float),
        gamma_db_per_m=args["gamma_db_per_m"],
        gamma_raster=args["gamma_raster"],
        gamma_origin_step=args["gamma_origin_step"],
    )
    per_tx = np.ascontiguousarray(per_site[np.asarray(index, dtype=np.intp)])
    return _trace(scn, jobs, x_m, y_m, gains, {**args, "gamma_per_tx": per_tx})


def ray_power(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    weights: Sequence[Weight | None] | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Received power (mW, isotropic receiver) of every (site, cell) at every pixel centre,
    (M, H, W), each the mean over its pixel; and, if ``weights`` are given, the power of the
    part of each pattern they select (``weights[m]`` scales cell m's pattern; None: nothing).
    Directions, gains, the rain field and the obstacles are prepared once for both."""
    shape = (len(jobs), y_m.size, x_m.size)
    gd, gr = ray_gains(scn, jobs, x_m, y_m)
    wd, wr = np.zeros(shape), np.zeros(shape)
    for m, (site, cell) in enumerate(jobs):
        if weights is not None and weights[m] is not None:
            az, el_d, el_r = _directions(scn, site, x_m, y_m)
            wd[m] = _weight_at(weights[m], cell, az, el_d)
            wr[m] = _weight_at(weights[m], cell, az, el_r)
    args = _medium_args(scn)
    full = _trace(scn, jobs, x_m, y_m, (gd, gr), args)
    if weights is None:
        return full, None
    return full, _trace(scn, jobs, x_m, y_m, (gd * wd, gr * wr), args)
