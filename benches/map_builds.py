"""Radio-map build times per preset and engine, one run each (the table in BENCHMARKS.md,
"Radio maps"): ``python benches/map_builds.py [--budget-sweep]``.

Each row is ``build_radio_map(preset.replace(engine=E), cache=False)`` timed around the call,
with ``RadioMap.timings`` (rays, PE source and march), the cells the hybrid marched, and the
PE's share of the received power. ``--budget-sweep`` adds ``uma`` at 4.9 GHz with per-cell PE
budgets 0.1, 0.25 and 1.0 and the SINR change between them (what the PE cone costs and buys).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import time
from typing import Any

import numpy as np
from rainuav.radio import build_radio_map, presets
from rainuav.radio.scene.scenario import Scenario

ROWS = (
    ("paper", 4.9e9, 0.0),
    ("paper", 4.9e9, 25.0),
    ("uma", 4.9e9, 0.0),
    ("uma", 4.9e9, 25.0),
    ("uma", 28e9, 0.0),
    ("rain_cell", 28e9, None),
    ("urban", 4.9e9, 0.0),
)


def build(scn: Scenario) -> tuple[float, Any]:
    t = time.perf_counter()
    rm = build_radio_map(scn, cache=False)
    return time.perf_counter() - t, rm


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--budget-sweep", action="store_true")
    ap.add_argument("--engines", nargs="+", default=["ray", "hybrid"])
    ap.add_argument("--only", nargs="*", default=None, help="preset names to run")
    args = ap.parse_args()
    for name, freq, rain in ROWS:
        if args.only and name not in args.only:
            continue
        kw: dict = {"freq_hz": freq}
        if rain is not None:
            kw["rain_rate_mm_h"] = rain
        for engine in args.engines:
            dt, rm = build(presets.PRESETS[name](**kw).replace(engine=engine))
            marched = int((rm.pe_cone_deg[:, 0] > 0).sum())
            split = {k: round(v, 1) for k, v in rm.timings.items()}
            print(f"{name} {freq / 1e9:g} GHz {rain} mm/h {engine}: {dt:.1f} s {split} marched "
                  f"{marched}/{len(rm.rss_dbm)} PE share {100 * rm.pe_share.mean():.2f}%",
                  flush=True)  # fmt: skip
    if args.budget_sweep:
        base = presets.uma(0.0, 4.9e9)
        maps = {}
        for b in (0.1, 0.25, 1.0):
            dt, rm = build(base.replace(pe=dataclasses.replace(base.pe, budget_gpoints=b)))
            maps[b] = rm
            cone = np.median(rm.pe_cone_deg, axis=0).round(2)
            print(f"uma 4.9 GHz budget {b}: {dt:.1f} s, cone (median) {cone} deg, "
                  f"PE share {100 * rm.pe_share.mean():.2f}%", flush=True)  # fmt: skip
        bs = sorted(maps)
        for a, b in itertools.pairwise(bs):
            d = np.abs(maps[a].sinr_db - maps[b].sinr_db)
            print(
                f"budget {a} -> {b}: SINR change p95 {np.percentile(d, 95):.3f} dB, "
                f"max {d.max():.3f} dB, share over 0.5 dB {np.mean(d > 0.5):.4f}"
            )


if __name__ == "__main__":
    main()
