"""The exact planner on a map and on maps in time, same starts, same run.

    python benches/storm_planner.py

200 fixed starts (seed 12345) on the paper preset's map and on the `storm` world (storm seed
0, ray engine, 61 slices over the 300-move horizon); the best of two timings of
``planner.optimal_many`` each.
"""

from __future__ import annotations

import time

from rainuav.nav import planner
from rainuav.rl.evaluation import eval_starts
from rainuav.world import WorldSpec, build_world


def main() -> None:
    for name, spec in (
        ("paper (one map)", WorldSpec()),
        ("storm seed 0 (61 slices)", WorldSpec(scenario="storm", engine="ray")),
    ):
        env = build_world(spec).env()
        starts = eval_starts(env, 200, 12345)
        best = float("inf")
        for _ in range(2):
            t0 = time.perf_counter()
            planner.optimal_many(env, starts)
            best = min(best, time.perf_counter() - t0)
        print(f"{name}: 200 exact plans in {best:.2f} s")


if __name__ == "__main__":
    main()
