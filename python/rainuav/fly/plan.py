"""The ``fly`` command's plan at a place: the map, the exact optimum (or a network's flight) and
the straight line from the start, and the files an autopilot and a person read
([`FLIGHT_FILES`][rainuav.fly.plan.FLIGHT_FILES]); among flight levels,
[`rainuav.fly.heights`][rainuav.fly.heights]. The place itself (sites, weather, terrain and
footprints in latitude and longitude, as a scenario) is the library's
([`rainuav.world.place`][rainuav.world.place])."""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._io import begin_folder, write_atomic
from rainuav.errors import InvalidInputError
from rainuav.fly.figure import plot_flight
from rainuav.geo import latlon_text
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
from rainuav.nav.field import pixel_index
from rainuav.nav.task import NavConfig, base_reward
from rainuav.radio.engines import for_time
from rainuav.radio.outputs.maps import build_radio_map
from rainuav.radio.outputs.maptiff import write_map_geotiff
from rainuav.radio.outputs.timemap import build_radio_map_series, series_times
from rainuav.radio.scene import presets
from rainuav.radio.scene.buildings import buildings_near_route
from rainuav.radio.scene.scenario import Scenario
from rainuav.radio.scene.terrain import (
    flight_heights_at,
    obstacle_pixel_max,
    scenario_terrain,
)
from rainuav.world import SLICE_S, World, world_from
from rainuav.world.place import Place

__all__ = ["FLIGHT_FILES", "fly_place", "mission_heights"]

FLIGHT_FILES = ("flight.geojson", "flight.kml", "mission.plan", "mission.waypoints",
                "flight.png", "sinr.tif", "summary.json")  # fmt: skip
"""The files of a flight, in the order they are written: ``summary.json`` last, so a folder
holding it is complete."""


# Long: the command's flight read top to bottom (the maps, the plan, the straight line and the
# baselines, the waypoints, the mission files, the figure); each step writes a part of the
# summary the next ones extend.
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
    measurements: Path | None = None,
) -> dict:
    """Builds a place's map, plans the flight and writes its files.

    [`FLIGHT_FILES`][rainuav.fly.plan.FLIGHT_FILES] go into `out`, each atomically.

    Args:
        place: The place ([`place_scenario()`][rainuav.world.place.place_scenario]).
        out: The output folder.
        speed_m_s: The ground speed, m/s.
        min_db: The SINR's outage threshold, dB (default: the `uma` preset's, whose radio settings
            the place takes).
        progress: A line on standard error per map built.
        flyer: Flies the place's env (with the weather observation) from its start and returns the
            path and whether it arrived, in place of the exact optimum (which stays the yardstick:
            `excess_over_optimum`).
        flown_by: The flyer's name in the summary.
        start_altitude_m: Among levels, the level to start at
            ([`fly_levels()`][rainuav.fly.heights.fly_levels]).
        measurements: A drive-test or flight log that corrects the map before the plan
            ([`rainuav.radio.measured`][rainuav.radio.measured]); the summary then gives the plan's
            expected outage and its spread, `fit.json` the fit.

    Returns:
        The summary (`summary.json`).

    Raises:
        InvalidInputError: A start or destination off the map, no flight that reaches the
            destination, or a log or a policy with flight levels.
    """
    a = place.scenario.area
    if measurements is not None and (a.altitudes_m or place.scenario.medium.moves):
        raise InvalidInputError("--measurements corrects one map: not with --altitudes-m or a "
                                "--weather file in time")  # fmt: skip
    if a.altitudes_m:  # altitude as a decision
        if flyer is not None:
            raise InvalidInputError("--policy flies one altitude: not with --altitudes-m")
        from rainuav.fly.heights import fly_levels

        return fly_levels(place, out, speed_m_s=speed_m_s, min_db=min_db, progress=progress,
                          start_altitude_m=start_altitude_m)  # fmt: skip
    span = abs(place.goal_m[0] - place.start_m[0]) + abs(place.goal_m[1] - place.start_m[1])
    steps = math.ceil(2.0 * span / 10.0) + 50  # room for a detour twice the direct route
    scn = place.scenario
    if scn.medium.moves:  # the weather of a file with several instants: maps every 5 s
        horizon = math.ceil(steps * 10.0 / speed_m_s / SLICE_S) * SLICE_S
        scn = for_time(scn)
        rm: Any = build_radio_map_series(scn, series_times(horizon, SLICE_S), progress=progress)
    else:
        rm = build_radio_map(scn, progress=progress)
    if measurements is not None:
        rm = _corrected(place, rm, measurements)
    threshold = presets.SINR_THRESHOLDS_DB["uma"] if min_db is None else min_db
    task = NavConfig(
        goal_m=place.goal_m, start_m=place.start_m, max_steps=steps, speed_m_s=speed_m_s,
        min_db=threshold,
    )  # fmt: skip
    world: World = world_from(rm, task)
    for name, (x, y) in (("--start", place.start_m), ("--goal", place.goal_m)):
        if world.field.blocked(x, y):
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
    from rainuav.radio.measured.outage import (
        flight_outage_in_time,
        outage_probability,
        path_outage,
        path_outage_draws,
    )

    if hasattr(rm, "rss_std_db"):  # one map: outage as a probability, from its spreads
        r, c = pixel_index(rm.sinr_db.shape, rm.extent_m, path[1:, 0], path[1:, 1])
        prob = outage_probability(rm, min_db, pixels=(r, c), draws=4096)  # the path's pixels
        summary["outage_chance"] = {
            "spreads": "the prior's by mechanism" if rm.fit is None else "the measurements'",
            **path_outage(prob),
            "along_path": path_outage_draws(rm, (r, c), min_db),
        }
        if rm.fit is not None:
            summary["measurements"] = {"log": rm.fit["log"],
                                       "cross_validation": rm.fit["cross_validation"],
                                       **path_outage(prob)}  # fmt: skip
    elif world.varies:  # maps in time, a weather that moves: each move on its own slice
        summary["outage_chance"] = {
            "spreads": "the prior's by mechanism, each move on the map of the slice it lands in",
            **path_outage(flight_outage_in_time(rm, path[1:], t_s[1:], min_db)),
        }
    _write(place, out, ll, path, t_s, sinr, serving, min_db, summary, rm, mission)
    return summary


def mission_heights(scn: Scenario, path: np.ndarray) -> tuple[np.ndarray, Any, float]:
    """The mission's waypoints along a path, their heights and home's height.

    Over terrain, [`terrain_waypoints()`][rainuav.missions.terrain_waypoints] on the path sampled
    [`SAMPLES_PER_MOVE`][rainuav.missions.SAMPLES_PER_MOVE] times a move, with the planned flight
    height and the highest terrain or obstacle of the pixel under each sample.

    Args:
        scn: The place's scenario.
        path: The path (K, 2), local metres.

    Returns:
        `(waypoints, heights or None over flat open ground (relative to home), home's height)`.
    """
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


def _corrected(place: Place, rm: Any, log_path: Path) -> Any:
    from rainuav.radio.measured import correct_map, read_log
    from rainuav.radio.scene.sites import cell_names

    scn = place.scenario
    log = read_log(log_path, scn, cell_names=cell_names(place.sites),
                   altitude_reference=scn.area.altitude_reference or "ground")  # fmt: skip
    print(log.summary(), file=sys.stderr)
    return correct_map(rm, log, progress=True)


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
    if getattr(rm, "fit", None) is not None:
        fit = json.dumps(rm.fit, indent=2) + "\n"
        write_atomic(out / "fit.json", lambda tmp: tmp.write_text(fit))
    done = json.dumps(summary, indent=2) + "\n"  # last: the folder is complete
    write_atomic(out / "summary.json", lambda tmp: tmp.write_text(done))
