"""Peers, side by side: rainuav's default learner, the paper's Algorithm 1 literally
(``--preset paper-learner``) and Stable-Baselines3's DQN on the same task with the same wall-clock
budget, measured the same way (the network alone, greedy, from the run's 200 fixed evaluation
starts, against the exact planner).

    pip install 'rainuav[peer]'
    python experiments/peer.py --scenario paper --seed 0 --out runs/peer_paper_s0

First trains rainuav's default learner (``rainuav.rl.loop.train``, its own folder under
``--out``), then the literal preset (``time_budget_s``) and SB3's DQN for as many seconds as
that training took (``--budget-s`` sets another budget); SB3 is configured as a user would
configure it for a 300-step sparse-arrival task (below), on the same world's env
(:func:`rainuav.world.build_world`). ``--peers`` picks among them and Tianshou's DQN with
dueling, double-Q and 3-step returns (``tianshou_dqn``; ``pip install tianshou``), configured
likewise. Writes ``peer.json`` with the metric sets. Results with the machine go to
BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from rainuav.nav.env import UAVNavEnv
from rainuav.rl.config import TrainConfig
from rainuav.rl.evaluation import eval_starts, flights, reference_flights, summarise
from rainuav.rl.loop import train
from rainuav.world import build_world

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


PEERS = ("paper_preset", "sb3_dqn", "tianshou_dqn")


def policy_flights(predict: Any, env: UAVNavEnv, starts: np.ndarray) -> dict[str, np.ndarray]:
    """Greedy flights of ``predict`` (a batch of the env's observations -> (N,) actions) from
    every start at once, on the batched stepper (the scalar env's transitions)."""
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
        a = np.asarray(predict(env.observe(pos, t[idx])), dtype=np.int64).reshape(-1)
        r = env.step_batch(starts[idx], off[idx], np.zeros_like(idx), t[idx], a)
        off[idx], t[idx] = r["offset"], r["t"]
        ret[idx] += r["reward"]
        for j, k in enumerate(idx):
            paths[k].append(r["position"][j].copy())
        arrived[idx[r["arrived"]]] = True
        live[idx[r["terminated"] | r["truncated"]]] = False
    return flights(env, ret, arrived, [np.array(p) for p in paths])


def run_sb3(
    env: Any, seed: int, budget_s: float, config: dict[str, Any] | None = None, algo: str = "dqn"
) -> tuple[Any, dict[str, Any]]:
    """SB3's DQN (or ``algo="ppo"``: PPO) trained on ``env`` for ``budget_s`` seconds of wall
    clock; ``config``: its policy and keywords (default :data:`SB3_CONFIG`)."""
    from stable_baselines3 import DQN, PPO
    from stable_baselines3.common.callbacks import BaseCallback

    class WallClock(BaseCallback):
        def __init__(self, seconds: float) -> None:
            super().__init__()
            self.seconds, self.t0 = seconds, time.perf_counter()

        def _on_step(self) -> bool:
            return time.perf_counter() - self.t0 < self.seconds

    cfg = dict(SB3_CONFIG if config is None else config)
    kind = DQN if algo == "dqn" else PPO
    model = kind(cfg.pop("policy"), env, seed=seed, device="cpu", verbose=0, **cfg)
    t0 = time.perf_counter()
    model.learn(total_timesteps=10**9, callback=WallClock(budget_s), progress_bar=False)
    return model, {"training_seconds": time.perf_counter() - t0, "steps": model.num_timesteps}


TIANSHOU_CONFIG: dict[str, Any] = {
    # Tianshou's DQN with the three extensions the issue names (dueling head, double-Q,
    # n-step), sized like the SB3 configuration above; 8 environments collected at once.
    "hidden_sizes": [256, 256],
    "dueling_hidden": [128],
    "gamma": 0.998,
    "n_step": 3,
    "target_update_freq": 1000,
    "lr": 5e-4,
    "buffer_size": 100_000,
    "batch_size": 64,
    "envs": 8,
    "collect_steps": 32,
    "updates_per_collect": 8,
    "learning_starts": 1000,
    "eps_start": 1.0,
    "eps_final": 0.05,
    "eps_fraction": 0.3,
}


def run_tianshou(make: Any, seed: int, budget_s: float) -> tuple[Any, dict[str, Any]]:
    """Tianshou 2's DQN (dueling, double-Q, n-step) trained for ``budget_s`` seconds of wall
    clock on ``TIANSHOU_CONFIG["envs"]`` copies of ``make()``; epsilon falls linearly over the
    first ``eps_fraction`` of the budget. Returns a greedy ``predict`` and run figures."""
    import torch
    from tianshou.algorithm import DQN
    from tianshou.algorithm.modelfree.dqn import DiscreteQLearningPolicy
    from tianshou.algorithm.optim import AdamOptimizerFactory
    from tianshou.data import Batch, Collector, VectorReplayBuffer
    from tianshou.env import DummyVectorEnv
    from tianshou.utils.net.common import Net

    c = TIANSHOU_CONFIG
    np.random.seed(seed)  # noqa: NPY002 - Tianshou's exploration draws from the global stream
    torch.manual_seed(seed)
    envs = DummyVectorEnv([make for _ in range(c["envs"])])
    envs.seed(seed)
    probe = make()
    net = Net(
        state_shape=probe.observation_space.shape,
        action_shape=int(probe.action_space.n),
        hidden_sizes=c["hidden_sizes"],
        dueling_param=({"hidden_sizes": c["dueling_hidden"]},) * 2,
    )
    policy = DiscreteQLearningPolicy(
        model=net, action_space=probe.action_space, eps_training=c["eps_start"]
    )
    algo = DQN(
        policy=policy,
        optim=AdamOptimizerFactory(lr=c["lr"]),
        gamma=c["gamma"],
        n_step_return_horizon=c["n_step"],
        target_update_freq=c["target_update_freq"],
        is_double=True,
    )
    buf = VectorReplayBuffer(c["buffer_size"], c["envs"])
    collector = Collector(algo, envs, buf, exploration_noise=True)
    collector.reset()
    t0, steps, updates = time.perf_counter(), 0, 0
    while (spent := time.perf_counter() - t0) < budget_s:
        frac = min(spent / (c["eps_fraction"] * budget_s), 1.0)
        policy.set_eps_training(c["eps_start"] + frac * (c["eps_final"] - c["eps_start"]))
        # What Tianshou's trainer does around a training step (exploration on, updates
        # allowed), without its epoch and test machinery.
        policy.is_within_training_step = True
        steps += collector.collect(n_step=c["collect_steps"]).n_collected_steps
        if len(buf) >= c["learning_starts"]:
            algo.train()
            for _ in range(c["updates_per_collect"]):
                algo.update(buf, c["batch_size"])
                updates += 1
        policy.is_within_training_step = False
    algo.eval()

    def predict(obs: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return policy(Batch(obs=obs.astype(np.float32), info={})).act

    info = {"training_seconds": time.perf_counter() - t0, "steps": steps, "updates": updates}
    return predict, info


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--budget-s", type=float, default=None)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument(
        "--peers", nargs="+", choices=PEERS, default=["paper_preset", "sb3_dqn"],
        help="which peers to train after rainuav's default (tianshou_dqn: pip install tianshou)",
    )  # fmt: skip
    args = ap.parse_args(argv)
    import torch

    torch.set_num_threads(1)
    cfg = TrainConfig(scenario=args.scenario, seed=args.seed, out=str(args.out / "rainuav"))
    world = build_world(cfg)
    ours = train(cfg, world, progress=False)
    budget = ours["training_seconds"] if args.budget_s is None else args.budget_s
    keys = ("success_rate", "mean_excess_cost", "worst_excess_cost", "training_seconds")
    report: dict[str, Any] = {
        "scenario": args.scenario,
        "seed": args.seed,
        "rainuav": {k: ours[k] for k in keys},
        "straight_line_mean_excess_cost": ours["straight_line_mean_excess_cost"],
    }
    if "paper_preset" in args.peers:
        literal = train(
            dataclasses.replace(
                cfg,
                preset="paper-learner",
                time_budget_s=budget,
                out=str(args.out / "paper_preset"),
            ),
            world,
            progress=False,
        )
        report["paper_preset"] = {**{k: literal[k] for k in keys}, "episodes": literal["episodes"]}
    env = world.env()
    starts = eval_starts(env, cfg.eval_starts, cfg.eval_seed)
    optimum = reference_flights(env, starts)["optimal"]
    if "sb3_dqn" in args.peers:
        model, info = run_sb3(world.env(), args.seed, budget)
        theirs = summarise(
            policy_flights(lambda o: model.predict(o, deterministic=True)[0], env, starts), optimum
        )
        report["sb3_dqn"] = {**theirs, **info, "config": SB3_CONFIG}
    if "tianshou_dqn" in args.peers:
        predict, info = run_tianshou(world.env, args.seed, budget)
        theirs = summarise(policy_flights(predict, env, starts), optimum)
        report["tianshou_dqn"] = {**theirs, **info, "config": TIANSHOU_CONFIG}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "peer.json").write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
