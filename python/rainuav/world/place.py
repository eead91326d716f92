"""A real place as a world, and a flight through it written for an autopilot
(``python -m rainuav.fly``).

[`place_scenario()`][rainuav.world.place.place_scenario]: sites from a file
([`rainuav.radio.sites`][rainuav.radio.sites]), a start and a destination in latitude and longitude,
the flight altitude, the carrier and homogeneous rain become a scenario of the ``uma`` preset's
radio settings (bandwidth, noise figure, ground, engine) over an area around the start, the
destination and the sites with a margin, in metres of a [`rainuav.geo.Georef`][rainuav.geo.Georef]
centred on that box. [`fly_place()`][rainuav.world.place.fly_place] plans the exact optimum from the
start (``rainuav.nav.planner``) and the straight line, and writes the flight
([`rainuav.missions`][rainuav.missions])."""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._io import begin_folder, write_atomic
from rainuav.errors import InvalidInputError
from rainuav.geo import Georef, latlon_text
from rainuav.missions import (
    corners,
    densify,
    expand,
    geojson_dict,
    kml_text,
    plan_dict,
    terrain_waypoints,
    wpl_text,
)
from rainuav.nav import planner
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import blocked_at, pixel_index
from rainuav.nav.task import NavConfig, base_reward
from rainuav.radio import presets
from rainuav.radio.buildings import buildings_near_route
from rainuav.radio.maps import build_radio_map
from rainuav.radio.maptiff import write_map_geotiff
from rainuav.radio.radar import read_radar_grid
from rainuav.radio.scenario import Area, FootprintsFile, Origin, Scenario, TerrainFile
from rainuav.radio.sites import read_site_rows, sites_from_rows
from rainuav.radio.terrain import (
    flight_heights_at,
    ground_over,
    obstacle_pixel_max,
    scenario_terrain,
)
from rainuav.radio.timemap import build_radio_map_series, series_times
from rainuav.world import SLICE_S, World, world_from
from rainuav.world.flightplot import plot_flight

__all__ = ["MARGIN_M", "MAX_SIDE_M", "Place", "fly_place", "place_scenario"]

MARGIN_M = 300.0
"""The area reaches this far beyond the start, the destination and the sites, m."""
MAX_SIDE_M = 10_000.0
"""The widest and tallest area a place maps, m: at 10 m it is 1e6 pixels (about 35 s and 3.5 GB
on a 2-core machine with the 9 sectors of the example), and the hybrid engine's PE march
of the ``uma`` settings carries every sector over it, from any site in it (tested with a
site in a corner pointing across the diagonal)."""
ARRIVAL_TOL_M = NavConfig.tol_m
"""A destination this close to the take-off point is reached before any move, m."""
FLIGHT_FILES = ("flight.geojson", "flight.kml", "mission.plan", "mission.waypoints",
                "flight.png", "sinr.tif", "summary.json")  # fmt: skip
"""The files of a flight, in the order they are written: ``summary.json`` last, so a folder
holding it is complete."""


@dataclass
class Place:
    """A place's scenario, its georeference, the start and destination in its metres and the
    sites as the file gave them."""

    scenario: Scenario
    georef: Georef
    start_m: tuple[float, float]
    goal_m: tuple[float, float]
    sites: list[dict[str, Any]]


def place_scenario(
    sites_file: str | Path,
    start: tuple[float, float],
    goal: tuple[float, float],
    *,
    altitude_m: float = 100.0,
    freq_ghz: float = 28.0,
    rain_rate: float = 0.0,
    weather: str | Path | None = None,
    resolution_m: float = 10.0,
    box: tuple[float, float, float, float] | None = None,
    terrain: str | Path | None = None,
    altitude_reference: str | None = None,
    footprints: str | Path | None = None,
    altitudes: list[float] | None = None,
    engine: str | None = None,
    default_height_m: float | None = None,
    ground: str | None = None,
) -> Place:
    """The place (module docstring); ``start`` and ``goal`` are (lat, lon) in degrees. ``weather``:
    a georeferenced rain file ([`rainuav.radio.radar`][rainuav.radio.radar], mm/h or dBZ, one
    instant or several) in place of homogeneous rain. ``box``: the area as (south latitude, west
    longitude, north latitude, east longitude), degrees, in place of the box around the start, the
    destination and the sites; the start and the destination must lie in it. ``terrain``: a DEM
    GeoTIFF under the place ([`rainuav.ground.dem`][rainuav.ground.dem]), with the flight altitude
    above the terrain (``altitude_reference="ground"``, the default) or above sea level (``"msl"``).
    ``footprints``: building footprints in GeoJSON
    ([`rainuav.ground.footprints`][rainuav.ground.footprints]) standing on it. ``altitudes``: the
    flight levels a flight chooses among (``area.altitudes_m``). ``engine``: the maps' engine
    (default the preset's, hybrid). ``default_height_m``: the roof of a footprint with neither a
    height nor storeys (``[footprints] default_height_m``, default 10 m). ``ground``: the ground's
    material (default: the preset's PEC on flat ground, medium-dry over a DEM:
    [`ground_over()`][rainuav.radio.terrain.ground_over])."""
    rows = read_site_rows(sites_file)
    _check_leg(start, goal)
    freqs = {r["freq_ghz"] for r in rows if "freq_ghz" in r}
    if freqs and freqs != {freq_ghz}:
        raise InvalidInputError(f"--freq-ghz {freq_ghz:g} differs from the sites file's "
                                f"freq_ghz {sorted(freqs)}")  # fmt: skip
    lats = [start[0], goal[0], *(r["lat"] for r in rows)]
    lons = [start[1], goal[1], *(r["lon"] for r in rows)]
    if box is not None:
        s_, w_, n_, e_ = box
        if not (-90 <= s_ < n_ <= 90 and -180 <= w_ < e_ <= 180):
            raise InvalidInputError(f"--area must be S,W,N,E with S < N and W < E (got {box})")
        for name, (la, lo) in (("--start", start), ("--goal", goal)):
            if not (s_ <= la <= n_ and w_ <= lo <= e_):
                raise InvalidInputError(f"{name} {la},{lo} lies outside the --area {box}")
        for r in rows:
            if not (s_ <= r["lat"] <= n_ and w_ <= r["lon"] <= e_):
                raise InvalidInputError(
                    f"sites file {sites_file}: site {r['site_id']} at "
                    f"{latlon_text(r['lat'], r['lon'])} lies outside the --area {box} (every "
                    "site must lie in the area)"
                )
        lats, lons = [s_, n_], [w_, e_]
        # Its size on the sphere, before any projection (a box round the globe has no plane).
        widest = 0.0 if s_ < 0 < n_ else min(abs(s_), abs(n_))  # the latitude nearest the equator
        w = math.radians(e_ - w_) * 6371e3 * math.cos(math.radians(widest))
        _check_size(w, math.radians(n_ - s_) * 6371e3, "--area spans")
    if max(lons) - min(lons) > 180.0:
        raise InvalidInputError("the start, destination and sites straddle the date line; "
                                "give longitudes on one side of it")  # fmt: skip
    geo = Georef((max(lats) + min(lats)) / 2.0, (max(lons) + min(lons)) / 2.0)
    sites = sites_from_rows(rows, geo, f"sites file {sites_file}")
    sx, sy = geo.to_local(*start, name="--start")
    gx, gy = geo.to_local(*goal, name="--goal")
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
        _check_size(max(xs) - min(xs), max(ys) - min(ys), "--area spans")

    def edge(v: float, up: bool) -> float:
        f = math.ceil if up else math.floor
        return f(v / resolution_m) * resolution_m

    area = Area(
        x_min_m=edge(min(xs) - margin, False), x_max_m=edge(max(xs) + margin, True),
        y_min_m=edge(min(ys) - margin, False), y_max_m=edge(max(ys) + margin, True),
        altitude_m=altitude_m, resolution_m=resolution_m, altitude_reference=altitude_reference,
        altitudes_m=None if altitudes is None else [float(v) for v in altitudes],
    )  # fmt: skip
    base = presets.uma(rain_rate, freq_ghz * 1e9)
    if weather is not None:
        medium = read_radar_grid(weather, area, geo, base=base.medium)
        base = dataclasses.replace(base, medium=medium)
    origin = Origin(geo.lat_deg, geo.lon_deg)
    scn = dataclasses.replace(base, name="place", area=area, sites=sites, origin=origin)
    if engine is not None:
        scn = dataclasses.replace(scn, engine=engine)
    if terrain is not None:
        if not Path(terrain).is_file():
            raise InvalidInputError(f"--terrain: no file {terrain}")
        dem = TerrainFile(str(Path(terrain).resolve()))
        scn = dataclasses.replace(scn, terrain=dem)
    scn = dataclasses.replace(scn, ground=ground_over(terrain is not None, ground, scn.ground))
    if footprints is not None:
        if not Path(footprints).is_file():
            raise InvalidInputError(f"--footprints: no file {footprints}")
        fp = FootprintsFile(str(Path(footprints).resolve()))
        if default_height_m is not None:
            fp = dataclasses.replace(fp, default_height_m=default_height_m)
        scn = dataclasses.replace(scn, footprints=fp)
    elif default_height_m is not None:
        raise InvalidInputError("--default-height needs building footprints (--footprints)")
    scn.check()
    return Place(scn, geo, (float(sx), float(sy)), (float(gx), float(gy)), rows)


def _check_leg(start: tuple[float, float], goal: tuple[float, float]) -> None:
    """Refuses a destination within the arrival tolerance of the take-off point (no flight
    to plan: a take-off and a landing on the spot are the autopilot's, not a plan), and one
    too far for any area fly maps (before anything is projected: a leg across the date line
    or half the globe is refused for its length)."""
    from rainuav.geo import check_latlon, geodesic_m

    check_latlon("--start", *start)
    check_latlon("--goal", *goal)
    d = float(geodesic_m(*start, *goal))
    if d <= ARRIVAL_TOL_M:
        raise InvalidInputError(
            f"--start and --goal are {d:.1f} m apart, within the arrival tolerance of "
            f"{ARRIVAL_TOL_M:g} m: there is no flight to plan (give a destination farther away)"
        )
    if d > math.sqrt(2.0) * (MAX_SIDE_M - 2 * MARGIN_M):  # cannot fit, however it turns
        raise InvalidInputError(
            f"--start and --goal are {d / 1e3:.1f} km apart; fly maps at most "
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
        _check_size(leg_w, leg_h, f"--start and --goal are {d / 1e3:.1f} km apart: the route "
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
        f"from the route from --start to --goal; fly maps at most {MAX_SIDE_M / 1e3:g} km x "
        f"{MAX_SIDE_M / 1e3:g} km around the route and the sites (with a {MARGIN_M:g} m "
        "margin): leave out the sites that far away"
    )


def fly_place(
    place: Place,
    out: Path,
    *,
    speed_m_s: float = 10.0,
    min_db: float | None = None,
    progress: bool = False,
    flyer: Callable[[UAVNavEnv], tuple[np.ndarray, bool]] | None = None,
    flown_by: str = "exact optimum",
    start_altitude_m: float | None = None,
) -> dict:
    """Builds the place's map, plans the exact optimum and the straight line from the start, writes
    [`FLIGHT_FILES`][rainuav.world.place.FLIGHT_FILES] into ``out`` (each atomically) and returns
    the summary. ``min_db``: the outage threshold of the SINR (default: the ``uma`` preset's, whose
    radio settings the place takes). ``flyer``: flies the place's env (with the weather observation)
    from its start and returns the path and whether it arrived, in place of the exact optimum (which
    stays the yardstick: ``excess_over_optimum``); ``flown_by`` names it in the summary.
    ``start_altitude_m``: with ``area.altitudes_m``, the level to start at
    ([`rainuav.world.flylevels.fly_levels()`][rainuav.world.flylevels.fly_levels])."""
    a = place.scenario.area
    if a.altitudes_m:  # altitude as a decision
        if flyer is not None:
            raise InvalidInputError("--policy flies one altitude: not with --altitudes")
        from rainuav.world.flylevels import fly_levels

        return fly_levels(place, out, speed_m_s=speed_m_s, min_db=min_db, progress=progress,
                          start_altitude_m=start_altitude_m)  # fmt: skip
    span = abs(place.goal_m[0] - place.start_m[0]) + abs(place.goal_m[1] - place.start_m[1])
    steps = math.ceil(2.0 * span / 10.0) + 50  # room for a detour twice the direct route
    scn = place.scenario
    if scn.medium.moves:  # the weather of a file with several instants: maps every 5 s
        horizon = math.ceil(steps * 10.0 / speed_m_s / SLICE_S) * SLICE_S
        if scn.engine == "pe":
            scn = dataclasses.replace(scn, engine="hybrid")
        rm: Any = build_radio_map_series(scn, series_times(horizon, SLICE_S), progress=progress)
    else:
        rm = build_radio_map(scn, progress=progress)
    threshold = presets.SINR_THRESHOLDS_DB["uma"] if min_db is None else min_db
    task = NavConfig(
        goal_m=place.goal_m, start_m=place.start_m, max_steps=steps, speed_m_s=speed_m_s,
        min_db=threshold,
    )  # fmt: skip
    world: World = world_from(rm, task)
    for name, (x, y) in (("--start", place.start_m), ("--goal", place.goal_m)):
        if blocked_at(world.field, x, y):
            lat, lon = place.georef.to_latlon(x, y)
            raise InvalidInputError(
                f"{name} {latlon_text(float(lat), float(lon))} lies where the UAV may not "
                f"fly: terrain or obstacles within {scn.area.clearance_m:g} m of the flight "
                "height (fly higher with --altitude-m, or move the point)"
            )
    env = world.env()
    best = planner.optimal(env, np.asarray(place.start_m))
    straight = planner.straight_line(env, np.asarray(place.start_m))
    if np.hypot(*(best.path_m[-1] - np.asarray(place.goal_m))) > task.tol_m:
        raise InvalidInputError(f"no flight reaches the destination within {steps} moves")
    path = best.path_m
    if flyer is not None:
        path, arrived = flyer(dataclasses.replace(world, observation="weather").env())
        if not arrived:
            raise InvalidInputError(
                f"the {flown_by} does not reach the destination within {steps} moves "
                "(fly without --policy for the exact plan)"
            )
    merged = expand(path[corners(path)], task.step_m)
    if merged.shape != path.shape or not np.allclose(merged, path, atol=1e-6):
        raise AssertionError("the waypoints do not fly the planned path")  # never: tested
    t_s = np.arange(len(path)) * task.move_s
    sinr = env.field(path[:, 0], path[:, 1], t_s)
    serving = env.field.serving_cell(path[:, 0], path[:, 1], t_s)
    lat, lon = place.georef.to_latlon(path[:, 0], path[:, 1])
    ll = np.stack([lat, lon], axis=1)
    min_db = float(world.task.min_db)
    cost_best = -(best.return_ - task.goal_reward)
    if flyer is None:
        cost = cost_best
    else:  # the flight's moves and shortfall, as the task charges them
        cost = float(-base_reward(sinr[1:], env.cfg).sum())
    # A straight line that leaves the area or flies into ground it may not enter does not
    # arrive: it has no cost to compare, and the summary says so.
    straight_arrives = bool(
        np.hypot(*(straight.path_m[-1] - np.asarray(place.goal_m))) <= task.tol_m
    )
    cost_straight = -(straight.return_ - task.goal_reward) if straight_arrives else None
    mission = mission_heights(scn, path)  # once: the summary counts what _write writes
    summary = {
        "flown_by": flown_by, "cost": cost, "optimal_cost": cost_best,
        "excess_over_optimum": (cost - cost_best) / cost_best,
        "straight_line_arrives": straight_arrives,
        "straight_line_cost": cost_straight,
        "excess_of_straight_line": None if cost_straight is None else (cost_straight - cost) / cost,
        "outage_share": float(np.mean(sinr[1:] < min_db)),
        "straight_line_outage_share": float(np.mean(env.field(
            straight.path_m[1:, 0], straight.path_m[1:, 1],
            np.arange(1, len(straight.path_m)) * task.move_s) < min_db)),
        "weather_moves": bool(scn.medium.moves),
        "flight_time_s": float(t_s[-1]), "moves": len(path) - 1,
        "waypoints": len(mission[0]), "min_db": min_db,
        "origin": {"lat": place.georef.lat_deg, "lon": place.georef.lon_deg,
                   "projection": place.georef.proj4},
        "area_m": [a.x_min_m, a.x_max_m, a.y_min_m, a.y_max_m],
        **(buildings_near_route(scn, path) or {}),
    }  # fmt: skip
    _write(place, out, ll, path, t_s, sinr, serving, min_db, summary, rm, mission)
    return summary


def mission_heights(scn: Scenario, path: np.ndarray) -> tuple[np.ndarray, Any, float]:
    """The mission's waypoints along ``path`` (K, 2: local metres), their heights above mean sea
    level (None over flat open ground: the flight altitude relative to home) and home's height: over
    terrain, [`rainuav.missions.terrain_waypoints()`][rainuav.missions.terrain_waypoints] on the
    path sampled [`rainuav.missions.SAMPLES_PER_MOVE`][rainuav.missions.SAMPLES_PER_MOVE] times a
    move, with the planned flight height and the highest terrain or obstacle of the pixel under each
    sample."""
    t = scenario_terrain(scn)
    if t is None:
        return path[corners(path)], None, 0.0
    a = scn.area
    dense = densify(path, a.resolution_m)
    x, y = dense[:, 0], dense[:, 1]
    z = flight_heights_at(scn, x, y)
    top = (t.pixel_max(a.shape) + obstacle_pixel_max(scn))[pixel_index(a.shape, a.bounds, x, y)]
    picks = terrain_waypoints(dense, z, top, a.clearance_m)
    return dense[picks], z[picks], float(t.at(x[0], y[0]))


def _write(place: Place, out: Path, ll: np.ndarray, path: np.ndarray, t_s: np.ndarray,
           sinr: np.ndarray, serving: np.ndarray, min_db: float, summary: dict,
           rm: Any, mission: tuple[np.ndarray, Any, float]) -> None:  # fmt: skip
    begin_folder(out, "summary.json")
    alt = place.scenario.area.altitude_m
    wp_m, heights, home_amsl = mission  # mission_heights' waypoints, heights and home
    wp = np.stack(place.georef.to_latlon(wp_m[:, 0], wp_m[:, 1]), axis=1)
    home = (float(ll[0, 0]), float(ll[0, 1]))
    props = {
        "t_s": t_s.tolist(), "sinr_db": np.round(sinr, 3).tolist(),
        "serving_cell": [int(c) for c in serving], "outage": [bool(s < min_db) for s in sinr],
    }  # fmt: skip
    sites = [{k: r[k] for k in ("site_id", "lat", "lon", "height_m", "azimuth_deg")}
             for r in place.sites]  # fmt: skip
    texts = {
        "flight.geojson": json.dumps(geojson_dict(ll, alt, props, sites, summary), indent=1),
        "flight.kml": kml_text(ll, alt, "rainuav flight", sites),
        "mission.plan": json.dumps(plan_dict(home, wp, alt, 10.0, heights, home_amsl), indent=2),
        "mission.waypoints": wpl_text(home, wp, alt, heights, home_amsl),
    }
    for name, text in texts.items():
        write_atomic(out / name, lambda tmp, text=text: tmp.write_text(text + "\n"))
    plot_flight(rm, path, place, out / "flight.png")
    # The map at take-off for a GIS (SINR, serving power and cell, not flyable).
    write_map_geotiff(rm, out / "sinr.tif", None if rm.sinr_db.ndim == 2 else 0)
    done = json.dumps(summary, indent=2) + "\n"  # last: the folder is complete
    write_atomic(out / "summary.json", lambda tmp: tmp.write_text(done))
