"""Which height to fly, measured on one network (BENCHMARKS.md, "Altitude as a decision"):

    python experiments/altitude_plans.py [--starts 100] [--freq-ghz 28] [--seed 0]

The `uma` network (21 cells) in clear air, ray engine, at six flight altitudes (25-150 m
every 25 m). Prints the share of the area in outage (SINR below -2 dB) at each, then for
``--starts`` flights (uniform starts, seeded; the default destination) the exact cost (time
plus the outage penalty, the navigation task's reward) of: the plan held at 100 m (the
paper's), the best single altitude for each flight (the exact plan at each level, chosen with
hindsight), the straight line at 100 m, the exact plan free to climb and descend (climb
5 m/s, descent 3 m/s) from 100 m, and the same with its start level chosen (the exact
optimum among levels: the take-off's climb is the autopilot's); each as mean excess over the
last and its outage share; and the time of the planner among levels for all starts.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=int, default=100)
    ap.add_argument("--freq-ghz", type=float, default=28.0)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    from rainuav.nav import planner
    from rainuav.nav.field import SignalField
    from rainuav.nav.task import NavConfig
    from rainuav.radio.outputs.levelmaps import build_radio_levels, sample_levels
    from rainuav.radio.scene import presets
    from rainuav.radio.scene.scenario import Area

    levels = [25.0, 50.0, 75.0, 100.0, 125.0, 150.0]
    scn = presets.uma(0.0, args.freq_ghz * 1e9, engine="ray").replace(area=Area(altitudes_m=levels))
    t0 = time.perf_counter()
    stack = build_radio_levels(scn)
    t_maps = time.perf_counter() - t0
    sinr = stack.sinr_db
    thr = presets.SINR_THRESHOLDS_DB["uma"]
    cfg = NavConfig(min_db=thr)
    print(f"machine: {platform.processor() or platform.machine()}; uma at {args.freq_ghz:g} GHz, "
          f"clear air, {len(levels)} levels built in {t_maps:.1f} s")  # fmt: skip
    print("outage share of the area: " + ", ".join(
        f"{a:g} m {np.mean(s < thr):.0%}" for a, s in zip(levels, sinr, strict=True)))  # fmt: skip
    rng = np.random.default_rng(args.seed)
    x0, x1, y0, y1 = stack.extent
    starts = []
    while len(starts) < args.starts:
        p = rng.uniform([x0, y0], [x1, y1])
        if np.hypot(*(p - np.asarray(cfg.goal_m))) > 50.0:
            starts.append(p)
    starts = np.asarray(starts)

    def outage(path: np.ndarray, lv: np.ndarray) -> float:
        s = sample_levels(sinr, stack.extent, path[1:, 0], path[1:, 1], lv[1:])
        return float(np.mean(s < thr)) if len(s) else 0.0

    def cost(r: float, arrived: bool) -> float:
        return cfg.goal_reward - r if arrived else np.nan

    per_level = []
    for k in range(len(levels)):
        plans = planner.plan_on(SignalField(sinr[k], stack.extent), cfg, starts)
        row = []
        for p in plans:
            row.append(
                (cost(p.return_, p.return_ > 0), outage(p.path_m, np.full(len(p.path_m), k)))
            )
        per_level.append(row)
    k100 = levels.index(100.0)
    from_100 = planner.optimal_levels(sinr, levels, stack.extent, cfg, starts,
                                      np.full(len(starts), k100))  # fmt: skip
    c_100f = np.array([cost(p.return_, p.return_ > 0) for p in from_100])
    o_100f = np.array([outage(p.path_m, p.levels) for p in from_100])
    t1 = time.perf_counter()
    free = planner.optimal_levels(sinr, levels, stack.extent, cfg, starts, np.full(len(starts), -1))
    t_free = time.perf_counter() - t1
    c_free = np.array([cost(p.return_, p.return_ > 0) for p in free])
    o_free = np.array([outage(p.path_m, p.levels) for p in free])
    c_lv = np.array([[c for c, _ in row] for row in per_level])  # (L, N)
    o_lv = np.array([[o for _, o in row] for row in per_level])
    best = np.nanargmin(c_lv, axis=0)
    c_best = c_lv[best, np.arange(len(starts))]
    o_best = o_lv[best, np.arange(len(starts))]
    from rainuav.nav.env import UAVNavEnv

    line_env = UAVNavEnv(sinr_db=sinr[k100], extent_m=stack.extent, config=cfg)
    lines = [planner.straight_line(line_env, p) for p in starts]
    c_line = np.array([cost(p.return_, p.return_ > 0) for p in lines])
    o_line = np.array([outage(p.path_m, np.full(len(p.path_m), k100)) for p in lines])
    rows = [("straight line at 100 m", c_line, o_line),
            ("held at 100 m (the paper's)", c_lv[k100], o_lv[k100]),
            ("best single altitude (hindsight)", c_best, o_best),
            ("from 100 m, free to climb and descend", c_100f, o_100f),
            ("free, the start level chosen (exact)", c_free, o_free)]  # fmt: skip
    print(f"{len(starts)} flights, destination {cfg.goal_m}:")
    for name, c, o in rows:
        ex = (c - c_free) / c_free
        print(
            f"  {name:34s} mean cost {np.nanmean(c):7.1f}, excess over the exact "
            f"{np.nanmean(ex):6.2%} (worst {np.nanmax(ex):6.2%}), outage {np.mean(o):5.1%}"
        )
    chosen = [f"{levels[k]:g} m x{int(np.sum(best == k))}" for k in range(len(levels))]
    print("  best single altitude chosen: " + ", ".join(c for c in chosen if not c.endswith("x0")))
    moves = np.array([np.sum(p.actions >= 4) for p in free])
    print(
        f"  the free plans climb or descend {moves.mean():.1f} times a flight on average; "
        f"planned in {t_free:.1f} s for {len(starts)} starts"
    )


if __name__ == "__main__":
    main()
