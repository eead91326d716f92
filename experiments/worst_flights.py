"""The worst flights of a network that flies any storm, for looking at what the
network gets wrong: in the storm of the evaluation where its mean excess cost was highest
(``evaluation.json`` of ``python -m rainuav.evaluate RUN --storm-seeds A-B``), the 3 starts of
the 20 where it paid most over the optimum (or did not arrive), drawn over the SINR at three
instants beside the frozen take-off plan's and the optimum's flights.

    python experiments/worst_flights.py runs/storms runs/storms/eval_storms_1000000-1000049

Writes ``worst_flights.png`` into the evaluation folder and prints, per flight drawn, its
storm, start, excess cost (or "did not arrive") and moves.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
from rainuav.nav import planner
from rainuav.nav.figures import plot_storm_flights
from rainuav.rl import checkpoint
from rainuav.rl.collect import greedy_rollouts
from rainuav.rl.config import load_config
from rainuav.rl.evaluation import eval_starts, load_agent
from rainuav.world import build_world, spec_of


def main(argv: list[str]) -> int:
    run, folder = Path(argv[0]), Path(argv[1])
    rows = json.loads((folder / "evaluation.json").read_text())["worlds"]
    worst = max(rows, key=lambda r: (1 - r["success_rate"], r["mean_excess_cost"] or 0.0))
    cfg = load_config(run / "config.toml")
    spec = dataclasses.replace(spec_of(cfg), storm_pool=0, random_goal=False)
    env = build_world(dataclasses.replace(spec, storm_seed=worst["storm_seed"])).env()
    state = checkpoint.load(run / "checkpoint.pt", ("agent", "returns", "train_seconds"))
    agent, _, _ = load_agent(run / "checkpoint.pt", state, cfg, env, "cpu", False)
    starts = eval_starts(env, worst["eval_starts"], cfg.eval_seed)
    rolls = greedy_rollouts(agent, env, starts)
    best = planner.optimal_many(env, starts)
    cost = np.array([-(r["return"] - env.cfg.goal_reward * r["reached"]) for r in rolls])
    opt = np.array([-(p.return_ - env.cfg.goal_reward) for p in best])
    excess = np.where([r["reached"] for r in rolls], (cost - opt) / opt, np.inf)
    pick = np.argsort(-excess)[:3]
    for k in pick:
        what = "did not arrive" if np.isinf(excess[k]) else f"excess {100 * excess[k]:.1f}%"
        print(f"storm {worst['storm_seed']}, start {starts[k].round(1)}: {what}, "
              f"{rolls[k]['steps']} moves (optimum {len(best[k].actions)})")  # fmt: skip
    plot_storm_flights(env, [rolls[k] for k in pick], folder / "worst_flights.png")
    print(f"wrote {folder / 'worst_flights.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
