"""Greedy evaluation flights (``rainuav.rl.collect.greedy_rollouts``) with the shield against the
same network without it, in the same run: 100 starts on a 200 x 200 map, an untrained network
(seeded). The two fly different numbers of moves, so each records its moves and the cost is
compared per move."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from rainuav.nav import UAVNavEnv
from rainuav.rl.collect import greedy_rollouts
from rainuav.rl.config import TrainConfig
from rainuav.rl.evaluation import eval_starts
from rainuav.rl.setup import make_agent

SIR = np.random.default_rng(0).uniform(-10, 30, (200, 200))


@pytest.mark.parametrize("shield", [False, True])
def test_bench_greedy_rollouts(benchmark, shield: bool) -> None:
    env = UAVNavEnv(sir_db=SIR, extent_m=(0, 2000, 0, 2000))
    torch.manual_seed(0)
    agent = make_agent(TrainConfig(), env, torch.device("cpu"))
    starts = eval_starts(env, 100, 3)
    rolls = benchmark.pedantic(
        greedy_rollouts, args=(agent, env, starts, shield), rounds=3, iterations=1
    )
    moves = sum(r["steps"] for r in rolls)
    assert moves > 0
    benchmark.extra_info["moves_per_call"] = moves
