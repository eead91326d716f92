"""The ray engine: every cell's received power at every pixel from two rays ([physics reference,
section 8][8-rays-over-flat-ground]), the per-pixel work in Rust
(``rainuav_core::propagation::rays``).

For each cell and pixel: the line-of-sight ray and the ray reflected by the ground, each with the
cell's antenna gain in its own departure direction
([`rainuav.radio.scene.cell`][rainuav.radio.scene.cell]) and free-space spreading; the ground is
PEC, absent, or an ITU-R P.527 soil (Fresnel coefficients for the scenario's polarisation); rain
attenuation is integrated along each ray through the scenario's rain field (homogeneous: ``gamma
d``; rain cells and rate maps: a raster of ``gamma`` nodes integrated along the ray). Over terrain
([`rainuav.radio.scene.terrain`][rainuav.radio.scene.terrain]) and obstacles (buildings, the height
map, standing on the terrain), each site-pixel path reads its profile: the direct ray gets the
diffraction loss of the whole profile (the terrain's: ITU-R P.526-15 section 4.5.1 Bullington with
its correction; a building's: Deygout's isolated edges) with the antenna gain toward the principal
edge, and the ground reflects off the line fitted over its first Fresnel zone, weighted by the
terrain's roughness, faded where its legs are half hidden
([`departures()`][rainuav.radio.engines.ray_engine.departures]); the walls reflect once and twice
and the buildings' corners diffract round them
([`rainuav.radio.engines.wall_rays`][rainuav.radio.engines.wall_rays]; [physics reference, sections
8][8-rays-over-flat-ground] and [12][12-terrain-buildings-diffraction-and-reflections]). Each pixel
holds the mean power over its area (ground-reflection fringes finer than a pixel are averaged, not
aliased).

With ``weights``, [`ray_power()`][rainuav.radio.engines.ray_engine.ray_power] also returns the power
of the part of each pattern the weights select: what the PE would carry in the hybrid engine
([`rainuav.radio.outputs.maps.build_radio_map()`][rainuav.radio.outputs.maps.build_radio_map])."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rainuav import _core
from rainuav._threads import each
from rainuav.radio.engines.ray_media import (
    SOILS,
    _node_spacing,
    gamma_field,
    gamma_table,
    ground_permittivity,
    rain_args,
)
from rainuav.radio.engines.wall_rays import obstacle_args, trace_walls, wall_terms
from rainuav.radio.scene.cell import Cell, Weight, gain_linear, weight_at
from rainuav.radio.scene.scenario import Scenario, Site
from rainuav.radio.scene.terrain import core_args

__all__ = [
    "SOILS",
    "departures",
    "gamma_field",
    "gamma_table",
    "ground_permittivity",
    "rain_args",
    "ray_directions",
    "ray_gains",
    "ray_power",
    "ray_slicer",
    "ray_terms",
]


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


def _flat_open(scn: Scenario) -> bool:
    return (
        scn.terrain is None
        and not scn.buildings
        and scn.footprints is None
        and scn.height_map_m is None
    )


def departures(
    scn: Scenario, sites: Sequence[Site], x_m: np.ndarray, y_m: np.ndarray
) -> np.ndarray:
    """The departure elevations toward which each site's antenna gains are taken, degrees.

    The direct ray's (the diffracting edge where the profile costs a loss, else the pixel) and the
    reflected ray's (the specular point). Over flat open ground these are the closed forms.

    Args:
        scn: The scenario.
        sites: The sites.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.

    Returns:
        (S, H, W, 2) degrees.
    """
    return np.degrees(_path_table(scn, sites, x_m, y_m)[1][..., 3:5])


Paths = tuple[np.ndarray, np.ndarray]
"""Every path of some sites traced once: the sites (S, 3: x, y, height) and the geometry of
each path (S, H, W, 7: ``[d1, d2, loss_db, el_direct, el_reflect, psi, reflect]``, elevations
in radians), as `rainuav._core.ray_power` takes them back."""


def _path_table(scn: Scenario, sites: Sequence[Site], x_m: np.ndarray, y_m: np.ndarray) -> Paths:
    a = scn.area
    xyz = np.array([[s.x_m, s.y_m, s.height_m] for s in sites], dtype=float).reshape(-1, 3)
    table = _core.ray_departures(
        xyz,
        np.ascontiguousarray(x_m, dtype=float),
        np.ascontiguousarray(y_m, dtype=float),
        altitude_m=a.altitude_m,
        freq_hz=scn.freq_hz,
        ground="none" if scn.ground == "none" else "pec",
        full=True,
        polarization=scn.polarization,
        **obstacle_args(scn),
        **core_args(scn),
    )
    return xyz, table


def _trace(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    gains: tuple[np.ndarray, np.ndarray],
    medium_args: dict[str, Any],
    terms_only: bool = False,
    walls: np.ndarray | None = None,
    paths: Paths | None = None,
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
        terms_only=terms_only,
        walls=walls,
        geometry=None if paths is None else paths[1],
        geometry_sites=None if paths is None else paths[0],
        **medium_args,
    )


def _medium_args(scn: Scenario) -> dict[str, Any]:
    """The ground, rain and obstacles of ``scn`` as the core takes them."""
    g_uniform, g_raster, g_os = gamma_field(scn)
    if scn.ground in SOILS:
        ground, eps = "dielectric", ground_permittivity(scn.ground, scn.freq_hz)
    else:
        ground, eps = scn.ground, 1.0 + 0j
    return {
        "ground": ground,
        "eps_ground": (eps.real, eps.imag),
        "gamma_db_per_m": g_uniform,
        "gamma_raster": g_raster,
        "gamma_origin_step": g_os,
        **obstacle_args(scn),
        **core_args(scn),
    }


Directions = list[tuple[np.ndarray, np.ndarray, np.ndarray]]
"""Per (site, cell): the azimuth and the departure elevations of the direct and the reflected
ray toward every pixel, degrees."""


def ray_directions(
    scn: Scenario, jobs: Sequence[tuple[Site, Cell]], x_m: np.ndarray, y_m: np.ndarray
) -> Directions:
    """Each (site, cell)'s azimuth and departure elevations toward every pixel.

    The closed forms over flat open ground, else
    [`departures()`][rainuav.radio.engines.ray_engine.departures] (toward the diffracting edge and
    the specular point), traced once a site.

    Args:
        scn: The scenario.
        jobs: The `(site, cell)` pairs.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.

    Returns:
        The directions, (H, W) each.
    """
    return _paths(scn, jobs, x_m, y_m)[0]


def _paths(
    scn: Scenario, jobs: Sequence[tuple[Site, Cell]], x_m: np.ndarray, y_m: np.ndarray
) -> tuple[Directions, Paths | None]:
    """[`ray_directions()`][rainuav.radio.engines.ray_engine.ray_directions], and the paths traced
    for them (None over flat open ground, where the core's closed forms need no tracing)."""
    paths, index = None, {}
    if not _flat_open(scn):
        unique = list({id(s): s for s, _ in jobs}.values())
        index = {id(s): k for k, s in enumerate(unique)}
        paths = _path_table(scn, unique, x_m, y_m)
    out = []
    for site, _ in jobs:
        az, el_d, el_r = _directions(scn, site, x_m, y_m)
        if paths is not None:
            k = index[id(site)]
            el_d, el_r = np.degrees(paths[1][k, ..., 3]), np.degrees(paths[1][k, ..., 4])
        out.append((az, el_d, el_r))
    return out, paths


def ray_gains(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    directions: Directions | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The linear antenna gain of every (site, cell) toward every pixel, on both rays.

    The part of a ray map that no weather changes.

    Args:
        scn: The scenario.
        jobs: The `(site, cell)` pairs.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.
        directions: [`ray_directions()`][rainuav.radio.engines.ray_engine.ray_directions]; None:
            computed here.

    Returns:
        `(direct, reflected)`, (M, H, W) each.
    """
    dirs = ray_directions(scn, jobs, x_m, y_m) if directions is None else directions
    shape = (len(jobs), y_m.size, x_m.size)
    gd, gr = np.empty(shape), np.empty(shape)

    def one(m: int) -> None:
        (_, cell), (az, el_d, el_r) = jobs[m], dirs[m]
        gd[m], gr[m] = gain_linear(cell, az, el_d), gain_linear(cell, az, el_r)

    each(len(jobs), one)
    return gd, gr


def ray_terms(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    weights: Sequence[Weight | None] | None = None,
) -> np.ndarray:
    """Everything of a ray map that no weather changes, split into its parts.

    Each cell's clear-air power at every pixel split into direct, reflected and interference parts,
    and its rays' lengths: `[direct, reflect, cross, d1, d2, wall, d3]` (antenna gains, spreading,
    ground, pixel means, diffraction, the walls' rays:
    [`wall_terms()`][rainuav.radio.engines.wall_rays.wall_terms]).
    [`ray_slicer()`][rainuav.radio.engines.ray_engine.ray_slicer] adds the rain.

    Args:
        scn: The scenario.
        jobs: The `(site, cell)` pairs.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.
        weights: As [`ray_power()`][rainuav.radio.engines.ray_engine.ray_power] takes them: the
            parts of the whole pattern less those of the weighted part (what the rays keep where the
            PE carries the rest).

    Returns:
        (M, H, W, 7).
    """
    dirs, paths = _paths(scn, jobs, x_m, y_m)
    gd, gr = ray_gains(scn, jobs, x_m, y_m, dirs)
    args = _medium_args(scn)
    rays = trace_walls(scn, jobs, x_m, y_m)
    walls = wall_terms(scn, jobs, x_m, y_m, rays=rays)
    full = _trace(scn, jobs, x_m, y_m, (gd, gr), args, True, walls, paths)
    if weights is None:
        return full
    wd, wr = _weights_at(jobs, dirs, weights)
    out = full.copy()
    out[..., :3] -= _trace(scn, jobs, x_m, y_m, (gd * wd, gr * wr), args, True, None, paths)[
        ..., :3
    ]
    if walls is not None:
        inside = wall_terms(scn, jobs, x_m, y_m, weights, rays=rays)
        assert inside is not None
        kept = walls[..., 0] - inside[..., 0]
        # The kept rays' mean length: the power-weighted lengths less the weighted part's.
        dl = walls[..., 0] * walls[..., 1] - inside[..., 0] * inside[..., 1]
        out[..., 5] = np.maximum(kept, 0.0)
        out[..., 6] = np.divide(dl, kept, out=np.zeros_like(kept), where=kept > 0)
    return out


def _weights_at(
    jobs: Sequence[tuple[Site, Cell]],
    directions: Directions,
    weights: Sequence[Weight | None],
) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's weight (M, H, W) along the direct and the reflected ray's departure
    directions (0: none)."""
    shape = (len(jobs), *directions[0][0].shape) if jobs else (0, 0, 0)
    wd, wr = np.zeros(shape), np.zeros(shape)
    for m, ((_, cell), (az, el_d, el_r)) in enumerate(zip(jobs, directions, strict=True)):
        if weights[m] is not None:
            wd[m] = weight_at(weights[m], cell, az, el_d)
            wr[m] = weight_at(weights[m], cell, az, el_r)
    return wd, wr


def ray_slicer(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    terms: np.ndarray | None = None,
) -> _core.RaySlicer:
    """Every cell's rays over the map traced once in clear air, ready for any rain.

    `slicer.power(**rain_args(scn_at_t))` is the received power (M, H, W) in the weather of any
    instant, the rain integrated once a site for every pixel at once and shared by the site's cells
    and both rays (`rainuav_core::propagation::raytime`).

    Args:
        scn: The scenario.
        jobs: The `(site, cell)` pairs.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.
        terms: [`ray_terms()`][rainuav.radio.engines.ray_engine.ray_terms]; None: computed here.

    Returns:
        The core's `RaySlicer`.
    """
    places: dict[tuple[float, float, float], int] = {}
    site_of = [places.setdefault((s.x_m, s.y_m, s.height_m), len(places)) for s, _ in jobs]
    return _core.RaySlicer(
        ray_terms(scn, jobs, x_m, y_m) if terms is None else terms,
        np.array(list(places), dtype=float).reshape(-1, 3),
        np.asarray(site_of, dtype=np.int64),
        np.ascontiguousarray(x_m, dtype=float),
        np.ascontiguousarray(y_m, dtype=float),
        node_spacing_m=_node_spacing(scn),
    )


def ray_power(
    scn: Scenario,
    jobs: Sequence[tuple[Site, Cell]],
    x_m: np.ndarray,
    y_m: np.ndarray,
    weights: Sequence[Weight | None] | None = None,
) -> tuple[np.ndarray, np.ndarray | None]:
    """The received power of every (site, cell) at every pixel, the mean over the pixel.

    Directions, gains, the rain field and the obstacles are prepared once for both results; the
    receiver is isotropic.

    Args:
        scn: The scenario.
        jobs: The `(site, cell)` pairs.
        x_m: The pixel centres' east (W,), m.
        y_m: Their north (H,), m.
        weights: `weights[m]` scales cell m's pattern (None: nothing); None: no weighted part.

    Returns:
        `(power (M, H, W), the weighted parts' power or None)`, mW.
    """
    dirs, paths = _paths(scn, jobs, x_m, y_m)
    gd, gr = ray_gains(scn, jobs, x_m, y_m, dirs)
    args = _medium_args(scn)
    rays = trace_walls(scn, jobs, x_m, y_m)
    walls = wall_terms(scn, jobs, x_m, y_m, rays=rays)
    full = _trace(scn, jobs, x_m, y_m, (gd, gr), args, walls=walls, paths=paths)
    if weights is None:
        return full, None
    wd, wr = _weights_at(jobs, dirs, weights)
    inside = None if walls is None else wall_terms(scn, jobs, x_m, y_m, weights, rays=rays)
    return full, _trace(scn, jobs, x_m, y_m, (gd * wd, gr * wr), args, walls=inside, paths=paths)
