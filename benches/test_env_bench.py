"""Batched environment throughput (target: >= 10^6 UAV steps per second), against the scalar
Gymnasium env doing the same steps one at a time, in the same run."""

from __future__ import annotations

import numpy as np
from rainuav.nav import UAVNavEnv

N = 8192
SIR = np.random.default_rng(0).uniform(-10, 30, (200, 200))


def make():
    env = UAVNavEnv(sir_db=SIR, extent_m=(0, 2000, 0, 2000))
    rng = np.random.default_rng(1)
    starts = np.array([env.sample_start(rng) for _ in range(N)])
    actions = rng.integers(0, 4, N)
    return env, starts, actions


def test_bench_batched_steps(benchmark) -> None:
    env, starts, actions = make()
    off = np.zeros((N, 2), dtype=np.int64)
    t = np.zeros(N, dtype=np.int64)
    out = benchmark(env.step_batch, starts, off, np.zeros(N, dtype=np.int64), t, actions)
    assert out["reward"].shape == (N,)
    benchmark.extra_info["uav_steps_per_call"] = N


def test_bench_scalar_env_steps(benchmark) -> None:
    env, starts, actions = make()
    env.reset(options={"start_m": starts[0]})

    def run():
        for a in actions[:1000]:
            env.step(int(a))
            env.reset(options={"start_m": starts[0]})

    benchmark.pedantic(run, rounds=3, iterations=1)
    benchmark.extra_info["uav_steps_per_call"] = 1000


def _vector_pair(n: int):
    """The batched vector env and Gymnasium's SyncVectorEnv of scalar envs, same task."""
    from gymnasium.vector import SyncVectorEnv
    from rainuav.nav.vector import UAVNavVectorEnv

    env = UAVNavEnv(sir_db=SIR, extent_m=(0, 2000, 0, 2000))
    vec = UAVNavVectorEnv(env, n)
    sync = SyncVectorEnv([lambda: UAVNavEnv(sir_db=SIR, extent_m=(0, 2000, 0, 2000))] * n)
    return vec, sync


def _steps(envs, n: int, calls: int):
    actions = np.random.default_rng(2).integers(0, 4, (calls, n))
    envs.reset(seed=0)

    def run():
        for a in actions:
            envs.step(a)

    return run


def test_bench_vector_env_steps(benchmark) -> None:
    # 64 UAVs x 100 calls, autoreset included: rainuav's VectorEnv over the batched stepper.
    vec, _ = _vector_pair(64)
    benchmark.pedantic(_steps(vec, 64, 100), rounds=5, iterations=1)
    benchmark.extra_info["uav_steps_per_call"] = 6400


def test_bench_sync_vector_env_steps(benchmark) -> None:
    # The same steps through Gymnasium's SyncVectorEnv of 64 scalar envs (the reference).
    _, sync = _vector_pair(64)
    benchmark.pedantic(_steps(sync, 64, 100), rounds=5, iterations=1)
    benchmark.extra_info["uav_steps_per_call"] = 6400
