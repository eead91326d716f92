"""Peers over the storm distribution: Stable-Baselines3's DQN and PPO with
``MultiInputPolicy`` on the same env as rainuav's network that reads the weather, each for the
same wall-clock budget, all measured the same way on held-out storms.

    pip install 'rainuav[peer]'
    python experiments/peer_storms.py --budget-s 900 --storms 10 --out runs/peer_storms

The env: ``UAVNavEnv(observation="weather")`` (the task's fixed destination) over a pool of 16
training storms (:class:`rainuav.world.pool.StormPool`, the pool ``python -m rainuav.train
--preset storms`` trains on), one drawn per episode, a storm renewed every 32 episodes.
rainuav's learner trains first with ``time_budget_s`` = the budget (``--skip-rainuav RUN``: take
a run already trained, e.g. the README's, and its training time as the budget;
``--peers-only``: the peers alone, for ``--budget-s``, each peer in its own process with
``--peers NAME`` to run them one after the other on a quiet machine). Each peer is
then flown greedily from the same 20 fixed starts to the fixed destination in the storms
1 000 000 .. 1 000 000 + ``--storms`` - 1 (never trained on), against each storm's exact
space-time optimum. Writes ``peer_storms.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from peer import policy_flights, run_sb3
from rainuav.nav.env import UAVNavEnv
from rainuav.rl.config import DQNConfig, TrainConfig, load_config, preset_learner
from rainuav.rl.evaluation import eval_starts, reference_flights, summarise
from rainuav.rl.loop import train
from rainuav.rl.storm_eval import SUMMARY_KEYS
from rainuav.world import build_world, spec_of
from rainuav.world.pool import StormPool

SB3: dict[str, dict[str, Any]] = {
    # A user's configurations for a long-horizon task with a Dict observation.
    "sb3_dqn": {
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
    },
    "sb3_ppo": {
        "policy_kwargs": {"net_arch": [256, 256]},
        "gamma": 0.998,
        "n_steps": 2048,
        "batch_size": 256,
        "learning_rate": 3e-4,
    },
}


class RenewStorms(gym.Wrapper):
    """Renews one storm of the pool every ``every`` resets, round robin (between episodes:
    no flight sees its storm change)."""

    def __init__(self, env: UAVNavEnv, pool: StormPool, every: int) -> None:
        super().__init__(env)
        self.pool, self.every, self.resets = pool, every, 0

    def reset(self, **kw: Any) -> Any:
        self.resets += 1
        if self.resets % self.every == 0:
            self.pool.renew((self.resets // self.every) % self.pool.bank.worlds)
        return self.env.reset(**kw)


def held_out(cfg: TrainConfig, predicts: dict[str, Any], storms: int) -> dict[str, Any]:
    """Each predictor's mean figures over the held-out storms (20 fixed starts each)."""
    rows: dict[str, list[dict[str, Any]]] = {k: [] for k in predicts}
    base = dataclasses.replace(spec_of(cfg), storm_pool=0, random_goal=False)
    for k in range(1_000_000, 1_000_000 + storms):
        env = build_world(dataclasses.replace(base, storm_seed=k), cache=False).env()
        starts = eval_starts(env, 20, cfg.eval_seed)
        refs = reference_flights(env, starts, cfg.replan_every)
        for name, predict in predicts.items():
            m = summarise(policy_flights(predict, env, starts), refs["optimal"])
            for ref in ("straight_line", "frozen_plan", "replan"):
                m.update(
                    {f"{ref}_{key}": v for key, v in summarise(refs[ref], refs["optimal"]).items()}
                )
            m["optimal_outage_share"] = summarise(refs["optimal"], refs["optimal"])["outage_share"]
            rows[name].append(m)
    return {
        name: {key: float(np.mean([r[key] for r in rs if r.get(key) is not None]))
               for key in SUMMARY_KEYS if any(r.get(key) is not None for r in rs)}
        for name, rs in rows.items()
    }  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--budget-s", type=float, default=900.0)
    ap.add_argument("--storms", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--skip-rainuav", type=Path, default=None, help="a trained run to compare")
    ap.add_argument(
        "--peers-only",
        action="store_true",
        help="train and fly only the peers, for --budget-s (rainuav's run measured elsewhere)",
    )
    ap.add_argument("--peers", nargs="+", choices=tuple(SB3), default=list(SB3))
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    import torch
    from rainuav.rl.storm_eval import evaluate_storms

    torch.set_num_threads(1)
    # The storm learner (what --preset storms trains), its episodes scaled to the budget
    # at the 4.0 episodes/s of the README's run (9000 in 2256 s), the budget a cap.
    episodes = max(100, int(args.budget_s * 9000 / 2256))
    cfg = TrainConfig(
        scenario="storm", observation="weather", storm_pool=16, seed=args.seed,
        out=str(args.out / "rainuav"), time_budget_s=args.budget_s, validate_every=0,
        eval_starts=20, dqn=DQNConfig(**{**preset_learner("storms"), "episodes": episodes}),
    )  # fmt: skip
    seeds = list(range(1_000_000, 1_000_000 + args.storms))
    report: dict[str, Any] = {"budget_s": args.budget_s, "storms": seeds}
    if not args.peers_only:
        if args.skip_rainuav is None:
            train(cfg, StormPool(cfg, cfg.seed).world(), progress=False)
            run = Path(cfg.out)
        else:
            run, cfg = args.skip_rainuav, load_config(args.skip_rainuav / "config.toml")
        ours = json.loads((run / "metrics.json").read_text())
        report["budget_s"] = float(ours["training_seconds"])
        report["rainuav"] = evaluate_storms(run, seeds, starts=20, progress=False)[0]["mean"]
    budget = float(report["budget_s"])
    predicts = {}
    for name in args.peers:
        pool = StormPool(dataclasses.replace(cfg, storm_pool=16), args.seed)
        env = RenewStorms(pool.world().env(), pool, cfg.storm_episodes)
        algo = "dqn" if name == "sb3_dqn" else "ppo"
        model, info = run_sb3(
            env, args.seed, budget, {"policy": "MultiInputPolicy", **SB3[name]}, algo
        )
        pool.close()
        predicts[name] = lambda o, model=model: model.predict(o, deterministic=True)[0]
        report[f"{name}_run"] = {**info, "config": SB3[name]}
    report.update(held_out(cfg, predicts, args.storms))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "peer_storms.json").write_text(json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
