"""Radio maps in time, timed (BENCHMARKS.md, "Radio maps in time"):

    python benches/storm_slices.py [--seed 0] [--slices 61] [--terrain] [--footprints]

The `storm` preset (ray engine, 10 m pixels, 21 cells) at 61 instants 0-300 s: the static part
(the rays traced once), the time per slice, and in the same run a static ray-engine build of the
frozen weather at three of the instants (the reference a slice replaces), with their ratio and
the largest difference between a slice and its static build. ``--terrain`` puts the storm over
the hilly DEM of ``benches/terrain_map.py`` (every path's own profile: Bullington diffraction,
the reflection's visibility; the rain along the same rays). ``--footprints`` adds 500
buildings (the district of ``examples/make_footprints.py``, as ``benches/building_map.py``):
roofs in every profile and the walls' first-order reflections, their rain along each wall
ray's length.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from rainuav.radio import build_radio_map, presets
from rainuav.radio.outputs.timemap import build_radio_map_series


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--slices", type=int, default=61)
    ap.add_argument("--terrain", action="store_true", help="over a hilly DEM")
    ap.add_argument("--footprints", action="store_true", help="among about 500 buildings")
    args = ap.parse_args()
    scn = presets.storm(seed=args.seed, engine="ray")
    here = Path(__file__).resolve().parent
    sys.path.insert(0, str(here))
    sys.path.insert(0, str(here.parent / "examples"))
    from rainuav.radio.scene.scenario import FootprintsFile, Origin, TerrainFile
    from terrain_map import ORIGIN

    if args.terrain:
        from terrain_map import write_dem

        dem = write_dem(Path(tempfile.mkdtemp()) / "hills.tif")
        scn = scn.replace(origin=Origin(*ORIGIN), terrain=TerrainFile(str(dem)))
    if args.footprints:
        import json

        from make_footprints import district
        from rainuav.geo import Georef

        a = scn.area
        cx, cy = 0.5 * (a.x_min_m + a.x_max_m), 0.5 * (a.y_min_m + a.y_max_m)
        lat, lon = Georef(*ORIGIN).to_latlon(cx, cy)
        avoid = [(s.x_m - cx, s.y_m - cy) for s in scn.sites]
        fc = district(float(lat), float(lon), 0.5 * (a.x_max_m - a.x_min_m), 5, avoid, 80.0)
        fc["features"] = fc["features"][:500]
        city = Path(tempfile.mkdtemp()) / "city.geojson"
        city.write_text(json.dumps(fc))
        scn = scn.replace(origin=Origin(*ORIGIN), footprints=FootprintsFile(str(city)))
    times = np.linspace(0.0, 300.0, args.slices)
    t0 = time.perf_counter()
    series = build_radio_map_series(scn, times, cache=False)
    total = time.perf_counter() - t0
    per_slice = series.timings["slices"] / len(times)
    static, worst = [], 0.0
    for k in (0, len(times) // 2, len(times) - 1):
        t1 = time.perf_counter()
        ref = build_radio_map(scn.replace(medium=scn.medium.at(times[k])), cache=False)
        static.append(time.perf_counter() - t1)
        worst = max(worst, float(np.abs(series.sinr_db[k] - ref.sinr_db).max()))
    mb = (series.rss_dbm.nbytes + series.sinr_db.nbytes * 2 + series.serving_cell.nbytes) / 1e6
    print(
        f"storm seed {args.seed}{' over the DEM' if args.terrain else ''}"
        f"{' among buildings' if args.footprints else ''}, {len(times)} slices, "
        f"{series.rss_dbm.shape[1]} cells x "
        f"{series.sinr_db.shape[1]} x {series.sinr_db.shape[2]} pixels: total {total:.1f} s, "
        f"static part {series.timings['static']:.2f} s, then {series.timings['slices']:.2f} s: "
        f"{1e3 * per_slice:.0f} ms a slice; "
        f"a static ray build {np.median(static):.2f} s (median of 3): a slice costs "
        f"{per_slice / np.median(static):.3f} of it; slices within {worst:.4f} dB of SINR of "
        f"their static builds; the series holds {mb:.0f} MB"
    )


if __name__ == "__main__":
    main()
