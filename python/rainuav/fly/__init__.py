"""``python -m rainuav.fly``: a flight plan for a real place, in files an autopilot loads.

    python -m rainuav.fly --sites examples/sites.csv --start 47.3700,8.5400 \\
        --goal 47.3830,8.5570 --rain-rate-mm-h 25 --out runs/flight
    python -m rainuav.fly --sites examples/sites.csv --start 47.3700,8.5400 \\
        --goal 47.3830,8.5570 --terrain dem.tif --out runs/flight

Sites from a CSV or GeoJSON file (one row per sector: ``site_id, lat, lon, height_m, azimuth_deg,
electrical_tilt_deg, tx_power_dbm``, optional ``antenna, rows, mechanical_tilt_deg, freq_ghz``;
azimuths clockwise from north, tilts positive down, as operators give them:
[`rainuav.radio.scene.sites`][rainuav.radio.scene.sites]), the start and destination as ``LAT,LON``
(degrees, WGS 84; south and west negative), the flight altitude, the carrier and homogeneous rain
(``--rain-rate-mm-h``) or a georeferenced rain file (``--weather``: NetCDF, a GeoTIFF with one band
per instant or a folder of GeoTIFF scans, in mm/h or dBZ, Marshall-Palmer; several instants give a
weather that moves and the exact plan in space-time:
[`rainuav.radio.scene.radar`][rainuav.radio.scene.radar]). The area is the box around the start, the
destination and the sites with a 300 m margin (at most 10 km x 10 km), in metres of an azimuthal
equidistant projection centred on it ([`rainuav.geo`][rainuav.geo]). Plans the exact optimum
(``rainuav.nav.planner``) and writes into ``--out``:

- ``flight.geojson`` (the path, WGS 84, with per-vertex time, SINR, serving cell and outage;
  the sites as points), ``flight.kml`` (Google Earth, altitude above the ground);
- ``mission.plan`` (QGroundControl) and ``mission.waypoints`` (QGC WPL 110): take-off, the path's
  corners at the flight altitude relative to home, landing; over ``--terrain``, the waypoints above
  mean sea level (MAVLink's global frame), enough of them that every straight leg between two holds
  the planned height above the ground within 5 m and never passes closer to the ground than the
  clearance ([`rainuav.missions.terrain_waypoints()`][rainuav.missions.terrain_waypoints]);
- ``flight.png`` (the path over the SINR map with the sites, the buildings and the pixels the
  UAV may not fly) and ``summary.json`` (cost, outage share and flight time, against the
  straight line; the fields: the documentation's troubleshooting page).

``summary.json`` is written last: a folder without it holds a flight that was stopped part
way (an earlier run's ``summary.json`` is removed before the new files are written).

``--terrain DEM.tif`` puts the place on its ground (a GeoTIFF in any CRS, heights in metres above
sea level, as SRTM or Copernicus GLO-30 deliver it: [`rainuav.ground.dem`][rainuav.ground.dem]): the
map is made over it (the march over the ground, the rays over each path's profile), the altitude is
above the terrain under the UAV (``--altitude-reference ground``, the default) or above sea level
(``msl``), and the flight keeps out of the pixels where terrain comes within 10 m of it; a start or
destination there is refused.

``--footprints FILE.geojson`` adds buildings (OpenStreetMap's footprints and height tags:
[`rainuav.ground.footprints`][rainuav.ground.footprints]) standing on that ground: their roofs
diffract, their walls reflect, and the flight keeps out of every pixel a building overlaps that
reaches within 10 m of it.

A planning aid, not an airworthiness tool: check the airspace, obstacles the map does not know
(without ``--terrain`` it assumes flat open ground; a DEM leaves out vegetation and clutter,
footprints leave out masts, cranes and trees), and the link budget's assumptions before flying.
Needs the ``geo`` extra (``pip install '.[geo]' from the rainuav clone``). """

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rainuav import _cli
from rainuav.errors import InvalidInputError
from rainuav.radio.engines import ENGINES

LATLON_FLAGS = ("--start", "--goal", "--area")
"""The flags whose values may begin with a minus sign (southern and western degrees)."""


def _latlon(text: str) -> tuple[float, float]:
    try:
        lat, lon = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LAT,LON in degrees (got {text!r})") from None
    return lat, lon


def _start(text: str) -> tuple[float, ...]:
    """``LAT,LON`` or ``LAT,LON,ALTITUDE`` (the altitude: one of ``--altitudes-m``)."""
    try:
        vals = tuple(float(v) for v in text.split(","))
    except ValueError:
        vals = ()
    if len(vals) not in (2, 3):
        raise argparse.ArgumentTypeError(
            f"expected LAT,LON in degrees, or LAT,LON,ALTITUDE with --altitudes-m (got {text!r})"
        )
    return vals


def _grounds() -> tuple[str, ...]:
    from rainuav.radio.scene.scenario import GROUNDS

    return GROUNDS


@dataclass
class FlyOptions:
    """What ``python -m rainuav.fly`` takes (one docstring line per field = one flag, generated
    as ``train``'s are)."""

    sites: Path | None = field(default=None, metadata={"required": True})
    """Sites file (.csv or .geojson)."""
    start: tuple[float, ...] | None = field(
        default=None, metadata={"required": True, "type": _start}
    )
    """Take-off point LAT,LON in degrees, south and west negative (--start -33.87,151.21 and
    --start=-33.87,151.21 both work); with --altitudes-m, LAT,LON,ALTITUDE starts at that level
    (default: the exact planner chooses the take-off level, and the summary says which)."""
    goal: tuple[float, float] | None = field(
        default=None, metadata={"required": True, "type": _latlon}
    )
    """Destination LAT,LON, as --start."""
    area: str | None = None
    """The area as S,W,N,E in degrees, south and west negative (default: around the start, goal
    and sites)."""
    altitude_m: float = 100.0
    """Flight altitude above ground, m."""
    freq_ghz: float = 28.0
    """Carrier frequency, GHz."""
    rain_rate_mm_h: float = 0.0
    """Homogeneous rain, mm/h."""
    weather: Path | None = None
    """A georeferenced rain file (NetCDF on lat/lon or x/y with a CRS, a GeoTIFF with a band per
    instant, or a folder of GeoTIFF scans; mm/h or dBZ)."""
    speed_m_s: float = field(default=10.0, metadata={"more": True})
    """Ground speed, m/s."""
    min_db: float | None = field(default=None, metadata={"more": True})
    """SINR outage threshold, dB."""
    policy: Path | None = None
    """Fly a trained network that reads the weather (a run of --observation weather)."""
    terrain: Path | None = None
    """A DEM GeoTIFF under the place (any CRS, heights in metres above sea level, as SRTM or
    Copernicus GLO-30): maps and flights over the ground."""
    footprints: Path | None = None
    """Building footprints in GeoJSON (longitude/latitude, OpenStreetMap height tags): buildings
    that block, diffract and reflect, and that the flight keeps clear of."""
    default_height: float | None = field(default=None, metadata={"more": True, "metavar": "M"})
    """With --footprints: the roof of a building whose footprint gives neither a height nor
    storeys, m (default 10; central-city buildings are often 18-28 m)."""
    ground: str | None = field(default=None, metadata={"more": True, "choices": _grounds})
    """The ground's material: pec, none, or an ITU-R P.527 soil (default: pec on flat ground,
    medium-dry over a --terrain DEM)."""
    engine: str | None = field(default=None, metadata={"more": True, "choices": tuple(ENGINES)})
    """The radio map's engine (default: hybrid, the PE inside each cell's cone and rays outside;
    ray: rays alone, seconds instead of minutes)."""
    altitudes_m: str | None = field(default=None, metadata={"metavar": "LOW:HIGH:STEP"})
    """Fly a band of heights, m above the ground (e.g. 30:120:15): the flight chooses its
    height, climbing at 5 m/s and descending at 3 m/s; --altitude-m is then the single height
    it is compared with."""
    altitude_reference: str | None = field(
        default=None, metadata={"more": True, "choices": ("ground", "msl")}
    )
    """--altitude-m above the terrain under the UAV (ground, the default) or above mean sea
    level (msl)."""
    measurements: Path | None = field(default=None, metadata={"metavar": "LOG.csv"})
    """A drive-test or flight log (cells as the sites file's site_id:k or the map's index): the
    map corrected by it before the plan; the summary gives the plan's expected outage and its
    spread, fit.json the fit (rainuav.radio.measured)."""
    out: Path | None = field(default=None, metadata={"required": True})
    """Output folder."""


def build_parser() -> argparse.ArgumentParser:
    """The command line: a flag for each field of [`FlyOptions`][rainuav.fly.FlyOptions]."""
    ap = _cli.Parser(
        prog="python -m rainuav.fly",
        description=_cli.plain_help(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _cli.add_fields(ap, FlyOptions)
    return ap


# Long: the command's flags checked in the order its help lists them, before any map is built;
# then the place, the flight and the files.
def main(argv: Sequence[str] | None = None) -> int:
    ap = build_parser()
    args = ap.parse_args(_cli.attach_negative_values(argv, LATLON_FLAGS))

    def body() -> int:
        from rainuav._checks import check_number
        from rainuav._io import check_out_dir
        from rainuav.fly.plan import fly_place
        from rainuav.world.place import place_scenario

        if args.altitude_reference == "msl":
            check_number("--altitude-m", args.altitude_m, -500.0, 9000.0, " m above sea level")
        else:
            check_number("--altitude-m", args.altitude_m, 0.5, 3000.0, " m")
        check_number("--freq-ghz", args.freq_ghz, 1.0, 100.0, " GHz")
        check_number("--rain-rate-mm-h", args.rain_rate_mm_h, 0.0, 500.0, " mm/h")
        if args.weather is not None and args.rain_rate_mm_h:
            raise InvalidInputError("give --rain-rate-mm-h or --weather, not both")
        check_number("--speed-m-s", args.speed_m_s, 0.1, 100.0, " m/s")
        if args.default_height is not None:
            check_number("--default-height", args.default_height, 0.5, 1000.0, " m")
        box = None
        if args.area is not None:
            try:
                box = tuple(float(v) for v in args.area.split(","))
            except ValueError:
                box = ()
            if len(box) != 4:
                raise InvalidInputError(f"--area must be S,W,N,E in degrees (got {args.area!r})")
        altitudes = None if args.altitudes_m is None else _cli.altitude_band(args.altitudes_m)
        start_alt = args.start[2] if len(args.start) == 3 else None
        if start_alt is not None and altitudes is None:
            raise InvalidInputError(
                "--start LAT,LON,ALTITUDE needs --altitudes-m (a band to start in)"
            )
        if start_alt is not None and not any(abs(start_alt - a) < 1e-6 for a in altitudes):
            raise InvalidInputError(
                f"--start altitude {start_alt:g} m must be one of --altitudes-m "
                f"{[round(a, 3) for a in altitudes]}"
            )
        out = check_out_dir(args.out, "--out")
        if not args.sites.is_file():
            raise InvalidInputError(f"--sites: no file {args.sites}")
        if args.policy is not None:  # before any map or torch: seconds and memory
            _check_policy_run(args.policy)
            if altitudes is not None:
                raise InvalidInputError("--policy flies one altitude: not with --altitudes-m")
        place = place_scenario(
            args.sites, args.start[:2], args.goal, altitude_m=args.altitude_m,
            freq_ghz=args.freq_ghz, rain_rate_mm_h=args.rain_rate_mm_h, weather=args.weather,
            box=box, terrain=args.terrain, altitude_reference=args.altitude_reference,
            footprints=args.footprints, altitudes_m=altitudes, engine=args.engine,
            default_height_m=args.default_height, ground=args.ground,
        )  # fmt: skip
        if args.footprints is not None:
            from rainuav.radio.scene.buildings import scenario_buildings

            print(scenario_buildings(place.scenario).summary, file=sys.stderr)  # type: ignore[union-attr]
        flyer, by = (None, "exact optimum") if args.policy is None else _policy(args.policy)
        summary = fly_place(
            place,
            out,
            speed_m_s=args.speed_m_s,
            min_db=args.min_db,
            flyer=flyer,
            flown_by=by,
            start_altitude_m=start_alt,
            measurements=args.measurements,
        )
        print(json.dumps(summary, indent=2))
        if place.scenario.footprints is not None:
            from rainuav.radio.scene.buildings import default_height_warning

            warn = default_height_warning(summary, place.scenario.footprints.default_height_m)
            if warn:
                print(warn, file=sys.stderr)
        print(f"wrote {out.resolve()}", file=sys.stderr)
        return 0

    def flagged() -> int:
        try:
            return body()
        except InvalidInputError as err:  # the library names arguments, the command its flags
            raise InvalidInputError(as_flags(str(err))) from err

    return _cli.run(flagged)


FLAGS = {
    "`box`": "--area",
    "`start`": "--start",
    "`goal`": "--goal",
    "`terrain`": "--terrain",
    "`footprints`": "--footprints",
    "`default_height_m`": "--default-height",
    "`freq_ghz`": "--freq-ghz",
    "a place maps at most": "fly maps at most",
}
"""The names of the arguments of
[`rainuav.world.place.place_scenario()`][rainuav.world.place.place_scenario], as its messages
write them, and this command's flags."""


def as_flags(message: str) -> str:
    """A library message with its argument names as this command's flags
    ([`FLAGS`][rainuav.fly.FLAGS])."""
    for name, flag in FLAGS.items():
        message = message.replace(name, flag)
    return message


def _check_policy_run(run: Path) -> None:
    """Refuses, in one line and before anything is mapped or torch is loaded, a ``--policy``
    that is not a run of a network reading the weather on one altitude (its ``config.toml``
    read as data)."""
    from rainuav._io import read_toml

    if not (run / "config.toml").is_file() or not (run / "checkpoint.pt").is_file():
        raise InvalidInputError(
            f"--policy {run}: not a rainuav.train run (config.toml, checkpoint.pt)"
        )
    cfg = read_toml(run / "config.toml", f"--policy {run}: config.toml")
    observation = cfg.get("observation", "position")
    if observation != "weather":
        raise InvalidInputError(
            f"--policy {run}: its network sees only its own map (trained with observation = "
            f"{observation!r}); fly a network that reads the weather (--observation weather)"
        )
    levels = cfg.get("altitudes_m") or cfg.get("altitudes")  # (its earlier name)
    if levels:
        raise InvalidInputError(
            f"--policy {run}: its network chooses among the flight levels {levels} m, "
            "and --policy flies one altitude; fly it with rainuav.evaluate, or give a run "
            "trained on one altitude"
        )


def _policy(run: Path) -> tuple[object, str]:
    """A flyer for [`rainuav.fly.plan.fly_place()`][rainuav.fly.plan.fly_place]: the network
    the run ``run`` reports, flown greedily from the place's start (read as data, refused in one
    line if it does not read the weather: ``_check_policy_run`` is the one place that says so)."""
    from rainuav.rl import checkpoint
    from rainuav.rl.collect import greedy_rollouts
    from rainuav.rl.config import check_config, load_config
    from rainuav.rl.evaluation import load_agent

    _check_policy_run(run)  # main checked it before any map; a direct caller gets it here
    cfg = load_config(run / "config.toml")
    check_config(cfg)
    state = checkpoint.load(run / "checkpoint.pt", ("agent", "returns", "train_seconds"))

    def fly(env: object) -> tuple[object, bool]:
        agent, _, _ = load_agent(run / "checkpoint.pt", state, cfg, env, "cpu", False)
        start = env.cfg.start_m  # type: ignore[attr-defined]
        roll = greedy_rollouts(agent, env, [start])[0]  # type: ignore[arg-type]
        return roll["path"], bool(roll["reached"])

    return fly, f"network {run}"
