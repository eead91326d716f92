"""The batched stepper and the vector env on maps in time against one map, same work, same run:
does a weather that moves keep the speed of a step?

    python benches/stepper_in_time.py

A storm-sized signal (61 slices of 200 x 200 pixels) against its first slice alone; 1024 UAVs
stepped 200 times with random moves, and a 64-UAV vector env stepped 2000 times. Prints the
steps per second of each and the ratio (in time / one map); then the batched stepper among three
flight levels (six moves), on maps and in time, against the one map.
"""

from __future__ import annotations

import time

import numpy as np
from rainuav.nav import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.vector import UAVNavVectorEnv

EXT = (0.0, 2000.0, 0.0, 2000.0)


def per_second(env: UAVNavEnv, n: int, steps: int, rng: np.random.Generator) -> float:
    start = np.array([env.sample_start(rng) for _ in range(n)])
    off = np.zeros((n, 2), dtype=np.int64)
    t = np.zeros(n, dtype=np.int64)
    level = np.zeros(n, dtype=np.int64)
    moves = int(env.action_space.n)  # among levels a climb and a descent besides
    t0 = time.perf_counter()
    for _ in range(steps):
        r = env.step_batch(start, off, level, t % env.cfg.max_steps, rng.integers(0, moves, n))
        off, t, level = np.clip(r["offset"], -50, 50), r["t"], r["level"]
    return n * steps / (time.perf_counter() - t0)


def vector_per_second(env: UAVNavEnv, n: int, steps: int, rng: np.random.Generator) -> float:
    vec = UAVNavVectorEnv(env, n)
    vec.reset(seed=0)
    t0 = time.perf_counter()
    for _ in range(steps):
        vec.step(rng.integers(0, 4, n))
    return n * steps / (time.perf_counter() - t0)


def main() -> None:
    rng = np.random.default_rng(0)
    slices = rng.normal(5.0, 8.0, (61, 200, 200))
    task = {"goal_m": (1400.0, 1600.0), "min_db": -2.0}
    one = UAVNavEnv(field=SignalField(slices[0], EXT), **task)
    moving = UAVNavEnv(field=SignalField.series(slices, np.arange(61) * 5.0, EXT), **task)
    for name, fn, n, steps in (
        ("batched stepper, 1024 UAVs", per_second, 1024, 200),
        ("vector env, 64 UAVs", vector_per_second, 64, 2000),
    ):
        a = min(fn(one, n, steps, np.random.default_rng(1)) for _ in range(3))
        b = min(fn(moving, n, steps, np.random.default_rng(1)) for _ in range(3))
        print(f"{name}: one map {a:,.0f} steps/s, in time {b:,.0f} steps/s, ratio {b / a:.2f}")
    # Among three flight levels (six moves), on maps and in time, against the one map.
    alts = [30.0, 60.0, 90.0]
    three = rng.normal(5.0, 8.0, (61, 3, 200, 200))
    still = UAVNavEnv(field=SignalField.from_stack(three[0], alts, EXT), **task)
    storm = UAVNavEnv(field=SignalField.from_stack(three, alts, EXT, t_s=np.arange(61) * 5.0),
                      **task)  # fmt: skip
    a = min(per_second(one, 1024, 200, np.random.default_rng(1)) for _ in range(3))
    for name, env in (("three levels", still), ("three levels in time", storm)):
        b = min(per_second(env, 1024, 200, np.random.default_rng(1)) for _ in range(3))
        print(f"batched stepper, 1024 UAVs, {name}: {b:,.0f} steps/s, ratio to one map {b / a:.2f}")


if __name__ == "__main__":
    main()
