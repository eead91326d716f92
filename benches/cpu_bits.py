"""Which bits this CPU gives: a fingerprint of one forward and backward pass of the storm
learner's network (``STORM_LEARNER``, seed 0) on a fixed batch of 128 observations, one torch
thread. The same seed gives the same training run on one machine; across machines the run
repeats only where this fingerprint is the same, because oneDNN and MKL choose their kernels
(and so the order of their sums) by the CPU's vector instructions.

    python benches/cpu_bits.py
    ONEDNN_MAX_CPU_ISA=AVX2 MKL_CBWR=AVX2 python benches/cpu_bits.py   # kernels capped at AVX2

Prints the fingerprint (the first 12 hex digits of a SHA-256 of the Q values and every
parameter's gradient), the torch version and the two environment variables.
"""

from __future__ import annotations

import hashlib
import os

import numpy as np
import torch
from rainuav.nav import UAVNavEnv
from rainuav.nav.field import SignalSeries
from rainuav.rl.config import STORM_LEARNER, DQNConfig
from rainuav.rl.dqn import Agent
from rainuav.rl.setup import make_encoder

N = 128


def fingerprint() -> str:
    torch.set_num_threads(1)
    rng = np.random.default_rng(0)
    field = SignalSeries(
        rng.normal(5.0, 8.0, (61, 200, 200)), np.arange(61) * 5.0, (0.0, 2000.0, 0.0, 2000.0)
    )
    env = UAVNavEnv(field=field, goal_m=(1400.0, 1600.0), min_db=-2.0, observation="weather")
    keys = ("conv", "move_features", "goal_maps")
    d = DQNConfig(**{k: v for k, v in STORM_LEARNER.items() if k in keys})
    agent = Agent(d, 0, torch.device("cpu"), make_encoder(d, env, (0.005, 0.005)))
    pos, t = rng.uniform(0.0, 2000.0, (N, 2)), rng.integers(0, 300, N)
    goals = rng.uniform(100.0, 1900.0, (N, 2))
    x = torch.as_tensor(agent.observe(env.observe(pos, t, goals), t))
    q = agent.online(x)
    q.square().sum().backward()
    h = hashlib.sha256(q.detach().numpy().tobytes())
    for p in agent.online.parameters():
        assert p.grad is not None
        h.update(p.grad.numpy().tobytes())
    return h.hexdigest()[:12]


def main() -> None:
    env = {k: os.environ.get(k, "") for k in ("ONEDNN_MAX_CPU_ISA", "MKL_CBWR")}
    print(f"fingerprint {fingerprint()} (torch {torch.__version__}, {env})")


if __name__ == "__main__":
    main()
