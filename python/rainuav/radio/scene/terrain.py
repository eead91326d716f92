"""A scenario's ground as the radio layer uses it ([physics reference, section
12][12-terrain-buildings-diffraction-and-reflections]): its terrain on the area's nodes
([`rainuav.ground`][rainuav.ground]), the heights the ray engine takes, the flight height over every
pixel and the pixels that are not flyable.

- A site's antenna stands ``height_m`` above the terrain at the site; the UAV flies
  ``area.altitude_m`` above the terrain under it (``area.altitude_reference = "ground"``, the
  default) or above mean sea level (``"msl"``).
- A pixel is **not flyable** where the highest point of terrain and obstacles within it, plus
  ``area.min_clearance_m`` (default 10 m), reaches the flight height over the pixel's centre.
  Obstacles (buildings, ``height_map_m``) count wherever they overlap the pixel: footprints
  and boxes intersected with it as polygons
  ([`rainuav.radio.scene.buildings`][rainuav.radio.scene.buildings]).
- Without a terrain the ground is flat at 0: a flat DEM at any height gives the same map.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from rainuav.ground import Terrain, file_digest, read_dem
from rainuav.radio.scene.scenario import Scenario

__all__ = [
    "DEM_GROUND",
    "core_args",
    "flight_heights",
    "flight_heights_at",
    "floor_m",
    "ground_over",
    "map_mask",
    "not_flyable",
    "obstacle_pixel_max",
    "scenario_terrain",
    "site_height_above_floor",
    "surface_at",
]


@lru_cache(maxsize=8)
def _read(
    path: str,
    digest: str,
    origin: tuple[float, float],
    bounds: tuple[float, float, float, float],
    shape: tuple[int, int],
) -> Terrain:
    from rainuav.geo import Georef

    del digest  # in the key only: a changed file is read again
    return read_dem(path, Georef(*origin), bounds, shape)


def scenario_terrain(scn: Scenario) -> Terrain | None:
    """The terrain of a scenario on its area's nodes, read once per file contents and area.

    Args:
        scn: The scenario.

    Returns:
        The [`Terrain`][rainuav.ground.dem.Terrain], or None for a flat ground at 0.
    """
    if scn.terrain is None or scn.origin is None:
        return None
    a = scn.area
    return _read(
        str(scn.terrain.file),
        file_digest(scn.terrain.file),
        (scn.origin.lat_deg, scn.origin.lon_deg),
        a.bounds,
        a.shape,
    )


DEM_GROUND = "medium-dry"
"""The ground under a DEM unless one is named: ITU-R P.527's medium-dry soil (a perfect conductor
is a mirror no real ground is; its reflection is further weighted by the terrain's roughness)."""


def ground_over(terrain: bool, ground: str | None, current: str) -> str:
    """The ground a map uses.

    Args:
        terrain: Whether the scenario has a DEM.
        ground: The ground named, or None.
        current: The scenario's ground otherwise.

    Returns:
        `ground` where one is named, else [`DEM_GROUND`][rainuav.radio.scene.terrain.DEM_GROUND]
        over a DEM, else `current`.
    """
    if ground is not None:
        return ground
    return DEM_GROUND if terrain else current


def core_args(scn: Scenario) -> dict[str, Any]:
    """The terrain and the altitude reference as the core's ray functions take them.

    Args:
        scn: The scenario.

    Returns:
        The keyword arguments.
    """
    t = scenario_terrain(scn)
    if t is None:
        return {"terrain": None, "altitude_msl": scn.area.msl}
    assert scn.terrain is not None
    return {
        "terrain": t.heights_m,
        "terrain_origin_step": t.origin_step,
        "altitude_msl": scn.area.msl,
        "terrain_roughness_m": scn.terrain.roughness_m,
    }


def flight_heights(scn: Scenario) -> np.ndarray:
    """The UAV's height above sea level over every pixel centre.

    Args:
        scn: The scenario.

    Returns:
        (H, W), m.
    """
    x, y = scn.area.centres()
    gx, gy = np.meshgrid(x, y)
    return flight_heights_at(scn, gx, gy)


def obstacle_pixel_max(scn: Scenario, at_least_m: float = 0.0) -> np.ndarray:
    """The tallest obstacle touching each pixel, m above the terrain.

    Buildings (boxes and footprints, intersected with each pixel as polygons) and `height_map_m`.

    Args:
        scn: The scenario.
        at_least_m: Buildings lower than this are left out, m.

    Returns:
        (H, W), m.
    """
    from rainuav.radio.scene.buildings import pixels_touched_max

    a = scn.area
    h, w = a.shape
    out = pixels_touched_max(scn, at_least_m=at_least_m)
    if scn.height_map_m is not None:
        hm = np.asarray(scn.height_map_m, dtype=float)
        rows, cols = hm.shape

        # Every height-map cell that overlaps the pixel (cells and pixels both tile the area):
        # pixel i touches rows r0[i] .. r1[i] - 1, and r1[i] - 1 <= r0[i + 1].
        def touched_max(v: np.ndarray, n: int, cells: int, axis: int) -> np.ndarray:
            k = np.arange(n)
            r0 = np.floor(k * cells / n).astype(int)
            r1 = np.minimum(np.ceil((k + 1) * cells / n).astype(int), cells)
            head = np.maximum.reduceat(v, r0, axis=axis)
            return np.maximum(head, np.take(v, r1 - 1, axis=axis))

        cell_max = touched_max(touched_max(hm, h, rows, 0), w, cols, 1)
        out = np.maximum(out, cell_max)
    return out


def not_flyable(scn: Scenario) -> np.ndarray:
    """The pixels the UAV may not enter (the module's docstring).

    Args:
        scn: The scenario.

    Returns:
        (H, W) bool.
    """
    a = scn.area
    t = scenario_terrain(scn)
    ground = np.zeros(a.shape) if t is None else t.pixel_max(a.shape)
    flight = flight_heights(scn)
    # A building lower than this stands below every pixel's flight height less the clearance,
    # whatever the ground under it: it cannot close a pixel (10 000 footprints under a flight
    # above the roofs: the few towers are intersected with the pixels, not every house).
    lowest = float(flight.min() - a.clearance_m - ground.max())
    top = ground + obstacle_pixel_max(scn, at_least_m=lowest)
    return top + a.clearance_m >= flight


def map_mask(scn: Scenario) -> np.ndarray | None:
    """The not-flyable pixels a map of a scenario carries.

    Args:
        scn: The scenario.

    Returns:
        [`not_flyable()`][rainuav.radio.scene.terrain.not_flyable] where anything stands on the
        ground (terrain, buildings, a height map); None over flat open ground (every pixel flyable).
    """
    if (
        scn.terrain is None
        and not scn.buildings
        and scn.footprints is None
        and scn.height_map_m is None
    ):
        return None
    return not_flyable(scn)


def floor_m(scn: Scenario) -> float:
    """The lowest terrain over the area's nodes: the parabolic equation's grids start there.

    Args:
        scn: The scenario.

    Returns:
        m above sea level (0 without a terrain).
    """
    t = scenario_terrain(scn)
    return 0.0 if t is None else float(t.heights_m.min())


def site_height_above_floor(scn: Scenario, x_m: float, y_m: float, height_m: float) -> float:
    """A site's antenna height above [`floor_m()`][rainuav.radio.scene.terrain.floor_m].

    Args:
        scn: The scenario.
        x_m: The site's east, m.
        y_m: Its north, m.
        height_m: The antenna's height above the ground there, m.

    Returns:
        m.
    """
    t = scenario_terrain(scn)
    if t is None:
        return float(height_m)
    return float(t.at(x_m, y_m)) + height_m - floor_m(scn)


def surface_at(scn: Scenario, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The terrain's height above sea level at points (0 without a terrain).

    Args:
        scn: The scenario.
        x: East, m.
        y: North, m.

    Returns:
        Heights, m.
    """
    t = scenario_terrain(scn)
    return np.zeros(np.shape(x)) if t is None else t.at(x, y)


def flight_heights_at(scn: Scenario, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The UAV's height above sea level over points.

    Args:
        scn: The scenario.
        x: East, m.
        y: North, m.

    Returns:
        Heights, m.
    """
    a = scn.area
    if a.msl or scn.terrain is None:
        return np.full(np.shape(x), float(a.altitude_m))
    return surface_at(scn, x, y) + a.altitude_m
