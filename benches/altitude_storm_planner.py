"""The exact planner among levels in a storm that moves, against the plane's on one level.

    python benches/altitude_storm_planner.py [--starts 200] [--levels 30:120:15]

The `storm` world (storm seed 0, ray engine, 61 slices over the 300-move horizon) mapped at
every level of the band (30 to 120 m every 15 m by default: seven levels), 200 fixed
starts (seed 12345, the shared default destination), each starting at the lowest level.
Times in the same run: the maps at every level; ``planner.optimal_levels`` in space and
time (climb 5 m/s, descent 3 m/s: 3 and 5 moves a 15 m gap); and the plane's space-time
planner (``planner.plan_on``) on the 100 m level's series, the reference doing the work of
one level. The best of ``--repeats`` timings each.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=int, default=200)
    ap.add_argument("--levels", default="30:120:15")
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    from rainuav.nav import planner
    from rainuav.nav.field import SignalField
    from rainuav.radio.outputs.levelmaps import build_radio_level_series
    from rainuav.rl.evaluation import eval_starts
    from rainuav.world import WorldSpec, build_world, make_scenario, series_instants

    lo, hi, step = (float(v) for v in args.levels.split(":"))
    levels = list(np.arange(lo, hi + step / 2, step))
    spec = WorldSpec(scenario="storm", engine="ray")
    scn = make_scenario(spec, None)
    scn = scn.replace(area=dataclasses.replace(scn.area, altitudes_m=levels))
    t0 = time.perf_counter()
    series = build_radio_level_series(scn, series_instants(spec))
    alts, times, sinr = series.altitudes_m, series.t_s, series.sinr_db
    t_maps = time.perf_counter() - t0
    env = build_world(spec).env()
    cfg = env.cfg
    starts = eval_starts(env, args.starts, 12345)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; "
          f"storm seed 0, {len(alts)} levels x {len(times)} slices of {sinr.shape[2:]} built in "
          f"{t_maps:.1f} s")  # fmt: skip

    def best_of(fn):
        out, best = None, float("inf")
        for _ in range(args.repeats):
            t = time.perf_counter()
            out = fn()
            best = min(best, time.perf_counter() - t)
        return out, best

    sig = sinr.astype(np.float64)
    plans, t_lv = best_of(lambda: planner.optimal_levels(
        sig, alts, env.field.extent, cfg, starts, np.zeros(len(starts)), t_s=times))  # fmt: skip
    k100 = int(np.argmin(np.abs(alts - 100.0)))
    one = SignalField.series(sig[:, k100], times, env.field.extent)
    flat, t_one = best_of(lambda: planner.plan_on(one, cfg, starts))
    arrived = np.mean([p.return_ > 0 for p in plans])
    moves = np.mean([np.sum(p.actions >= 4) for p in plans])
    print(f"{len(starts)} exact plans among {len(alts)} levels in space-time: {t_lv:.1f} s "
          f"({arrived:.0%} arrive, {moves:.1f} climbs or descents a flight)")  # fmt: skip
    print(f"{len(starts)} exact plans on the {alts[k100]:g} m level alone (the plane's "
          f"space-time planner): {t_one:.2f} s; ratio {t_lv / t_one:.1f}x for "
          f"{len(alts)} levels")  # fmt: skip
    gain = np.mean([a.return_ - b.return_ for a, b in zip(plans, flat, strict=True)])
    print(f"mean return gained by the band over the {alts[k100]:g} m level: {gain:.1f}")


if __name__ == "__main__":
    main()
