"""One decision for 64 UAVs by the weather-reading network, on the CPU (the aim: at
most 1 ms): the storm learner's network (the ``storms`` preset's: 8/16 channels, move features), the
first one (16/32 channels), and the single-map network doing the same decision in the same
run.

    python benches/decision.py [--threads 2]

A decision: the observation of every UAV (``env.observe``: the SINR window and whole-area grid
sampled from a 61-slice storm) encoded, and the network's greedy actions (one torch thread by
default, as training and evaluation run; ``--threads 2``: both cores of the 2-core machine).
The UAVs are at 64 different instants of the storm (as a training batch flies them), and, for
the decision, also at one instant (a fleet's step: every UAV reads the same two slices). The
weights are the initial ones: the time does not depend on them. Prints the median of 200 timed
decisions (after 20 warm-up ones) for the observation, the network and both, for each learner.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import torch
from rainuav.nav import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.training import network_inputs
from rainuav.rl.config import DQNConfig, preset_learner
from rainuav.rl.dqn import Agent
from rainuav.rl.setup import make_encoder

EXT = (0.0, 2000.0, 0.0, 2000.0)
N = 64


def median_ms(fn: Callable[[], object], reps: int = 200) -> float:
    for _ in range(20):
        fn()
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def storm_and_fleet(n: int = N) -> tuple[SignalField, np.ndarray, np.ndarray, np.ndarray]:
    """The bench's storm (61 random slices of 200 x 200 pixels over 2 km, 5 s apart) and ``n``
    UAVs in it: positions, instants (moves) and destinations, all drawn from seed 0."""
    rng = np.random.default_rng(0)
    field = SignalField.series(rng.normal(5.0, 8.0, (61, 200, 200)), np.arange(61) * 5.0, EXT)
    pos = rng.uniform(0.0, 2000.0, (n, 2))
    t = rng.integers(0, 300, n)
    return field, pos, t, rng.uniform(100.0, 1900.0, (n, 2))


def storm_network() -> DQNConfig:
    """The storm learner's network (the ``storms`` preset's architecture, default training)."""
    keys = ("conv", "move_features", "goal_maps")
    return DQNConfig(**{k: v for k, v in preset_learner("storms").items() if k in keys})


def make_agent(d: DQNConfig, observation: str, field: SignalField) -> tuple[UAVNavEnv, Agent]:
    """The env on ``field`` with the task's destination and the learner's agent (seed 0)."""
    env = UAVNavEnv(field=field, goal_m=(1400.0, 1600.0), min_db=-2.0, observation=observation)
    return env, Agent(
        d,
        0,
        torch.device("cpu"),
        make_encoder(d, replace(network_inputs(env), step=(0.005, 0.005))),
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")
    torch.set_num_threads(ap.parse_args().threads)
    field, pos, t, goals = storm_and_fleet()
    t1 = np.full(N, 150)  # a fleet's step: every UAV at one instant
    learners = (
        ("weather network (storm learner)", "weather", storm_network()),
        ("weather network (16/32 channels, no move features)", "weather", DQNConfig()),
        ("position network", "position", DQNConfig()),
    )
    for name, observation, d in learners:
        env, agent = make_agent(d, observation, field)
        g = goals if observation == "weather" else None
        x = agent.observe(env.observe(pos, t, g), t)
        obs_ms = median_ms(lambda env=env, g=g: env.observe(pos, t, g))
        net_ms = median_ms(lambda agent=agent, x=x: agent.greedy(x))
        both_ms = median_ms(
            lambda agent=agent, env=env, g=g: agent.greedy(agent.observe(env.observe(pos, t, g), t))
        )
        fleet_ms = median_ms(
            lambda agent=agent, env=env, g=g: agent.greedy(
                agent.observe(env.observe(pos, t1, g), t1)
            )
        )
        params = sum(p.numel() for p in agent.online.parameters())
        print(
            f"{name} ({params:,} weights, input {x.shape[1]}): {N} UAVs: observation "
            f"{obs_ms:.3f} ms, network {net_ms:.3f} ms, decision {both_ms:.3f} ms "
            f"(one instant: {fleet_ms:.3f} ms)"
        )


if __name__ == "__main__":
    main()
