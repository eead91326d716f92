"""Buildings from footprints, timed (BENCHMARKS.md, "Real buildings"), in one run:

    python benches/building_map.py [--repeats 3]

1. **Load and rasterise**: 10 000 footprints (the district of ``examples/make_footprints.py``
   over 8.8 km x 8.8 km) read from GeoJSON, merged, their walls found, and the not-flyable
   pixels of the area at 10 m (774 400 pixels) intersected as polygons.
2. **A ray map among 500 buildings**: the ``uma`` network (21 cells on 7 sites) over its 4 km2
   area at 10 m (200 x 200 pixels), ray engine, over the hilly DEM of
   ``benches/terrain_map.py``, with 500 footprints (blocks of 80 m): first-order wall
   reflections and
   every path's profile through the buildings; against the same map over the DEM without
   buildings, and the share of the time the walls' and corners' rays take.
3. **A ray map among 10 000 footprints**: the ``uma`` network's 21 cells spread over the
   8.8 km district of step 1 (its sites' layout scaled 4.4 times, each moved to the nearest
   open ground), 200 x 200 pixels (44 m), flat ground: every mechanism (roofs, corners,
   walls once and twice, roof edges beside the line).

No cache: every build is computed. Prints the best of ``--repeats`` wall times.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "benches"))
from make_footprints import district  # noqa: E402
from terrain_map import ORIGIN, write_dem  # noqa: E402


def best_of(repeats: int, job) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = job()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    from rainuav.geo import Georef
    from rainuav.radio.engines.wall_rays import trace_walls
    from rainuav.radio.outputs.maps import build_radio_map
    from rainuav.radio.scene import buildings as bld
    from rainuav.radio.scene.presets import uma
    from rainuav.radio.scene.scenario import Area, FootprintsFile, Origin, TerrainFile
    from rainuav.radio.scene.terrain import not_flyable

    print(f"machine: {platform.processor() or platform.machine()}")
    tmp = Path(tempfile.mkdtemp())
    # 1. Load and rasterise 10 000 footprints.
    big = district(*ORIGIN, 4400.0, seed=1)
    assert len(big["features"]) >= 10_000
    big["features"] = big["features"][:10_000]
    many = tmp / "many.geojson"
    many.write_text(json.dumps(big))
    n_big = len(big["features"])
    scn_big = uma(engine="ray", origin=Origin(*ORIGIN)).replace(
        area=Area(-4400.0, 4400.0, -4400.0, 4400.0, resolution_m=10.0),
        sites=[uma().sites[0].__class__(x_m=-4395.0, y_m=-4395.0)],
        footprints=FootprintsFile(str(many)),
    )

    def load() -> np.ndarray:
        bld._BUILT.clear()
        return not_flyable(scn_big)

    t_load, mask = best_of(args.repeats, load)
    b = bld.scenario_buildings(scn_big)
    print(f"load and rasterise {n_big} footprints ({len(b.footprints)} buildings merged, "
          f"{b.walls.shape[0]} walls), {mask.size} pixels: {t_load:.2f} s "
          f"({mask.mean():.1%} not flyable at 100 m)")  # fmt: skip

    # 2. uma over the hills with about 500 buildings.
    dem = write_dem(tmp / "hills.tif")
    base = uma(engine="ray", origin=Origin(*ORIGIN)).replace(terrain=TerrainFile(str(dem)))
    a = base.area
    geo = Georef(*ORIGIN)
    cx, cy = 0.5 * (a.x_min_m + a.x_max_m), 0.5 * (a.y_min_m + a.y_max_m)
    lat, lon = geo.to_latlon(cx, cy)
    avoid = [(s.x_m - cx, s.y_m - cy) for s in base.sites]
    fc = district(float(lat), float(lon), 0.5 * (a.x_max_m - a.x_min_m), 5, avoid, block_m=80.0)
    assert len(fc["features"]) >= 500
    fc["features"] = fc["features"][:500]
    city = tmp / "city.geojson"
    city.write_text(json.dumps(fc))
    with_b = base.replace(footprints=FootprintsFile(str(city)))
    t_dem, m_dem = best_of(args.repeats, lambda: build_radio_map(base, cache=False))
    t_city, m_city = best_of(args.repeats, lambda: build_radio_map(with_b, cache=False))
    jobs = [(s, c) for s in with_b.sites for c in s.cells]
    x, y = a.centres()
    t_walls, traced = best_of(args.repeats, lambda: trace_walls(with_b, jobs, x, y))
    n_rays = traced[0][0].size
    b = bld.scenario_buildings(with_b)
    strongest = np.max(m_city.rss_dbm, axis=0) - np.max(m_dem.rss_dbm, axis=0)
    print(f"uma 21 cells, 200 x 200 over the DEM: {t_dem:.2f} s; with {len(fc['features'])} "
          f"footprints ({b.walls.shape[0]} walls, {n_rays} wall rays): {t_city:.2f} s "
          f"({t_city / t_dem:.1f}x), of which tracing the walls' rays {t_walls:.2f} s")  # fmt: skip
    # 3. 21 cells among the 10 000 footprints, 200 x 200.
    from rainuav.radio.scene.scenario import Site

    prisms = bld.scenario_buildings(scn_big).prisms
    sites = []
    for s in uma().sites:
        px, py = (s.x_m - 1000.0) * 4.4, (s.y_m - 1000.0) * 4.4
        for r in np.arange(0.0, 400.0, 5.0):  # the nearest open ground on a spiral of rings
            ang = np.linspace(0, 2 * np.pi, 16, endpoint=False)
            cand = np.column_stack([px + r * np.cos(ang), py + r * np.sin(ang)])
            free = prisms.height_at(cand[:, 0].copy(), cand[:, 1].copy()) == 0.0
            if free.any():
                px, py = cand[np.argmax(free)]
                break
        sites.append(Site(x_m=float(px), y_m=float(py), height_m=s.height_m, cells=s.cells))
    wide = scn_big.replace(
        sites=sites, area=Area(-4400.0, 4400.0, -4400.0, 4400.0, resolution_m=44.0)
    )
    t_wide, _ = best_of(args.repeats, lambda: build_radio_map(wide, cache=False))
    jobs = [(s, c) for s in wide.sites for c in s.cells]
    x, y = wide.area.centres()
    t_rays, traced = best_of(args.repeats, lambda: trace_walls(wide, jobs, x, y))
    kinds = np.bincount(traced[0][6], minlength=5)
    print(f"uma 21 cells, 200 x 200 (44 m) among {n_big} footprints: {t_wide:.2f} s, of which "
          f"the walls' and edges' rays {t_rays:.2f} s ({kinds[1]} one wall, {kinds[2]} two "
          f"walls, {kinds[3]} corners, {kinds[4]} roof edges beside the line)")  # fmt: skip
    q = [np.median(strongest), *np.percentile(strongest, [10, 90])]
    nf = m_city.not_flyable.mean()
    print(f"strongest cell changed by the buildings (median, p10, p90 dB): "
          f"{q[0]:+.1f}, {q[1]:+.1f}, {q[2]:+.1f}; not flyable {nf:.1%}")  # fmt: skip


if __name__ == "__main__":
    main()
