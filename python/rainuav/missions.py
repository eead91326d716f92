"""Flight plans out: a lattice path as a few waypoints, and the files a ground
station or a GIS loads.

- [`corners()`][rainuav.missions.corners]: the vertices of a lattice path where its direction
  changes (and its two ends). Flying straight between them is the same path, move for move
  ([`expand()`][rainuav.missions.expand]).
- [`wpl_text()`][rainuav.missions.wpl_text]: QGroundControl's plain-text mission (``QGC WPL 110``,
  as MAVLink documents it: tab-separated, ``INDEX CURRENT FRAME COMMAND P1 P2 P3 P4 LAT LON ALT
  AUTOCONTINUE``): home, take-off, the waypoints at the flight altitude relative to home, landing.
- [`plan_dict()`][rainuav.missions.plan_dict]: the same mission as a QGroundControl ``.plan`` (JSON,
  the fields QGC's developer guide lists: ``fileType``, ``version``, ``groundStation``, ``mission``
  with ``items``, ``plannedHomePosition``, ``firmwareType``, ``vehicleType``, ``cruiseSpeed``,
  ``hoverSpeed``, ``globalPlanAltitudeMode``; ``geoFence`` and ``rallyPoints`` empty).
- [`geojson_dict()`][rainuav.missions.geojson_dict]: the path as a GeoJSON ``LineString`` (RFC 7946:
  longitude, latitude, altitude) with per-vertex properties, and the sites as points.
- [`kml_text()`][rainuav.missions.kml_text]: the same for Google Earth (altitude relative to the
  ground).
- Over terrain ([`terrain_waypoints()`][rainuav.missions.terrain_waypoints]): the waypoints carry
  altitudes above mean sea level (MAVLink's ``MAV_FRAME_GLOBAL``, QGroundControl's absolute altitude
  mode), the terrain under each plus the flight altitude, and there are enough of them that the
  straight line the autopilot flies between two holds the planned height above the ground within
  [`HOLD_M`][rainuav.missions.HOLD_M] along the whole leg (checked
  [`SAMPLES_PER_MOVE`][rainuav.missions.SAMPLES_PER_MOVE] times a move against the DEM) and never
  passes closer to the terrain and obstacles under the path than the clearance. Above sea level
  rather than MAVLink's terrain frame (``MAV_FRAME_GLOBAL_TERRAIN_ALT``): the autopilot then flies
  the heights the map was made for, over the DEM the map was made on, not those of its own terrain
  database.

Coordinates in: latitude and longitude in degrees (WGS 84), from
[`rainuav.geo.Georef`][rainuav.geo.Georef]."""

from __future__ import annotations

import itertools
from typing import Any
from xml.sax.saxutils import escape

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError

__all__ = [
    "HOLD_M",
    "MAV_CMD_NAV_LAND",
    "MAV_CMD_NAV_TAKEOFF",
    "MAV_CMD_NAV_WAYPOINT",
    "SAMPLES_PER_MOVE",
    "corners",
    "densify",
    "expand",
    "geojson_dict",
    "kml_text",
    "mission_items",
    "plan_dict",
    "terrain_waypoints",
    "wpl_text",
]

MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_LAND = 21
MAV_CMD_NAV_TAKEOFF = 22
MAV_FRAME_GLOBAL = 0
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
LATLON = ("lat", "lon")


def corners(path: npt.ArrayLike) -> np.ndarray:
    """The vertices of a lattice path where its direction changes: the waypoints that fly it.

    The first and the last vertex are among them; a change of height is a corner too.

    Args:
        path: The path's vertices (T+1, 2), or (T+1, 3) with a height.

    Returns:
        The corners' indices into `path`.

    Raises:
        InvalidInputError: A path that is not a finite (T+1, 2) or (T+1, 3) array.
    """
    p = np.asarray(path, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] not in (2, 3) or len(p) < 1 or not np.all(np.isfinite(p)):
        raise InvalidInputError(f"path must be a finite (T+1, 2) or (T+1, 3) array (got {p.shape})")
    if len(p) < 3:
        return np.arange(len(p))
    d = np.diff(p, axis=0)
    unit = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)
    turn = np.flatnonzero(np.linalg.norm(unit[1:] - unit[:-1], axis=1) > 1e-6) + 1
    return np.concatenate([[0], turn, [len(p) - 1]])


def expand(points: npt.ArrayLike, step_m: float) -> np.ndarray:
    """The lattice path that flies straight between points in moves of one step.

    Each leg is a whole number of moves along one axis, as [`corners()`][rainuav.missions.corners]
    leaves them.

    Args:
        points: The waypoints (K, 2), m.
        step_m: The move, m.

    Returns:
        The path's vertices (T+1, 2), m.
    """
    pts = np.asarray(points, dtype=np.float64)
    out = [pts[0]]
    for a, b in itertools.pairwise(pts):
        n = round(float(np.abs(b - a).sum()) / step_m)
        out += [a + (b - a) * k / n for k in range(1, n + 1)]
    return np.array(out)


HOLD_M = 5.0
"""Over terrain, how far the straight line between two waypoints may stray from the planned height
above the ground at any point of the leg, m (checked every
[`SAMPLES_PER_MOVE`][rainuav.missions.SAMPLES_PER_MOVE]-th of a move: the height the map was made
for, flown within this)."""
SAMPLES_PER_MOVE = 4
"""The points of each move where a leg is checked against the ground
([`densify()`][rainuav.missions.densify])."""


def densify(path: npt.ArrayLike, step_m: float, samples: int = SAMPLES_PER_MOVE) -> np.ndarray:
    """A lattice path sampled finely enough to check against the ground: the same straight legs.

    Args:
        path: The path (T+1, 2 or 3), in moves of `step_m`.
        step_m: The move, m.
        samples: Points a move.

    Returns:
        The sampled path (T samples + 1, of `path`'s columns).
    """
    p = np.asarray(path, dtype=np.float64)
    if len(p) < 2:
        return p.copy()
    return expand(p[corners(p)], step_m / samples)


def terrain_waypoints(
    path: npt.ArrayLike,
    height_amsl_m: npt.ArrayLike,
    top_amsl_m: npt.ArrayLike,
    clearance_m: float,
    hold_m: float | None = HOLD_M,
) -> np.ndarray:
    """The waypoints that fly a path over terrain: its corners, and as few more as the ground asks.

    Within each straight leg, as few more waypoints as keep the straight line between two waypoints'
    heights within `hold_m` of the planned height and at least `clearance_m` above the highest
    terrain or obstacle under each vertex (greedy: each waypoint as far along the leg as the checks
    allow). Give a path sampled finely ([`densify()`][rainuav.missions.densify]): the checks are at
    its vertices.

    Args:
        path: The path (N, 2 or 3), m.
        height_amsl_m: The planned flight height over each vertex (N,), m above mean sea level.
        top_amsl_m: The highest terrain or obstacle under each vertex (N,), m.
        clearance_m: The least height above `top_amsl_m`, m.
        hold_m: How far from the planned height a leg may stray, m; None: any.

    Returns:
        The waypoints' indices into `path`.

    Raises:
        InvalidInputError: Heights that are not one a vertex.
    """
    z = np.asarray(height_amsl_m, dtype=np.float64)
    top = np.asarray(top_amsl_m, dtype=np.float64)
    turns = corners(path)
    if z.shape != (len(np.asarray(path)),) or top.shape != z.shape:
        raise InvalidInputError("height_amsl_m and top_amsl_m need one value per path vertex")
    hold = np.inf if hold_m is None else float(hold_m)
    keep = [int(turns[0])]
    for a0, b0 in itertools.pairwise(turns):
        a = int(a0)
        while a < b0:
            b = int(b0)
            while b > a + 1:
                k = np.arange(a + 1, b)
                line = z[a] + (z[b] - z[a]) * (k - a) / (b - a)
                if np.all(line - top[k] >= clearance_m) and np.all(np.abs(line - z[k]) <= hold):
                    break
                b -= 1
            keep.append(b)
            a = b
    return np.array(keep)


def mission_items(
    home: tuple[float, float],
    waypoints: npt.ArrayLike,
    altitude_m: npt.ArrayLike,
    altitudes_amsl_m: npt.ArrayLike | None = None,
) -> list[dict[str, Any]]:
    """The mission: take-off at home, the waypoints, landing at the last one.

    Each item has `command`, `frame` and `params` (7: param1-4, latitude, longitude, altitude).

    Args:
        home: `(lat, lon)` of the take-off, degrees.
        waypoints: The waypoints (K, 2) of (lat, lon), degrees.
        altitude_m: The height above home, m: one, or one a waypoint (K,) for a flight that changes
            height.
        altitudes_amsl_m: Heights above mean sea level (K,), m, in place of `altitude_m`
            (`MAV_FRAME_GLOBAL`; the take-off climbs to the first waypoint's height).

    Returns:
        The items, in order.

    Raises:
        InvalidInputError: Heights outside 0.5-3000 m, or not one a waypoint.
    """
    wps = np.asarray(waypoints, dtype=np.float64).reshape(-1, 2)
    if altitudes_amsl_m is None:
        rel_alts = np.asarray(altitude_m, dtype=np.float64).reshape(-1)
        if rel_alts.size == 1:
            rel_alts = np.full(len(wps), float(rel_alts[0]))
        if rel_alts.shape != (len(wps),) or not np.all((rel_alts >= 0.5) & (rel_alts <= 3000.0)):
            raise InvalidInputError(
                f"altitude_m must be in [0.5, 3000] m, one value or one a waypoint "
                f"(got {altitude_m!r})"
            )
        frame, alts = MAV_FRAME_GLOBAL_RELATIVE_ALT, rel_alts
        climb = float(rel_alts[0])
    else:
        alts = np.asarray(altitudes_amsl_m, dtype=np.float64).reshape(-1)
        if alts.shape != (len(wps),) or not np.all(np.isfinite(alts)):
            raise InvalidInputError("altitudes_amsl_m must hold one finite height per waypoint")
        frame, climb = MAV_FRAME_GLOBAL, float(alts[0])
    rel = MAV_FRAME_GLOBAL_RELATIVE_ALT
    items = [
        {"command": MAV_CMD_NAV_TAKEOFF, "frame": frame,
         "params": [0.0, 0.0, 0.0, None, home[0], home[1], climb]},
    ]  # fmt: skip
    for (lat, lon), alt in zip(wps, alts, strict=True):
        items.append(
            {"command": MAV_CMD_NAV_WAYPOINT, "frame": frame,
             "params": [0.0, 0.0, 0.0, None, float(lat), float(lon), float(alt)]}
        )  # fmt: skip
    lat, lon = wps[-1]
    items.append(
        {"command": MAV_CMD_NAV_LAND, "frame": rel,
         "params": [0.0, 0.0, 0.0, None, float(lat), float(lon), 0.0]}
    )  # fmt: skip
    return items


def wpl_text(
    home: tuple[float, float],
    waypoints: npt.ArrayLike,
    altitude_m: npt.ArrayLike,
    altitudes_amsl_m: npt.ArrayLike | None = None,
    home_amsl_m: float = 0.0,
) -> str:
    """The mission as `QGC WPL 110` text.

    Item 0 is the home position (frame global, at `home_amsl_m`), then
    [`mission_items()`][rainuav.missions.mission_items] (yaw, param 4, written 0: keep the heading).

    Args:
        home: `(lat, lon)` of the take-off, degrees.
        waypoints: The waypoints (K, 2) of (lat, lon), degrees.
        altitude_m: The height above home, m (one, or one a waypoint).
        altitudes_amsl_m: Heights above mean sea level (K,), m, in place of `altitude_m`.
        home_amsl_m: Home's height above mean sea level, m.

    Returns:
        The file's text.
    """
    rows = [[0, 1, MAV_FRAME_GLOBAL, MAV_CMD_NAV_WAYPOINT, 0, 0, 0, 0, home[0], home[1],
             float(home_amsl_m), 1]]  # fmt: skip
    items = mission_items(home, waypoints, altitude_m, altitudes_amsl_m)
    for k, it in enumerate(items, start=1):
        p = [0.0 if v is None else v for v in it["params"]]
        rows.append([k, 0, it["frame"], it["command"], *p, 1])
    return "QGC WPL 110\n" + "".join("\t".join(_num(v) for v in r) + "\n" for r in rows)


def _num(v: Any) -> str:
    return str(v) if isinstance(v, int) else repr(float(v))


def plan_dict(
    home: tuple[float, float],
    waypoints: npt.ArrayLike,
    altitude_m: npt.ArrayLike,
    speed_m_s: float,
    altitudes_amsl_m: npt.ArrayLike | None = None,
    home_amsl_m: float = 0.0,
) -> dict[str, Any]:
    """The mission as a QGroundControl `.plan` (the module's docstring has the form).

    A generic multirotor (`firmwareType` 0, `vehicleType` 2), altitudes relative to home
    (`globalPlanAltitudeMode` 1), or above mean sea level with `altitudes_amsl_m` (2).

    Args:
        home: `(lat, lon)` of the take-off, degrees.
        waypoints: The waypoints (K, 2) of (lat, lon), degrees.
        altitude_m: The height above home, m (one, or one a waypoint).
        speed_m_s: The cruise speed, m/s.
        altitudes_amsl_m: Heights above mean sea level (K,), m, in place of `altitude_m`.
        home_amsl_m: Home's height above mean sea level, m.

    Returns:
        The plan, as JSON-ready data.
    """
    mode = 1 if altitudes_amsl_m is None else 2
    items = []
    for k, it in enumerate(mission_items(home, waypoints, altitude_m, altitudes_amsl_m), 1):
        items.append(
            {
                "AMSLAltAboveTerrain": None,
                "Altitude": it["params"][6],
                "AltitudeMode": mode if it["command"] != MAV_CMD_NAV_LAND else 1,
                "autoContinue": True,
                "command": it["command"],
                "doJumpId": k,
                "frame": it["frame"],
                "params": it["params"],
                "type": "SimpleItem",
            }
        )
    return {
        "fileType": "Plan",
        "version": 1,
        "groundStation": "QGroundControl",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "rallyPoints": {"points": [], "version": 2},
        "mission": {
            "version": 2,
            "firmwareType": 0,
            "vehicleType": 2,
            "cruiseSpeed": speed_m_s,
            "hoverSpeed": speed_m_s,
            "globalPlanAltitudeMode": mode,
            "plannedHomePosition": [home[0], home[1], float(home_amsl_m)],
            "items": items,
        },
    }


def geojson_dict(
    latlon: npt.ArrayLike,
    altitude_m: npt.ArrayLike,
    vertex_properties: dict[str, list[Any]],
    sites: list[dict[str, Any]] | None = None,
    properties: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The flight as a GeoJSON `FeatureCollection`: the path as a `LineString`, each site a `Point`.

    Args:
        latlon: The path (N, 2) of (lat, lon), degrees.
        altitude_m: Its height, m: one, or one a vertex.
        vertex_properties: Lists of N values each, one a vertex (the signal, the serving cell, ...).
        sites: Each site's `lat`, `lon` and its own fields.
        properties: The path's own properties.

    Returns:
        The collection, as JSON-ready data.

    Raises:
        InvalidInputError: A vertex property without one value a vertex.
    """
    ll = np.asarray(latlon, dtype=np.float64).reshape(-1, 2)
    for name, values in vertex_properties.items():
        if len(values) != len(ll):
            raise InvalidInputError(f"{name}: {len(values)} values for {len(ll)} vertices")
    z = np.broadcast_to(np.asarray(altitude_m, dtype=np.float64), (len(ll),))
    line = {
        "type": "Feature",
        "geometry": {
            "type": "LineString",
            "coordinates": [
                [float(lo), float(la), float(h)] for (la, lo), h in zip(ll, z, strict=True)
            ],
        },
        "properties": {"kind": "flight", **(properties or {}), **vertex_properties},
    }
    points = [
        {
            "type": "Feature",
            "geometry": {"type": "Point", "coordinates": [float(s["lon"]), float(s["lat"])]},
            "properties": {
                "kind": "site",
                **{k: v for k, v in s.items() if k not in ("lat", "lon")},
            },
        }
        for s in sites or []
    ]
    return {"type": "FeatureCollection", "features": [line, *points]}


def kml_text(
    latlon: npt.ArrayLike,
    altitude_m: npt.ArrayLike,
    name: str,
    sites: list[dict[str, Any]] | None = None,
) -> str:
    """The flight as KML 2.2 for Google Earth: the path as a `LineString`, each site a `Point`.

    Args:
        latlon: The path (N, 2) of (lat, lon), degrees.
        altitude_m: Its height above the ground, m (`relativeToGround`): one, or one a vertex.
        name: The document's name.
        sites: Each site's `lat`, `lon` and its own fields.

    Returns:
        The file's text.
    """
    ll = np.asarray(latlon, dtype=np.float64).reshape(-1, 2)
    z = np.broadcast_to(np.asarray(altitude_m, dtype=np.float64), (len(ll),)).tolist()
    coords = " ".join(
        f"{lo!r},{la!r},{float(h)!r}" for (la, lo), h in zip(ll.tolist(), z, strict=True)
    )
    marks = "".join(
        f"<Placemark><name>{escape(str(s.get('site_id', 'site')))}</name>"
        f"<Point><coordinates>{float(s['lon'])!r},{float(s['lat'])!r},0</coordinates></Point>"
        "</Placemark>"
        for s in sites or []
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        f"<name>{escape(name)}</name>"
        f"<Placemark><name>{escape(name)}</name><LineString><altitudeMode>relativeToGround"
        f"</altitudeMode><coordinates>{coords}</coordinates></LineString></Placemark>"
        f"{marks}</Document></kml>\n"
    )
