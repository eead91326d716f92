"""``python -m rainuav.radiomap``: build a radio map and write it as .npz and PNGs.

    python -m rainuav.radiomap --scenario paper --rain-rate-mm-h 25 --out maps/
    python -m rainuav.radiomap --scenario uma --freq-ghz 28 --rain-rate-mm-h 50 --engine hybrid
    python -m rainuav.radiomap --config my_scenario.toml --out maps/
    python -m rainuav.radiomap --config my_place.toml --terrain dem.tif --out maps/
    python -m rainuav.radiomap --config my_place.toml --footprints city.geojson --out maps/
    python -m rainuav.radiomap --scenario storm --storm-seed 3 --duration-s 300 --slice-s 5
    python -m rainuav.radiomap --scenario uma --engine ray --altitudes-m 30:120:15 --out maps/
    python -m rainuav.radiomap --clear-cache

Writes the PNGs first (and, for a georeferenced scenario, ``radiomap.tif``: SINR, the serving cell's
power, the serving cell and the not-flyable pixels for a GIS,
[`rainuav.radio.outputs.maptiff`][rainuav.radio.outputs.maptiff]) and ``radiomap.npz``
(``radiomap_series.npz`` for maps in time) last: a folder holding it is complete (an earlier run's
copy is removed before the new files are written). At several heights (``--altitudes-m``, or a
scenario with ``area.altitudes_m``): per level ``sinr_<A>m.png``, ``radiomap_<A>m.npz`` and for a
georeferenced scenario ``radiomap_<A>m.tif``, then ``radiomap_levels.json`` (the levels, their files
and outage shares) last. The library lives in [`rainuav.radio`][rainuav.radio]."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rainuav import _cli
from rainuav.errors import InvalidInputError
from rainuav.radio.engines import ENGINES


def _presets() -> tuple[str, ...]:
    from rainuav.radio.scene import presets

    return tuple(sorted(presets.PRESETS))


def _grounds() -> tuple[str, ...]:
    from rainuav.radio.scene.scenario import GROUNDS

    return GROUNDS


@dataclass
class RadiomapOptions:
    """What ``python -m rainuav.radiomap`` takes (one docstring line per field = one flag,
    generated as ``train``'s are)."""

    scenario: str = field(default="paper", metadata={"choices": _presets})
    """The preset scenario."""
    config: Path | None = None
    """A scenario TOML file (overrides --scenario)."""
    rain_rate_mm_h: float | None = None
    """Homogeneous rain, mm/h, in place of the scenario's weather (0: clear air; the scenario's
    rain model, drop sizes, shape, temperature and wind are kept)."""
    rain_file: Path | None = None
    """Rain rates in time from a NetCDF file, (time, y, x) in mm/h on the area's metres
    (rainuav.radio.scene.rategrid; needs the 'weather' extra)."""
    freq_ghz: float | None = None
    """Carrier frequency, GHz (1-100)."""
    engine: str | None = field(default=None, metadata={"choices": tuple(ENGINES)})
    """Propagation engine (default: the scenario's, 'hybrid' for the presets)."""
    storm_seed: int | None = None
    """With --scenario storm: the storm drawn (default 0; from 1000000: evaluation storms)."""
    at_s: float | None = field(default=None, metadata={"more": True})
    """The weather this many seconds into its motion (moving rain cells; default 0)."""
    duration_s: float | None = None
    """Maps in time: the weather's first DURATION seconds, every --slice-s (ray engine), written
    as radiomap_series.npz and storm.gif."""
    slice_s: float | None = field(default=None, metadata={"more": True})
    """With --duration-s: the step, s (default 5)."""
    terrain: Path | None = None
    """A DEM GeoTIFF (any CRS; heights in metres above sea level) under the area: the scenario
    needs an [origin] (a --config TOML)."""
    ground: str | None = field(default=None, metadata={"more": True, "choices": _grounds})
    """The ground's material: pec, none, or an ITU-R P.527 soil (default: the scenario's;
    medium-dry over a --terrain DEM)."""
    footprints: Path | None = None
    """Building footprints in GeoJSON (longitude/latitude; OpenStreetMap height tags): the
    scenario needs an [origin] (a --config TOML)."""
    default_height: float | None = field(default=None, metadata={"more": True, "metavar": "M"})
    """The roof of a building whose footprint gives neither a height nor storeys, m (default:
    the scenario's footprints.default_height_m, 10 m)."""
    altitude_reference: str | None = field(
        default=None, metadata={"more": True, "choices": ("ground", "msl")}
    )
    """The flight altitude above the terrain under the UAV (ground, the default) or above mean
    sea level (msl)."""
    altitudes_m: str | None = field(default=None, metadata={"metavar": "LOW:HIGH:STEP"})
    """Map a band of flight altitudes, m (e.g. 30:120:15): one map a level
    (rainuav.radio.outputs.levelmaps)."""
    measurements: Path | None = field(default=None, metadata={"metavar": "LOG.csv"})
    """A drive-test or flight log (lat,lon or x_m,y_m, alt_m, cell, rsrp_dbm or rss_dbm): the
    map calibrated and corrected by it, with each pixel's standard deviation
    (rainuav.radio.measured); writes fit.json."""
    calibrate: str | None = field(default=None, metadata={"more": True, "metavar": "NAMES"})
    """With --measurements: the site parameters fitted per cell, comma-separated, or 'none'
    (default: all four)."""
    receive_pattern: str = field(
        default="off", metadata={"more": True, "choices": ("off", "elevation", "heading", "both")}
    )
    """With --measurements: 'elevation' fits the UAV's receive gain by elevation before the
    residual field, 'heading' its gain against its heading (a log with heading_deg), 'both' the
    two (fit.json's held-out scores say whether it helped; default off)."""
    residual_kernel: str | None = field(
        default=None, metadata={"more": True, "choices": ("one-scale", "two-scale", "auto")}
    )
    """With --measurements: the residual field's kernel; 'two-scale' adds a field over tens of
    metres to the smooth one, 'auto' keeps the one that predicts the log's held-out blocks
    better (default one-scale)."""
    level_step_m: float | None = field(default=None, metadata={"more": True, "metavar": "M"})
    """With --measurements: the height between the maps built at the log's heights, 1..500 m
    (default 10; at most 40 maps, so a log spanning more needs a coarser step)."""
    out: Path = Path("maps")
    """The output folder."""
    no_cache: bool = field(default=False, metadata={"more": True})
    """Build afresh, do not store."""
    min_db: float | None = field(default=None, metadata={"more": True})
    """The SINR counted as outage in the summaries, dB (default: the preset's; for a scenario
    file the uma preset's, as fly uses)."""
    clear_cache: bool = field(default=False, metadata={"more": True})
    """Delete every cached map and exit."""


def build_parser() -> argparse.ArgumentParser:
    """The command line: a flag for each field of
    [`RadiomapOptions`][rainuav.radiomap.RadiomapOptions]."""
    ap = _cli.Parser(
        prog="python -m rainuav.radiomap",
        description="Build a radio map and write npz + PNGs.",
    )
    _cli.add_fields(ap, RadiomapOptions)
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    from rainuav.radio import cache_dir, clear_cache

    args = build_parser().parse_args(argv)
    if args.clear_cache:
        n = clear_cache()
        print(f"removed {n} cached map(s) from {cache_dir() / 'radiomaps'}")
        return 0
    return _cli.run(lambda: _build(args), "the map build stopped; nothing was written")


# Long: the command read top to bottom: the scenario and its overrides, the log checked before
# any build, then the map, its files and its summary in each of its forms (one map, maps in
# time, levels).
def _build(args: argparse.Namespace) -> int:
    import numpy as np

    from rainuav._checks import check_number
    from rainuav._io import begin_folder, check_out_dir
    from rainuav.radio import Scenario, build_radio_map, presets
    from rainuav.radio.outputs.plot import save_map_png

    check_out_dir(args.out)  # before any work
    if args.storm_seed is not None and (args.config is not None or args.scenario != "storm"):
        raise InvalidInputError("--storm-seed: only with --scenario storm")
    if args.config is not None:
        scn = Scenario.from_toml(args.config)
    elif args.scenario == "storm":
        scn = presets.storm(seed=0 if args.storm_seed is None else args.storm_seed)
    else:
        scn = presets.PRESETS[args.scenario]()
    if args.rain_file is not None:
        from rainuav.radio.scene.rategrid import read_rate_grid

        if args.rain_rate_mm_h is not None:
            raise InvalidInputError("--rain-rate-mm-h: not with --rain-file (which rain?)")
        scn = scn.replace(medium=read_rate_grid(args.rain_file, scn.area, base=scn.medium))
    if args.at_s is not None:
        scn = scn.replace(medium=scn.medium.at(args.at_s))
    if args.rain_rate_mm_h is not None:
        scn = presets.with_rain(scn, args.rain_rate_mm_h)
    if args.freq_ghz is not None:
        scn = scn.replace(freq_hz=args.freq_ghz * 1e9)
    if args.terrain is not None:
        from rainuav.radio.scene.scenario import TerrainFile

        if not args.terrain.is_file():
            raise InvalidInputError(f"--terrain {args.terrain}: no such file")
        scn = scn.replace(terrain=TerrainFile(str(args.terrain.resolve())))
    from rainuav.radio.scene.terrain import ground_over

    scn = scn.replace(ground=ground_over(args.terrain is not None, args.ground, scn.ground))
    if args.footprints is not None:
        from rainuav.radio.scene.scenario import FootprintsFile

        if not args.footprints.is_file():
            raise InvalidInputError(f"--footprints {args.footprints}: no such file")
        scn = scn.replace(footprints=FootprintsFile(str(args.footprints.resolve())))
    if args.default_height is not None:
        import dataclasses

        if scn.footprints is None:
            raise InvalidInputError("--default-height needs building footprints (--footprints)")
        check_number("--default-height", args.default_height, 0.5, 1000.0, " m")
        fp = dataclasses.replace(scn.footprints, default_height_m=float(args.default_height))
        scn = scn.replace(footprints=fp)
    if args.engine is not None:
        scn = scn.replace(engine=args.engine)
    if args.altitude_reference is not None:
        import dataclasses

        area = dataclasses.replace(scn.area, altitude_reference=args.altitude_reference)
        scn = scn.replace(area=area)
    if scn.footprints is not None:
        from rainuav.radio.scene.buildings import scenario_buildings

        # Read (or refused) before anything is built; what was left out, said.
        print(scenario_buildings(scn).summary, file=sys.stderr)  # type: ignore[union-attr]
    if args.altitudes_m is not None:
        import dataclasses

        band = _cli.altitude_band(args.altitudes_m)
        scn = scn.replace(area=dataclasses.replace(scn.area, altitudes_m=band))
        scn.area.check()
    fitted = {"--calibrate": args.calibrate is not None,
              "--receive-pattern": args.receive_pattern != "off",
              "--residual-kernel": args.residual_kernel is not None,
              "--level-step-m": args.level_step_m is not None}  # fmt: skip
    if args.measurements is None and any(fitted.values()):
        flag = next(k for k, v in fitted.items() if v)
        raise InvalidInputError(f"{flag} fits a map to a log: give the log with --measurements")
    if args.level_step_m is not None:
        from rainuav._checks import check_number

        check_number("--level-step-m", args.level_step_m, 1.0, 500.0, " m")
    if args.measurements is not None and (
        scn.area.altitudes_m or args.duration_s is not None or args.slice_s is not None
    ):
        raise InvalidInputError("--measurements corrects one map: not with --altitudes-m or "
                                "--duration-s")  # fmt: skip
    if scn.area.altitudes_m:
        if args.duration_s is not None or args.slice_s is not None:
            raise InvalidInputError("--altitudes-m: maps in time at several heights are not "
                                    "written by this command (use one of the two)")  # fmt: skip
        return _build_levels(args, scn)
    if args.duration_s is not None or args.slice_s is not None:
        return _build_series(args, scn)
    rm = build_radio_map(scn, cache=not args.no_cache, progress=True)
    if args.measurements is not None:
        rm = _corrected(args, rm)
    else:  # a physics map says how sure it is too: its prior's spreads
        from rainuav.radio.measured.prior import with_prior_spreads

        rm = with_prior_spreads(rm)
    begin_folder(args.out, "radiomap.npz")
    kinds: tuple[str, ...] = ("sinr", "sir", "serving", "rss", "rss_std", "rss_sample_std")
    if rm.prior_rss_dbm is not None:
        kinds += ("correction",)
    pngs = [save_map_png(rm, kind, args.out / f"{kind}.png") for kind in kinds]
    if rm.fit is not None:
        import json

        from rainuav._io import write_atomic

        text = json.dumps(rm.fit, indent=2) + "\n"
        pngs.append(write_atomic(args.out / "fit.json", lambda t: _write_text(t, text)))
    if scn.origin is not None:  # georeferenced: the map for a GIS too
        from rainuav.radio.outputs.maptiff import write_map_geotiff

        pngs.append(write_map_geotiff(rm, args.out / "radiomap.tif"))
    npz = rm.save(args.out / "radiomap.npz")  # last: the folder is complete
    split = ", ".join(f"{k} {v:.1f} s" for k, v in rm.timings.items()) or "from the cache"
    sinr = rm.sinr_db
    print(
        f"{scn.name} ({scn.engine}, {scn.freq_hz / 1e9:g} GHz): {len(rm.rss_dbm)} cells, SINR "
        f"median {float(np.median(sinr)):.1f} dB (5-95%: {float(np.percentile(sinr, 5)):.1f} "
        f"to {float(np.percentile(sinr, 95)):.1f}); PE share of the power "
        f"{100 * float(rm.pe_share.mean()):.1f}%; built in {rm.build_seconds:.1f} s ({split})"
    )
    print(f"wrote {npz}, " + ", ".join(str(p) for p in pngs))
    return 0


def _write_text(path: Path, text: str) -> None:
    path.write_text(text)


def _corrected(args: argparse.Namespace, rm: Any) -> Any:
    """``rm`` corrected by the log of ``--measurements`` (one line on the rows used, one on
    the cross-validated error)."""
    from rainuav.radio.measured import correct_map, read_log

    given = (
        args.calibrate if args.calibrate is not None else "power_db,tilt_deg,azimuth_deg,height_m"
    )
    names = [] if given.strip() == "none" else [
        p.strip() for p in given.split(",") if p.strip()
    ]  # fmt: skip
    from rainuav.radio.measured.calibrate import BOUNDS
    from rainuav.radio.measured.heldout import held_out_line

    for p in names:
        if p not in BOUNDS:
            raise InvalidInputError(f"--calibrate: {p!r} is not one of {', '.join(BOUNDS)}, none")
    ref = rm.scenario.area.altitude_reference or "ground"
    log = read_log(args.measurements, rm.scenario, altitude_reference=ref)
    print(log.summary(), file=sys.stderr)
    out = correct_map(rm, log, params=names, receive_pattern=args.receive_pattern,
                      kernel=args.residual_kernel or "one-scale",
                      level_step_m=args.level_step_m or 10.0, progress=True)  # fmt: skip
    assert out.fit is not None
    print(held_out_line(out.fit["cross_validation"]))
    return out


def _threshold(args: argparse.Namespace, scn: Any) -> float:
    """The SINR counted as outage, dB: ``--min-db``, else the preset's navigation threshold,
    else (a scenario file, a place) the ``uma`` preset's, the one ``fly`` uses."""
    from rainuav._checks import check_number
    from rainuav.radio.scene.presets import SINR_THRESHOLDS_DB

    if args.min_db is not None:
        return check_number("--min-db", args.min_db, -40.0, 60.0, " dB")
    return SINR_THRESHOLDS_DB.get(scn.name, SINR_THRESHOLDS_DB["uma"])


def _build_levels(args: argparse.Namespace, scn: Any) -> int:
    import json

    import numpy as np

    from rainuav._io import begin_folder, write_atomic
    from rainuav.radio.outputs.levelmaps import build_radio_levels
    from rainuav.radio.outputs.plot import save_map_png

    stack = build_radio_levels(scn, cache=not args.no_cache, progress=True)
    threshold = _threshold(args, scn)
    begin_folder(args.out, "radiomap_levels.json")
    written, levels = [], []
    for a, rm in zip(stack.altitudes_m, stack.maps, strict=True):
        name = f"{a:g}m"
        written.append(save_map_png(rm, "sinr", args.out / f"sinr_{name}.png"))
        if scn.origin is not None:
            from rainuav.radio.outputs.maptiff import write_map_geotiff

            written.append(write_map_geotiff(rm, args.out / f"radiomap_{name}.tif"))
        written.append(rm.save(args.out / f"radiomap_{name}.npz"))
        sinr = rm.sinr_db
        out = None if threshold is None else float(np.mean(sinr < threshold))
        levels.append({"altitude_m": float(a), "map": f"radiomap_{name}.npz",
                       "median_sinr_db": float(np.median(sinr)), "outage_share": out})  # fmt: skip
        tail = "" if out is None else f", {100 * out:.0f}% of the area below {threshold:g} dB"
        print(f"{a:6g} m: SINR median {float(np.median(sinr)):.1f} dB{tail}")
    summary = {"scenario": scn.name, "engine": scn.engine, "freq_ghz": scn.freq_hz / 1e9,
               "min_db": threshold, "levels": levels}  # fmt: skip
    done = json.dumps(summary, indent=2) + "\n"
    last = write_atomic(args.out / "radiomap_levels.json", lambda tmp: tmp.write_text(done))
    print(f"wrote {len(written)} files and {last}")
    return 0


def _build_series(args: argparse.Namespace, scn: Any) -> int:
    import numpy as np

    from rainuav._io import begin_folder
    from rainuav.radio.engines import engine_of
    from rainuav.radio.outputs.plot import save_series_gif
    from rainuav.radio.outputs.timemap import build_radio_map_series, series_times

    if args.duration_s is None:
        raise InvalidInputError("--slice-s: only with --duration-s")
    if args.at_s is not None:
        raise InvalidInputError("--at-s: not with --duration-s (the series starts at 0 s)")
    if not engine_of(scn).traces:
        raise InvalidInputError(
            f"--engine {scn.engine}: maps in time use the ray or the hybrid engine (a PE march "
            "per cell and instant is not offered)"
        )
    times = series_times(args.duration_s, 5.0 if args.slice_s is None else args.slice_s)
    series = build_radio_map_series(scn, times, cache=not args.no_cache, progress=True)
    threshold = _threshold(args, scn)
    begin_folder(args.out, "radiomap_series.npz")
    gif = save_series_gif(series, args.out / "storm.gif", min_db=threshold, progress=True)
    npz = series.save(args.out / "radiomap_series.npz")  # last: the folder is complete
    split = ", ".join(f"{k} {v:.1f} s" for k, v in series.timings.items()) or "from the cache"
    line = (
        f"{scn.name} ({scn.engine}, {scn.freq_hz / 1e9:g} GHz): {len(times)} slices "
        f"0-{times[-1]:g} s"
    )
    if threshold is not None:
        out = (series.sinr_db < threshold).mean(axis=(1, 2))
        line += f", outage {100 * out.min():.1f}-{100 * out.max():.1f}% of the area"
    changed = float(np.mean(np.ptp(series.sinr_db, axis=0) > 0.1))
    print(
        f"{line}; SINR moves by more than 0.1 dB over {100 * changed:.0f}% of the area; "
        f"built in {series.build_seconds:.1f} s ({split})"
    )
    print(f"wrote {npz}, {gif}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
