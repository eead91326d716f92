"""What a static plan costs once the storm moves: the exact space-time optimum against the
baselines a user would try, by storm speed.

For each storm seed and storm speed (every cell's velocity scaled alike, ``storm_speed_m_s``;
0: cells stay put and only grow or decay), the ``storm`` world (``uma`` at 28 GHz, ray engine,
maps every 5 s over the 300 s horizon) is flown from the same fixed starts by:

- the exact space-time optimum (the storm's motion known: ``rainuav.nav.planner``);
- ``frozen_plan``: the exact plan on the weather at take-off, flown through the moving storm;
- ``replan``: re-planned every 10 moves on the weather of that moment, held still;
- ``straight_line``.

    python benches/storm_baselines.py [--starts 100] [--seeds 0 1 2] [--speeds 0 5 10 20]

Prints a markdown table (success, mean excess cost over the optimum, outage share) and writes
``benches/results/storm_baselines.json``. No choice is made on these numbers.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from rainuav.rl.evaluation import eval_starts, reference_flights, summarise
from rainuav.world import WorldSpec, build_world


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--starts", type=int, default=100)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--speeds", type=float, nargs="+", default=[0.0, 5.0, 10.0, 20.0])
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = ap.parse_args()
    rows = []
    for speed in args.speeds:
        for seed in args.seeds:
            t0 = time.perf_counter()
            spec = WorldSpec(scenario="storm", storm_seed=seed, storm_speed_m_s=speed, engine="ray")
            env = build_world(spec).env()
            starts = eval_starts(env, args.starts, 12345)
            refs = reference_flights(env, starts)
            row = {"speed_m_s": speed, "seed": seed}
            for name, f in refs.items():
                s = summarise(f, refs["optimal"])
                row[f"{name}_success"] = s["success_rate"]
                row[f"{name}_excess"] = 0.0 if name == "optimal" else s["mean_excess_cost"]
                row[f"{name}_outage"] = s["outage_share"]
            row["seconds"] = time.perf_counter() - t0
            rows.append(row)
            print(json.dumps(row), flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "storm_baselines.json").write_text(json.dumps(rows, indent=2) + "\n")
    names = ("optimal", "frozen_plan", "replan", "straight_line")
    print("| storm speed | seed | " + " | ".join(names) + " |")
    print("|---|---|" + "---|" * len(names))
    for r in rows:
        cells = [
            f"{100 * r[f'{n}_excess']:.1f}% ({100 * r[f'{n}_outage']:.0f}% out)" for n in names
        ]
        print(f"| {r['speed_m_s']:g} m/s | {r['seed']} | " + " | ".join(cells) + " |")
    for speed in args.speeds:
        sel = [r for r in rows if r["speed_m_s"] == speed]
        means = {n: np.mean([r[f"{n}_excess"] for r in sel]) for n in names[1:]}
        print(f"speed {speed:g}: " + ", ".join(f"{n} {100 * v:.2f}%" for n, v in means.items()))


if __name__ == "__main__":
    main()
