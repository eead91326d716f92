"""The rays that building walls reflect ([physics reference, section
12][12-terrain-buildings-diffraction-and-reflections]), for the ray engine: each site's rays traced
once in the core (`rainuav._core.ray_walls`: the image method per wall, the specular point within
the wall, both legs clear), then each cell's antenna gain toward each ray's specular point, the
powers added incoherently per pixel ([`wall_terms()`][rainuav.radio.engines.wall_rays.wall_terms]).
Also the obstacles (buildings and the height map) as the core's ray functions take them
([`obstacle_args()`][rainuav.radio.engines.wall_rays.obstacle_args]).

**Rain** on a wall's ray is the mean specific attenuation of the site-pixel line times the
ray's length (the pixel's wall rays together: their power-weighted mean length): exact in
uniform rain for one wall, and within the rain's variation over the few hundred metres a
wall ray strays from that line otherwise.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rainuav import _core
from rainuav._threads import each
from rainuav.radio.scene.buildings import prism_eps, scenario_buildings, wall_args
from rainuav.radio.scene.cell import Cell, Weight, gain_linear, weight_at
from rainuav.radio.scene.scenario import Scenario, Site
from rainuav.radio.scene.terrain import core_args

__all__ = ["WallRays", "obstacle_args", "trace_walls", "wall_terms"]


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


def obstacle_args(scn: Scenario) -> dict[str, Any]:
    """A scenario's buildings and height map as the core's ray functions take them.

    Args:
        scn: The scenario ([`rainuav.radio.scene.buildings`][rainuav.radio.scene.buildings]).

    Returns:
        The keyword arguments.
    """
    b = scenario_buildings(scn)
    heights, h_os = _heights(scn)
    return {
        "buildings": np.zeros((0, 5)),
        "prisms": None if b is None else b.prisms,
        "heights": heights,
        "heights_origin_step": h_os,
    }


WallRays = tuple[np.ndarray, ...]
"""Per ray off the walls (`rainuav._core.ray_walls`): its site (index into the distinct sites),
pixel, departure azimuth and elevation (degrees), power per mW for isotropic antennas, length (m)
and kind (1: one wall, 2: two walls, 3: a corner, alone or after a wall, 4: a roof's edge beside
the line)."""


def trace_walls(
    scn: Scenario, jobs: Sequence[tuple[Site, Cell]], x_m: np.ndarray, y_m: np.ndarray
) -> tuple[WallRays, dict[int, int]] | None:
    """Every ray the walls reflect from each site to each pixel, and those edges diffract.

    The buildings' corners and the roofs' edges beside the line diffract into the pixels they hide
    from it (`rainuav_core::propagation::corners`).

    Args:
        scn: The scenario.
        jobs: The `(site, cell)` pairs (each distinct site traced once).
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.

    Returns:
        `(rays, each site's index)`, or None without walls.
    """
    walls, eps = wall_args(scn)
    if walls.shape[0] == 0:
        return None
    unique = list({id(s): s for s, _ in jobs}.values())
    index = {id(s): k for k, s in enumerate(unique)}
    rays = _core.ray_walls(
        np.array([[s.x_m, s.y_m, s.height_m] for s in unique], dtype=float).reshape(-1, 3),
        np.ascontiguousarray(x_m, dtype=float),
        np.ascontiguousarray(y_m, dtype=float),
        walls,
        eps,
        altitude_m=scn.area.altitude_m,
        freq_hz=scn.freq_hz,
        polarization=scn.polarization,
        prism_eps=prism_eps(scn),
        **obstacle_args(scn),
        **core_args(scn),
    )
    return rays, index


def wall_terms(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    weights: Sequence[Weight | None] | None = None,
    rays: tuple[WallRays, dict[int, int]] | None = None,
) -> np.ndarray | None:
    """Each cell's rays reflected by walls at every pixel: their clear-air power and mean length.

    [Physics reference, section 12][12-terrain-buildings-diffraction-and-reflections]: each ray with
    the cell's gain toward its specular point, added incoherently; the length power-weighted.

    Args:
        scn: The scenario.
        jobs: The `(site, cell)` pairs.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.
        weights: The part of each pattern to select, as the rays' engine takes them.
        rays: [`trace_walls()`][rainuav.radio.engines.wall_rays.trace_walls]; None: traced here.

    Returns:
        (M, H, W, 2): power (mW) and length (m); None where the scenario has no walls.
    """
    traced = trace_walls(scn, jobs, x_m, y_m) if rays is None else rays
    if traced is None:
        return None
    (site_k, pixel, az, el, factor, length, _kind), index = traced
    plane = y_m.size * x_m.size
    out = np.zeros((len(jobs), plane, 2))

    def one(m: int) -> None:
        site, cell = jobs[m]
        sel = site_k == index[id(site)]
        g = gain_linear(cell, az[sel], el[sel])
        if weights is not None:
            w = weights[m]
            g = g * (0.0 if w is None else weight_at(w, cell, az[sel], el[sel]))
        p = 10 ** (cell.tx_power_dbm / 10) * g * factor[sel]
        total = np.bincount(pixel[sel], p, minlength=plane)
        dl = np.bincount(pixel[sel], p * length[sel], minlength=plane)
        out[m, :, 0] = total
        out[m, :, 1] = np.divide(dl, total, out=np.zeros(plane), where=total > 0)

    each(len(jobs), one)
    return out.reshape(len(jobs), y_m.size, x_m.size, 2)
