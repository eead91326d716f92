"""``fly`` with altitude as a decision (``--altitudes-m``): the place mapped at each flight level
([`rainuav.radio.outputs.levelmaps`][rainuav.radio.outputs.levelmaps]), the exact plan among them
([`rainuav.nav.planner.optimal_levels()`][rainuav.nav.planner.optimal_levels]: climbs and descents
weighted by their duration) from the take-off level the planner finds best (of those flyable at the
start; or the one given), and the flight's files with a height on every waypoint (relative to home;
over a DEM, above sea level, with as many waypoints as keep every straight leg, climb or descent the
clearance above the ground).

Beside the plan, the summary holds the baselines: the exact plan held at the level nearest
``--altitude-m`` (the paper's single altitude) and the best single level for this flight
(the exact plan at each level, chosen with hindsight), each with its cost and outage share.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

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
from rainuav.nav.field import pixel_index
from rainuav.nav.task import NavConfig
from rainuav.radio.outputs.maptiff import write_map_geotiff
from rainuav.radio.outputs.timemap import series_times
from rainuav.radio.scene import presets
from rainuav.radio.scene.buildings import buildings_near_route
from rainuav.radio.scene.terrain import obstacle_pixel_max, scenario_terrain
from rainuav.world import SLICE_S, level_field
from rainuav.world.place import Place

__all__ = ["fly_levels"]


# Long: the command's flight among levels read top to bottom (the plan, the baselines at each
# level, the waypoints over terrain with their holds, the files, the figure); each step writes
# a part of the summary the next ones extend.
def fly_levels(
    place: Place, out: Path, *, speed_m_s: float = 10.0, min_db: float | None = None,
    progress: bool = False, start_altitude_m: float | None = None,
) -> dict:  # fmt: skip
    """Plans and writes the flight among a place's levels (the module's docstring).

    Args:
        place: The place, with `area.altitudes_m`.
        out: The output folder.
        speed_m_s: The ground speed, m/s.
        min_db: The SINR's outage threshold, dB.
        progress: A line on standard error per map built.
        start_altitude_m: The level to start at; None: the planner's choice, the level whose optimum
            is best among those the start may be flown at (the summary names it).

    Returns:
        The summary.

    Raises:
        InvalidInputError: A start or destination off the map, a start level the UAV may not fly, or
            no flight that reaches the destination.
    """
    scn = place.scenario
    if scn.area.msl and scn.terrain is not None:
        raise InvalidInputError(
            "--altitudes-m over --terrain are above the ground: not with --altitude-reference msl"
        )
    alts = np.asarray(scn.area.levels, dtype=float)
    probe = NavConfig(speed_m_s=speed_m_s)
    climb, descend = planner.level_durations(alts, probe)
    span = abs(place.goal_m[0] - place.start_m[0]) + abs(place.goal_m[1] - place.start_m[1])
    # Room for a detour twice the direct route and for crossing the band up and down.
    steps = math.ceil(2.0 * span / probe.step_m) + 50 + sum(climb) + sum(descend)
    times = None
    if scn.medium.moves:  # the weather of a file with several instants: maps every 5 s
        times = series_times(math.ceil(steps * probe.move_s / SLICE_S) * SLICE_S, SLICE_S)
    field, source = level_field(scn, times, progress=progress)
    sinr, blocked, extent = source.sinr_db, source.not_flyable, source.extent
    threshold = presets.SINR_THRESHOLDS_DB["uma"] if min_db is None else min_db
    task = NavConfig(goal_m=place.goal_m, start_m=place.start_m, max_steps=steps,
                     speed_m_s=speed_m_s, min_db=threshold)  # fmt: skip
    shape, bounds = blocked.shape[1:], scn.area.bounds

    flyable = field.flyable
    for name, (x, y) in (("--start", place.start_m), ("--goal", place.goal_m)):
        if not flyable(x, y).any():
            lat, lon = place.georef.to_latlon(x, y)
            raise InvalidInputError(
                f"{name} {latlon_text(float(lat), float(lon))} lies where the UAV may not fly "
                f"at any of --altitudes-m: obstacles within {scn.area.clearance_m:g} m"
            )
    start_level = -1  # the exact planner's choice: the level whose optimum is best
    if start_altitude_m is not None:
        start_level = int(np.argmin(np.abs(alts - start_altitude_m)))
        if not flyable(*place.start_m)[start_level]:
            raise InvalidInputError(
                f"--start altitude {start_altitude_m:g} m: the UAV may not fly there (obstacles "
                f"within {scn.area.clearance_m:g} m); the lowest level it may start at is "
                f"{alts[np.flatnonzero(flyable(*place.start_m))[0]]:g} m"
            )
    plan = planner.optimal_levels(sinr, alts, extent, task, [place.start_m], [start_level],
                                  t_s=times, not_flyable=blocked)[0]  # fmt: skip
    if np.hypot(*(plan.path_m[-1] - np.asarray(place.goal_m))) > task.tol_m:
        raise InvalidInputError(f"no flight reaches the destination within {steps} moves")
    path, lv = plan.path_m, plan.levels
    chosen_by = "planner" if start_level < 0 else "--start"
    start_level = int(lv[0])
    up, down = plan.actions == 4, plan.actions == 5
    t_s = plan.ticks * task.move_s
    sig = field(path[:, 0], path[:, 1], t_s, level=lv)
    serving = field.serving_cell(path[:, 0], path[:, 1], t_s, lv)
    cost = -(plan.return_ - task.goal_reward)
    # The baselines: each level alone, exactly (in space-time where the weather moves).
    per_level = []
    for k in range(len(alts)):
        p = planner.plan_on(field.level(k), task, np.asarray(place.start_m)[None])[0]
        arrives = bool(np.hypot(*(p.path_m[-1] - np.asarray(place.goal_m))) <= task.tol_m)
        q = p.path_m[1:]
        s = field(q[:, 0], q[:, 1], np.arange(1, len(p.path_m)) * task.move_s, level=k)
        per_level.append((-(p.return_ - task.goal_reward) if arrives else None,
                          float(np.mean(s < threshold)) if arrives else None))  # fmt: skip
    fixed = int(np.argmin(np.abs(alts - scn.area.altitude_m)))
    arriving = [k for k, (c, _) in enumerate(per_level) if c is not None]
    best_single = min(arriving, key=lambda k: per_level[k][0]) if arriving else None
    # Waypoints: the corners of the path in three dimensions (a change of height is one).
    xyz = np.column_stack([path, lv * task.step_m])
    picks = corners(xyz)
    if not np.allclose(expand(xyz[picks], task.step_m), xyz, atol=1e-6):
        raise AssertionError("the waypoints do not fly the planned path")  # never: tested
    lat, lon = place.georef.to_latlon(path[:, 0], path[:, 1])
    ll = np.stack([lat, lon], axis=1)
    z = alts[lv]
    # Over terrain: heights above sea level, with as many waypoints as keep each straight
    # climb, descent or leg within the hold of the planned height above the ground and at
    # least the clearance above the ground and the obstacles (checked along the legs).
    heights, home_amsl, wp_ll, wp_z = None, 0.0, ll[picks], z[picks]
    t = scenario_terrain(scn)
    if t is not None:
        dense = densify(xyz, task.step_m)
        dz = np.interp(dense[:, 2] / task.step_m, np.arange(len(alts)), alts)
        ground = t.at(dense[:, 0], dense[:, 1])
        under = pixel_index(shape, bounds, dense[:, 0], dense[:, 1])
        top = (t.pixel_max(shape) + obstacle_pixel_max(scn))[under]
        picks = terrain_waypoints(dense, ground + dz, top, scn.area.clearance_m)
        heights, home_amsl = (ground + dz)[picks], float(ground[0])
        wp_ll = np.stack(place.georef.to_latlon(dense[picks, 0], dense[picks, 1]), axis=1)
        wp_z = dz[picks]
    if times is None:  # one sample's outage as a probability, each move on its level's map
        from rainuav.radio.measured.outage import flight_outage_among_levels, path_outage

        prob = flight_outage_among_levels(source.maps, path[1:], lv[1:], threshold)
        chance: dict = {"spreads": "the prior's by mechanism, each move on its level's map",
                        **path_outage(prob)}  # fmt: skip
    else:
        chance = {"spreads": None, "why": "the maps of every level in a moving weather hold "
                  "SINR alone: no cell's power to draw"}  # fmt: skip
    summary = {
        "flown_by": "exact optimum among levels", "cost": cost, "optimal_cost": cost,
        "excess_over_optimum": 0.0, "outage_share": float(np.mean(sig[1:] < threshold)),
        "altitudes_m": alts.tolist(), "start_altitude_m": float(alts[start_level]),
        "start_altitude_chosen_by": chosen_by,
        "climbs": int(up.sum()), "descents": int(down.sum()),
        "fixed_altitude_m": float(alts[fixed]), "fixed_altitude_cost": per_level[fixed][0],
        "fixed_altitude_outage_share": per_level[fixed][1], "weather_moves": times is not None,
        "best_single_altitude_m": None if best_single is None else float(alts[best_single]),
        "best_single_altitude_cost": None if best_single is None else per_level[best_single][0],
        "flight_time_s": float(t_s[-1]), "moves": len(plan.actions), "waypoints": len(picks),
        "min_db": float(threshold), "outage_chance": chance,
        "origin": {"lat": place.georef.lat_deg, "lon": place.georef.lon_deg,
                   "projection": place.georef.proj4},
        "area_m": list(scn.area.bounds),
        **(buildings_near_route(scn, path) or {}),
    }  # fmt: skip
    begin_folder(out, "summary.json")
    home = (float(ll[0, 0]), float(ll[0, 1]))
    props = {
        "t_s": t_s.tolist(), "sinr_db": np.round(sig, 3).tolist(),
        "serving_cell": [int(c) for c in serving], "outage": [bool(s < threshold) for s in sig],
        "altitude_m": z.tolist(),
    }  # fmt: skip
    sites = [{k: r[k] for k in ("site_id", "lat", "lon", "height_m", "azimuth_deg")}
             for r in place.sites]  # fmt: skip
    texts = {
        "flight.geojson": json.dumps(geojson_dict(ll, z, props, sites, summary), indent=1),
        "flight.kml": kml_text(ll, z, "rainuav flight", sites),
        "mission.plan": json.dumps(
            plan_dict(home, wp_ll, wp_z, speed_m_s, heights, home_amsl), indent=2
        ),
        "mission.waypoints": wpl_text(home, wp_ll, wp_z, heights, home_amsl),
    }
    for name, text in texts.items():
        write_atomic(out / name, lambda tmp, text=text: tmp.write_text(text + "\n"))
    # The figure and the GIS map: the start level's map (at take-off where the weather moves).
    rm = source.maps[start_level] if times is None else source.at_take_off[start_level]
    plot_flight(rm, path, place, out / "flight.png", heights=(t_s, z, sig < threshold))
    write_map_geotiff(rm, out / "sinr.tif")
    done = json.dumps(summary, indent=2) + "\n"
    write_atomic(out / "summary.json", lambda tmp: tmp.write_text(done))
    return summary
