"""Which bits this CPU gives: a fingerprint of one forward and backward pass of the storm
learner's network (the ``storms`` preset's, seed 0) on a fixed batch of 128 observations, one
torch thread. The same seed gives the same training run on one machine; across machines the run
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

import torch
from decision import make_agent, storm_and_fleet, storm_network

N = 128


def fingerprint() -> str:
    torch.set_num_threads(1)
    field, pos, t, goals = storm_and_fleet(N)  # the decision bench's storm and draws
    env, agent = make_agent(storm_network(), "weather", field)
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
