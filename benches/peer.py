"""Peers, side by side: rainuav's default learner, the paper's Algorithm 1 literally
(``--preset paper``) and Stable-Baselines3's DQN on the same task with the same wall-clock
budget, measured the same way (the network alone, greedy, from the run's 200 fixed evaluation
starts, against the exact planner).

    pip install 'rainuav[peer]'
    python benches/peer.py --scenario paper --seed 0 --out runs/peer_paper_s0

First trains rainuav's default learner (``rainuav.rl.loop.train``, its own folder under
``--out``), then the literal preset (``time_budget_s``) and SB3's DQN for as many seconds as
that training took (``--budget-s`` sets another budget); SB3 is configured as a user would
configure it for a 300-step sparse-arrival task (below), on
``gym.make("rainuav/UAVNav-v0", radio_map=...)``. Writes ``peer.json`` with the three metric
sets. Results with the machine go to BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import rainuav  # noqa: F401 - registers rainuav/UAVNav-v0
from rainuav.envs import scenario_map
from rainuav.nav.env import UAVNavEnv
from rainuav.rl.config import TrainConfig
from rainuav.rl.evaluation import eval_starts, flights, reference_flights, summarise
from rainuav.rl.loop import train
from rainuav.rl.setup import make_env

SB3_CONFIG: dict[str, Any] = {
    # A user's configuration for a long-horizon task: a wide MLP, a long discount, a big
    # replay, a slower exploration decay than the default (10% of the run is short here).
    "policy": "MlpPolicy",
    "policy_kwargs": {"net_arch": [256, 256]},
    "gamma": 0.998,
    "buffer_size": 100_000,
    "learning_starts": 1000,
    "batch_size": 64,
    "learning_rate": 5e-4,
    "train_freq": 4,
    "target_update_interval": 1000,
    "exploration_fraction": 0.3,
    "exploration_final_eps": 0.05,
}


def policy_flights(predict: Any, env: UAVNavEnv, starts: np.ndarray) -> dict[str, np.ndarray]:
    """Greedy flights of ``predict`` ((N, 2) observations -> (N,) actions) from every start at
    once, on the batched stepper (the scalar env's transitions)."""
    n = len(starts)
    off = np.zeros((n, 2), dtype=np.int64)
    t = np.zeros(n, dtype=np.int64)
    live = np.ones(n, dtype=bool)
    ret = np.zeros(n)
    arrived = np.zeros(n, dtype=bool)
    paths: list[list[np.ndarray]] = [[s.copy()] for s in starts]
    while live.any():
        idx = np.flatnonzero(live)
        pos = starts[idx] + env.cfg.step_m * off[idx]
        a = np.asarray(predict(env.observe(pos)), dtype=np.int64).reshape(-1)
        r = env.stepper.step(starts[idx], off[idx], t[idx], a)
        off[idx], t[idx] = r["offset"], r["t"]
        ret[idx] += r["reward"]
        for j, k in enumerate(idx):
            paths[k].append(r["position"][j].copy())
        arrived[idx[r["arrived"]]] = True
        live[idx[r["terminated"] | r["truncated"]]] = False
    return flights(env, ret, arrived, [np.array(p) for p in paths])


def run_sb3(env: UAVNavEnv, seed: int, budget_s: float) -> tuple[Any, dict[str, Any]]:
    """SB3 DQN trained on ``env`` for ``budget_s`` seconds of wall clock."""
    from stable_baselines3 import DQN
    from stable_baselines3.common.callbacks import BaseCallback

    class WallClock(BaseCallback):
        def __init__(self, seconds: float) -> None:
            super().__init__()
            self.seconds, self.t0 = seconds, time.perf_counter()

        def _on_step(self) -> bool:
            return time.perf_counter() - self.t0 < self.seconds

    cfg = dict(SB3_CONFIG)
    model = DQN(cfg.pop("policy"), env, seed=seed, device="cpu", verbose=0, **cfg)
    t0 = time.perf_counter()
    model.learn(total_timesteps=10**9, callback=WallClock(budget_s), progress_bar=False)
    return model, {"training_seconds": time.perf_counter() - t0, "steps": model.num_timesteps}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--budget-s", type=float, default=None)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    import torch

    torch.set_num_threads(1)
    cfg = TrainConfig(scenario=args.scenario, seed=args.seed, out=str(args.out / "rainuav"))
    rm = scenario_map(args.scenario)
    ours = train(cfg, progress=False, radio_map=rm)
    budget = ours["training_seconds"] if args.budget_s is None else args.budget_s
    literal = train(
        dataclasses.replace(
            cfg, preset="paper", time_budget_s=budget, out=str(args.out / "paper_preset")
        ),
        progress=False,
        radio_map=rm,
    )
    env = make_env(cfg, rm)
    starts = eval_starts(env, cfg.eval_starts, cfg.eval_seed)
    optimum = reference_flights(env, starts)["optimal"]
    sb3_env = gym.make("rainuav/UAVNav-v0", radio_map=rm, **_task(env))
    model, info = run_sb3(sb3_env.unwrapped, args.seed, budget)
    theirs = summarise(
        policy_flights(lambda o: model.predict(o, deterministic=True)[0], env, starts), optimum
    )
    keys = ("success_rate", "mean_excess_cost", "worst_excess_cost", "training_seconds")
    report = {
        "scenario": args.scenario,
        "seed": args.seed,
        "rainuav": {k: ours[k] for k in keys},
        "paper_preset": {**{k: literal[k] for k in keys}, "episodes": literal["episodes"]},
        "straight_line_mean_excess_cost": ours["straight_line_mean_excess_cost"],
        "sb3_dqn": {**theirs, **info, "config": SB3_CONFIG},
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "peer.json").write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2))
    return 0


def _task(env: UAVNavEnv) -> dict[str, Any]:
    c = env.cfg
    return {
        "goal_m": c.goal_m, "step_m": c.step_m, "tol_m": c.tol_m, "max_steps": c.max_steps,
        "mu": c.mu, "reward": c.reward, "signal": c.signal, "min_db": c.min_db,
        "goal_reward": c.goal_reward, "out_of_bounds_penalty": c.out_of_bounds_penalty,
    }  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
