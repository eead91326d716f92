"""A real place as a world, and a flight through it written for an autopilot
(``python -m rainuav.fly``).

[`place_scenario()`][rainuav.world.place.place_scenario]: sites from a file
([`rainuav.radio.scene.sites`][rainuav.radio.scene.sites]), a start and a destination in latitude
and longitude, the flight altitude, the carrier and homogeneous rain become a scenario of the
``uma`` preset's radio settings (bandwidth, noise figure, ground, engine) over an area around the
start, the destination and the sites with a margin, in metres of a
[`rainuav.geo.Georef`][rainuav.geo.Georef] centred on that box.
[`fly_place()`][rainuav.fly.plan.fly_place] plans the exact optimum from the start
(``rainuav.nav.planner``) and the straight line, and writes the flight
([`rainuav.missions`][rainuav.missions])."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.geo import Georef, latlon_text
from rainuav.nav.task import NavConfig
from rainuav.radio.scene import presets
from rainuav.radio.scene.radar import read_radar_grid
from rainuav.radio.scene.scenario import Area, FootprintsFile, Origin, Scenario, TerrainFile
from rainuav.radio.scene.sites import read_site_rows, sites_from_rows
from rainuav.radio.scene.terrain import (
    ground_over,
)

__all__ = ["MARGIN_M", "MAX_SIDE_M", "Place", "place_scenario"]

MARGIN_M = 300.0
"""The area reaches this far beyond the start, the destination and the sites, m."""
MAX_SIDE_M = 10_000.0
"""The widest and tallest area a place maps, m: at 10 m it is 1e6 pixels (about 35 s and 3.5 GB
on a 2-core machine with the 9 sectors of the example), and the hybrid engine's PE march
of the ``uma`` settings carries every sector over it, from any site in it (tested with a
site in a corner pointing across the diagonal)."""
ARRIVAL_TOL_M = NavConfig.tol_m
"""A destination this close to the take-off point is reached before any move, m."""


@dataclass
class Place:
    """A place's scenario, its georeference, the start and destination in its metres and the
    sites as the file gave them."""

    scenario: Scenario
    georef: Georef
    start_m: tuple[float, float]
    goal_m: tuple[float, float]
    sites: list[dict[str, Any]]


# Long: the place in stages (the sites, the box, the area and its pixels, the weather, the
# terrain and the footprints); each stage works in the frame the ones before fix.
def place_scenario(
    sites_file: str | Path,
    start: tuple[float, float],
    goal: tuple[float, float],
    *,
    altitude_m: float = 100.0,
    freq_ghz: float = 28.0,
    rain_rate_mm_h: float = 0.0,
    weather: str | Path | None = None,
    resolution_m: float = 10.0,
    box: tuple[float, float, float, float] | None = None,
    terrain: str | Path | None = None,
    altitude_reference: str | None = None,
    footprints: str | Path | None = None,
    altitudes_m: list[float] | None = None,
    engine: str | None = None,
    default_height_m: float | None = None,
    ground: str | None = None,
) -> Place:
    """A real place as a scenario: sites, a start and a destination in degrees.

    The module's docstring has how. Bad input is refused in one line naming the argument in
    backticks (`` `box` ``), as the `fly` command translates it into its flag (`--area`).

    Args:
        sites_file: The sites file (.csv or .geojson).
        start: The take-off point (lat, lon), degrees.
        goal: The destination (lat, lon), degrees.
        altitude_m: The flight altitude, m (above the terrain, or above sea level with
            `altitude_reference="msl"`).
        freq_ghz: The carrier, GHz (the sites file's where it gives one).
        rain_rate_mm_h: Homogeneous rain, mm/h.
        weather: A georeferenced rain file
            ([`rainuav.radio.scene.radar`][rainuav.radio.scene.radar], mm/h or dBZ, one instant or
            several) in place of homogeneous rain.
        resolution_m: The map's pixel, m.
        box: The area as (south latitude, west longitude, north latitude, east longitude), degrees,
            in place of the box around the start, the destination and the sites; the start and the
            destination must lie in it.
        terrain: A DEM GeoTIFF under the place ([`rainuav.ground.dem`][rainuav.ground.dem]).
        altitude_reference: "ground" (the default) or "msl".
        footprints: Building footprints in GeoJSON
            ([`rainuav.ground.footprints`][rainuav.ground.footprints]) standing on it.
        altitudes_m: The flight levels a flight chooses among (`area.altitudes_m`).
        engine: The maps' engine (default the preset's, hybrid).
        default_height_m: The roof of a footprint with neither a height nor storeys (default 10 m).
        ground: The ground's material (default: PEC on flat ground, medium-dry over a DEM:
            [`ground_over()`][rainuav.radio.scene.terrain.ground_over]).

    Returns:
        The [`Place`][rainuav.world.place.Place]: its scenario, frame and points.

    Raises:
        InvalidInputError: A file that is missing, a box that is not S < N and W < E or that leaves
            out the start or the destination, points that straddle the date line, a frequency other
            than the sites file's, or `default_height_m` without footprints.
    """
    rows = read_site_rows(sites_file)
    _check_leg(start, goal)
    freqs = {r["freq_ghz"] for r in rows if "freq_ghz" in r}
    if freqs and freqs != {freq_ghz}:
        raise InvalidInputError(f"`freq_ghz` {freq_ghz:g} differs from the sites file's "
                                f"freq_ghz {sorted(freqs)}")  # fmt: skip
    lats = [start[0], goal[0], *(r["lat"] for r in rows)]
    lons = [start[1], goal[1], *(r["lon"] for r in rows)]
    if box is not None:
        s_, w_, n_, e_ = box
        if not (-90 <= s_ < n_ <= 90 and -180 <= w_ < e_ <= 180):
            raise InvalidInputError(f"`box` must be S,W,N,E with S < N and W < E (got {box})")
        for name, (la, lo) in (("`start`", start), ("`goal`", goal)):
            if not (s_ <= la <= n_ and w_ <= lo <= e_):
                raise InvalidInputError(f"{name} {la},{lo} lies outside the `box` {box}")
        for r in rows:
            if not (s_ <= r["lat"] <= n_ and w_ <= r["lon"] <= e_):
                raise InvalidInputError(
                    f"sites file {sites_file}: site {r['site_id']} at "
                    f"{latlon_text(r['lat'], r['lon'])} lies outside the `box` {box} (every "
                    "site must lie in the area)"
                )
        lats, lons = [s_, n_], [w_, e_]
        # Its size on the sphere, before any projection (a box round the globe has no plane).
        widest = 0.0 if s_ < 0 < n_ else min(abs(s_), abs(n_))  # the latitude nearest the equator
        w = math.radians(e_ - w_) * 6371e3 * math.cos(math.radians(widest))
        _check_size(w, math.radians(n_ - s_) * 6371e3, "`box` spans")
    if max(lons) - min(lons) > 180.0:
        raise InvalidInputError("the start, destination and sites straddle the date line; "
                                "give longitudes on one side of it")  # fmt: skip
    geo = Georef((max(lats) + min(lats)) / 2.0, (max(lons) + min(lons)) / 2.0)
    sites = sites_from_rows(rows, geo, f"sites file {sites_file}")
    sx, sy = geo.to_local(*start, name="`start`")
    gx, gy = geo.to_local(*goal, name="`goal`")
    xs = [float(sx), float(gx), *(s.x_m for s in sites)]
    ys = [float(sy), float(gy), *(s.y_m for s in sites)]
    margin = MARGIN_M
    if box is not None:  # the box's corners, projected, and no margin
        cx, cy = geo.to_local(np.array([box[0], box[0], box[2], box[2]]),
                              np.array([box[1], box[3], box[1], box[3]]))  # fmt: skip
        xs, ys, margin = [float(cx.min()), float(cx.max())], [float(cy.min()), float(cy.max())], 0.0

    if box is None:
        _check_reach(sites_file, rows, geo, (float(sx), float(sy)), (float(gx), float(gy)))
    else:
        _check_size(max(xs) - min(xs), max(ys) - min(ys), "`box` spans")

    def edge(v: float, up: bool) -> float:
        f = math.ceil if up else math.floor
        return f(v / resolution_m) * resolution_m

    area = Area(
        x_min_m=edge(min(xs) - margin, False), x_max_m=edge(max(xs) + margin, True),
        y_min_m=edge(min(ys) - margin, False), y_max_m=edge(max(ys) + margin, True),
        altitude_m=altitude_m, resolution_m=resolution_m, altitude_reference=altitude_reference,
        altitudes_m=None if altitudes_m is None else [float(v) for v in altitudes_m],
    )  # fmt: skip
    base = presets.uma(rain_rate_mm_h, freq_ghz * 1e9)
    if weather is not None:
        medium = read_radar_grid(weather, area, geo, base=base.medium)
        base = dataclasses.replace(base, medium=medium)
    origin = Origin(geo.lat_deg, geo.lon_deg)
    scn = dataclasses.replace(base, name="place", area=area, sites=sites, origin=origin)
    if engine is not None:
        scn = dataclasses.replace(scn, engine=engine)
    if terrain is not None:
        if not Path(terrain).is_file():
            raise InvalidInputError(f"`terrain`: no file {terrain}")
        dem = TerrainFile(str(Path(terrain).resolve()))
        scn = dataclasses.replace(scn, terrain=dem)
    scn = dataclasses.replace(scn, ground=ground_over(terrain is not None, ground, scn.ground))
    if footprints is not None:
        if not Path(footprints).is_file():
            raise InvalidInputError(f"`footprints`: no file {footprints}")
        fp = FootprintsFile(str(Path(footprints).resolve()))
        if default_height_m is not None:
            fp = dataclasses.replace(fp, default_height_m=default_height_m)
        scn = dataclasses.replace(scn, footprints=fp)
    elif default_height_m is not None:
        raise InvalidInputError("`default_height_m` needs building footprints (`footprints`)")
    scn.check()
    return Place(scn, geo, (float(sx), float(sy)), (float(gx), float(gy)), rows)


def _check_leg(start: tuple[float, float], goal: tuple[float, float]) -> None:
    """Refuses a destination within the arrival tolerance of the take-off point (no flight
    to plan: a take-off and a landing on the spot are the autopilot's, not a plan), and one
    too far for any area fly maps (before anything is projected: a leg across the date line
    or half the globe is refused for its length)."""
    from rainuav.geo import check_latlon, geodesic_m

    check_latlon("`start`", *start)
    check_latlon("`goal`", *goal)
    d = float(geodesic_m(*start, *goal))
    if d <= ARRIVAL_TOL_M:
        raise InvalidInputError(
            f"`start` and `goal` are {d:.1f} m apart, within the arrival tolerance of "
            f"{ARRIVAL_TOL_M:g} m: there is no flight to plan (give a destination farther away)"
        )
    if d > math.sqrt(2.0) * (MAX_SIDE_M - 2 * MARGIN_M):  # cannot fit, however it turns
        raise InvalidInputError(
            f"`start` and `goal` are {d / 1e3:.1f} km apart; a place maps at most "
            f"{MAX_SIDE_M / 1e3:g} km x {MAX_SIDE_M / 1e3:g} km (the start, the destination and "
            f"the sites with a {MARGIN_M:g} m margin): plan the flight in legs"
        )


def _check_size(w: float, h: float, what: str, hint: str = "give a smaller box") -> None:
    """Refuses an area ``w`` x ``h`` m wider or taller than
    [`MAX_SIDE_M`][rainuav.world.place.MAX_SIDE_M]."""
    if max(w, h) > MAX_SIDE_M:
        raise InvalidInputError(
            f"{what} {w / 1e3:.1f} km east-west and {h / 1e3:.1f} km north-south; fly maps at "
            f"most {MAX_SIDE_M / 1e3:g} km x {MAX_SIDE_M / 1e3:g} km: {hint}"
        )


def _check_reach(
    sites_file: str | Path,
    rows: list[dict[str, Any]],
    geo: Georef,
    start_m: tuple[float, float],
    goal_m: tuple[float, float],
) -> None:
    """Refuses, in the user's terms, an area around the start, the destination and the sites
    (with [`MARGIN_M`][rainuav.world.place.MARGIN_M]) wider or taller than
    [`MAX_SIDE_M`][rainuav.world.place.MAX_SIDE_M]: naming the distance
    between the start and the destination, or the site farthest from the route."""
    (x0, x1), (y0, y1) = sorted((start_m[0], goal_m[0])), sorted((start_m[1], goal_m[1]))
    leg_w, leg_h = x1 - x0 + 2 * MARGIN_M, y1 - y0 + 2 * MARGIN_M
    if max(leg_w, leg_h) > MAX_SIDE_M:
        d = math.hypot(goal_m[0] - start_m[0], goal_m[1] - start_m[1])
        _check_size(leg_w, leg_h, f"`start` and `goal` are {d / 1e3:.1f} km apart: the route "
                    f"with its {MARGIN_M:g} m margin spans", "plan the flight in legs")  # fmt: skip
    rx, ry = geo.to_local(np.array([r["lat"] for r in rows]), np.array([r["lon"] for r in rows]))
    w = max(x1, float(rx.max())) - min(x0, float(rx.min())) + 2 * MARGIN_M
    h = max(y1, float(ry.max())) - min(y0, float(ry.min())) + 2 * MARGIN_M
    if max(w, h) <= MAX_SIDE_M:
        return
    # Each site's distance from the route's box (0 inside it).
    off = np.hypot(np.maximum(np.maximum(x0 - rx, rx - x1), 0.0),
                   np.maximum(np.maximum(y0 - ry, ry - y1), 0.0))  # fmt: skip
    far = int(np.argmax(off))
    raise InvalidInputError(
        f"sites file {sites_file}: site {rows[far]['site_id']} lies {off[far] / 1e3:.1f} km "
        f"from the route from `start` to `goal`; a place maps at most {MAX_SIDE_M / 1e3:g} km x "
        f"{MAX_SIDE_M / 1e3:g} km around the route and the sites (with a {MARGIN_M:g} m "
        "margin): leave out the sites that far away"
    )
