"""The exact planner on a map and on maps in time, same starts, same run.

    python benches/storm_planner.py [--save FILE.npz]

200 fixed starts (seed 12345) on the paper preset's map, on the `storm` world (storm seed 0,
ray engine, 61 slices over the 300-move horizon) and on `urban` (ray engine); the best of two
timings of ``planner.optimal_many`` each. ``--save``: every plan's return, actions and path, to
compare two builds (``python benches/storm_planner.py --compare A.npz B.npz``).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from rainuav.nav import planner
from rainuav.rl.evaluation import eval_starts
from rainuav.world import WorldSpec, build_world

WORLDS = (
    ("paper", "paper (one map)", WorldSpec()),
    ("storm", "storm seed 0 (61 slices)", WorldSpec(scenario="storm", engine="ray")),
    ("urban", "urban (one map, ray engine)", WorldSpec(scenario="urban", engine="ray")),
)


def compare(a: Path, b: Path) -> None:
    """Prints the largest difference between two saved sets of plans."""
    x, y = np.load(a), np.load(b)
    for k in x.files:
        same = x[k].shape == y[k].shape and np.array_equal(x[k], y[k])
        print(f"{k}: {'equal' if same else 'DIFFERENT'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--save", type=Path, default=None)
    ap.add_argument("--compare", type=Path, nargs=2, default=None)
    args = ap.parse_args()
    if args.compare is not None:
        compare(*args.compare)
        return
    saved: dict[str, np.ndarray] = {}
    for key, name, spec in WORLDS:
        env = build_world(spec).env()
        starts = eval_starts(env, 200, 12345)
        best = float("inf")
        for _ in range(2):
            t0 = time.perf_counter()
            plans = planner.optimal_many(env, starts)
            best = min(best, time.perf_counter() - t0)
        print(f"{name}: 200 exact plans in {best:.2f} s", flush=True)
        saved[f"{key}_returns"] = np.array([p.return_ for p in plans])
        saved[f"{key}_moves"] = np.array([len(p.actions) for p in plans])
        saved[f"{key}_actions"] = np.concatenate([p.actions for p in plans])
        saved[f"{key}_paths"] = np.concatenate([p.path_m for p in plans])
    if args.save is not None:
        np.savez(args.save, **saved)


if __name__ == "__main__":
    main()
