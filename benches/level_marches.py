"""Maps at several heights from one march per cell, against a march per level, same run.

    python benches/level_marches.py [--levels 30:120:15] [--resolution-m 10] [--freq-ghz 28]

The `uma` network in clear air, hybrid engine: (a) the lowest level's map alone (the level
whose cones carry most: a march per cell on its own grid), (b) every level from one march per
cell (``build_radio_levels``: the highest level's grids, every level's rows recorded), (c)
every level marched apart (``one_march=False``: each level's own grid and cone), and (d) for
the first marched cell, its march on the highest level's grid recording one height against
recording every height (the recording's own cost). Prints the wall times, the ratios, and
how far (b)'s maps are from (c)'s (SINR, dB). No cache.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", default="30:120:15")
    ap.add_argument("--resolution-m", type=float, default=10.0)
    ap.add_argument("--freq-ghz", type=float, default=28.0)
    args = ap.parse_args()
    from rainuav.radio.outputs.levelmaps import build_radio_levels, level_scenario
    from rainuav.radio.outputs.maps import build_radio_map
    from rainuav.radio.scene import presets
    from rainuav.radio.scene.scenario import Area

    lo, hi, step = (float(v) for v in args.levels.split(":"))
    levels = [float(v) for v in np.arange(lo, hi + step / 2, step)]
    scn = presets.uma(0.0, args.freq_ghz * 1e9, engine="hybrid")
    scn = scn.replace(area=Area(resolution_m=args.resolution_m, altitudes_m=levels))
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; uma "
          f"{args.freq_ghz:g} GHz hybrid, {scn.area.shape} pixels, levels {levels}")  # fmt: skip
    t = time.perf_counter()
    build_radio_map(level_scenario(scn, levels[0]), cache=False)
    t_top = time.perf_counter() - t
    t = time.perf_counter()
    shared = build_radio_levels(scn, cache=False)
    t_one = time.perf_counter() - t
    t = time.perf_counter()
    apart = build_radio_levels(scn, cache=False, one_march=False)
    t_apart = time.perf_counter() - t
    print(f"(a) the {levels[0]:g} m map alone: {t_top:.1f} s")
    print(f"(b) {len(levels)} levels from one march a cell: {t_one:.1f} s "
          f"({t_one / t_top:.2f}x one map)")  # fmt: skip
    print(f"(c) {len(levels)} levels marched apart: {t_apart:.1f} s ({t_apart / t_one:.2f}x (b))")
    from rainuav.radio.engines.grid import march_grid
    from rainuav.radio.engines.pe_engine import march_cell, march_cell_levels

    top = level_scenario(scn, levels[-1])
    m = next(i for i, g in enumerate(shared.maps[0].pe_cone_deg) if g[0] > 0)
    site, cell = [(s, c) for s in top.sites for c in s.cells][m]
    grid = march_grid(top, site, cell)
    t = time.perf_counter()
    march_cell(top, site, cell, grid)
    t1 = time.perf_counter() - t
    t = time.perf_counter()
    march_cell_levels(top, site, cell, grid, levels)
    t_all = time.perf_counter() - t
    size = f"{grid.nx} x {grid.ny} x {grid.steps}"
    print(f"(d) cell {m} on the {levels[-1]:g} m grid ({size}): one height {t1:.2f} s, "
          f"{len(levels)} heights {t_all:.2f} s ({t_all / t1:.2f}x)")  # fmt: skip
    for k, a in enumerate(levels):
        d = np.abs(shared.maps[k].sinr_db - apart.maps[k].sinr_db)
        print(f"  {a:5g} m: SINR (b) - (c) median {np.median(d):.3f} dB, p99 "
              f"{np.percentile(d, 99):.3f} dB, max {d.max():.3f} dB")  # fmt: skip


if __name__ == "__main__":
    main()
