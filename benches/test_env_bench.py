"""Batched environment throughput (target: >= 10^6 UAV steps per second), against the scalar
Gymnasium env doing the same steps one at a time, in the same run."""

from __future__ import annotations

import numpy as np
from rainuav.nav import BatchStepper, UAVNavEnv

N = 8192
SIR = np.random.default_rng(0).uniform(-10, 30, (200, 200))


def make():
    env = UAVNavEnv(sir_db=SIR, extent_m=(0, 2000, 0, 2000))
    rng = np.random.default_rng(1)
    starts = np.array([env.sample_start(rng) for _ in range(N)])
    actions = rng.integers(0, 4, N)
    return env, BatchStepper(env.field, env.cfg), starts, actions


def test_bench_batched_steps(benchmark) -> None:
    _, stepper, starts, actions = make()
    off = np.zeros((N, 2), dtype=np.int64)
    t = np.zeros(N, dtype=np.int64)
    out = benchmark(stepper.step, starts, off, t, actions)
    assert out["reward"].shape == (N,)
    benchmark.extra_info["uav_steps_per_call"] = N


def test_bench_scalar_env_steps(benchmark) -> None:
    env, _, starts, actions = make()
    env.reset(options={"start_m": starts[0]})

    def run():
        for a in actions[:1000]:
            env.step(int(a))
            env.reset(options={"start_m": starts[0]})

    benchmark.pedantic(run, rounds=3, iterations=1)
    benchmark.extra_info["uav_steps_per_call"] = 1000
