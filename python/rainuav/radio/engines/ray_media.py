"""What the rays cross and bounce off: the rain's specific attenuation along them (tabulated
against the rain rate, and sampled over the area) and the ground's permittivity (ITU-R P.527
soils)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rainuav.radio.engines.grid import C0_M_S
from rainuav.radio.engines.pe_engine import rain_rate_at
from rainuav.radio.scene.scenario import Scenario

__all__ = ["SOILS", "gamma_field", "gamma_table", "ground_permittivity", "rain_args"]


SOILS: dict[str, tuple[float, float, float, float]] = {
    "very-dry": (3.0, 0.0, 0.00015, 2.52),
    "medium-dry": (15.0, -0.1, 0.035, 1.63),
    "wet": (30.0, -0.4, 0.15, 1.30),
}
"""ITU-R P.527 soils as the curve fits of ITU-R P.2040 Table 3: ``eps_r = a f^b``,
``sigma = c f^d`` S/m with f in GHz (fitted over 1-10 GHz; held as they are above)."""


def ground_permittivity(kind: str, freq_hz: float) -> complex:
    """The complex relative permittivity `eps_r - j 60 lambda sigma` of an ITU-R P.527 soil.

    Args:
        kind: The soil ("very-dry", "medium-dry", "wet").
        freq_hz: The frequency, Hz.

    Returns:
        The permittivity.
    """
    a, b, c, d = SOILS[kind]
    f_ghz = freq_hz / 1e9
    lam = C0_M_S / freq_hz
    return complex(a * f_ghz**b, -60.0 * lam * c * f_ghz**d)


def gamma_table(scn: Scenario, max_rate_mm_h: float) -> tuple[np.ndarray, np.ndarray]:
    """The rain's specific attenuation of a scenario's weather, tabulated against the rain rate.

    513 points over 0..`max_rate_mm_h`: smooth in the rate, so interpolating it errs far below 1e-4
    relative.

    Args:
        scn: The scenario.
        max_rate_mm_h: The highest rate tabulated, mm/h.

    Returns:
        `(rates mm/h, attenuation dB/km)`.
    """
    rm = scn.medium.rain_medium(scn.freq_hz, scn.polarization)
    table_r = np.linspace(0.0, max(max_rate_mm_h, 1e-3), 513)
    return table_r, np.asarray(rm.specific_attenuation(table_r), dtype=float)


def _node_spacing(scn: Scenario) -> float:
    """The spacing of the rain's nodes for the rays: the pixel, at most 10 m."""
    return min(scn.area.resolution_m, 10.0)


def gamma_field(
    scn: Scenario,
    spacing_m: float | None = None,
    table: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[float, np.ndarray | None, tuple[float, float, float, float]]:
    """The rain's specific attenuation for the rays: a uniform part and a raster of nodes.

    Rain cells and rate maps are sampled at nodes `spacing_m` apart over the area.

    Args:
        scn: The scenario.
        spacing_m: The nodes' spacing, m; None: the pixel, at most 10 m.
        table: A [`gamma_table()`][rainuav.radio.engines.ray_media.gamma_table] covering the
            field's rates, to save tabulating it again.

    Returns:
        `(uniform dB/m, raster dB/m or None, (x0, dx, y0, dy) of the raster)`.
    """
    m = scn.medium
    if m.kind == "clear":
        return 0.0, None, (0.0, 1.0, 0.0, 1.0)
    if m.kind == "homogeneous":
        rm = m.rain_medium(scn.freq_hz, scn.polarization)
        return float(rm.specific_attenuation(m.rain_rate_mm_h)) / 1000.0, None, (0, 1, 0, 1)
    a = scn.area
    step = spacing_m or _node_spacing(scn)
    nx = math.ceil((a.x_max_m - a.x_min_m) / step) + 1
    ny = math.ceil((a.y_max_m - a.y_min_m) / step) + 1
    xs = a.x_min_m + np.arange(nx) * step
    ys = a.y_min_m + np.arange(ny) * step
    rates = rain_rate_at(scn, xs[None, :], ys[:, None])
    if table is None or table[0][-1] < rates.max():
        table = gamma_table(scn, float(rates.max()))
    gamma = np.interp(rates, *table) / 1000.0
    return 0.0, np.ascontiguousarray(gamma), (a.x_min_m, step, a.y_min_m, step)


def rain_args(scn: Scenario, table: tuple[np.ndarray, np.ndarray] | None = None) -> dict[str, Any]:
    """A scenario's rain as the core's `RaySlicer.power` takes it.

    Args:
        scn: The scenario (at an instant).
        table: As [`gamma_field()`][rainuav.radio.engines.ray_media.gamma_field] takes it.

    Returns:
        The keyword arguments.
    """
    g_uniform, g_raster, g_os = gamma_field(scn, table=table)
    return {"gamma_db_per_m": g_uniform, "gamma_raster": g_raster, "gamma_origin_step": g_os}
