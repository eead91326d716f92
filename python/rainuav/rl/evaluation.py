"""Measuring a policy: greedy flights from fixed starts against the exact planner
(:func:`evaluate`), the run's evaluation (:func:`evaluate_run_policy`) and the greedy checks
on held-out validation starts during training (:class:`Validation`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from rainuav.errors import InvalidInputError
from rainuav.nav import planner
from rainuav.nav.env import UAVNavEnv
from rainuav.radio.radiomap import RadioMap
from rainuav.rl.collect import greedy_rollouts
from rainuav.rl.config import TrainConfig, load_config
from rainuav.rl.dqn import Agent
from rainuav.rl.setup import make_agent, make_env, pick_device

__all__ = [
    "Validation",
    "eval_starts",
    "evaluate",
    "evaluate_run_policy",
    "evaluate_saved_run",
    "relative_gap",
]


def eval_starts(env: UAVNavEnv, n: int, seed: int) -> np.ndarray:
    """``n`` starts drawn uniformly (farther than the tolerance from the goal) from ``seed``."""
    rng = np.random.default_rng(seed)
    return np.array([env.sample_start(rng) for _ in range(n)], dtype=np.float64).reshape(-1, 2)


def relative_gap(optimum: np.ndarray, returns: np.ndarray) -> np.ndarray:
    """Per start, the share of the exact optimum's return the policy gave up."""
    return (optimum - returns) / np.maximum(np.abs(optimum), 1e-9)


def evaluate(agent: Agent, env: UAVNavEnv, starts: np.ndarray) -> tuple[dict[str, Any], list]:
    """Greedy policy from every start against the exact planner. With the shield on, also
    the share of flights it steered and the same network's numbers without it."""
    rolls = greedy_rollouts(agent, env, starts)
    plans = planner.optimal_many(env, starts)
    rets = np.array([r["return"] for r in rolls])
    opt = np.array([p.return_ for p in plans])
    gap = relative_gap(opt, rets)
    shielded: dict[str, Any] = {}
    if agent.cfg.shield:
        free = greedy_rollouts(agent, env, starts, shield=False)
        free_gap = relative_gap(opt, np.array([r["return"] for r in free]))
        shielded = {
            "shielded_flights": float(np.mean([r["overridden"] > 0 for r in rolls])),
            "unshielded_success_rate": float(np.mean([r["reached"] for r in free])),
            "unshielded_mean_gap_to_optimal": float(free_gap.mean()),
        }
    sirs = np.concatenate([r["sir"] for r in rolls])
    metrics = {
        "success_rate": float(np.mean([r["reached"] for r in rolls])),
        "mean_return": float(rets.mean()),
        "mean_steps": float(np.mean([r["steps"] for r in rolls])),
        "mean_sir_db": float(sirs.mean()),
        "outage_share": float(np.mean(sirs < env.cfg.sir_min_db)),
        "mean_gap_to_optimal": float(gap.mean()),
        "median_gap_to_optimal": float(np.median(gap)),
        "worst_gap_to_optimal": float(gap.max()),
        "optimal_mean_return": float(opt.mean()),
        "straight_line_mean_return": float(
            np.mean([planner.straight_line(env, s).return_ for s in starts])
        ),
        "eval_starts": len(starts),
        **shielded,
    }
    return metrics, rolls


@dataclass
class Validation:
    """Greedy checks during training: every ``validate_every`` finished episodes the greedy
    policy flies from held-out validation starts (never the evaluation starts), and the
    history of (episodes, success, mean gap to the optimum) and the online weights with the
    smallest gap are kept. With ``keep_best`` those weights are the run's result (early
    stopping; when that pays: ``docs/learner.md``)."""

    starts: np.ndarray
    optimum: np.ndarray
    best_gap: float = math.inf
    best_at: int = 0
    best_online: dict[str, torch.Tensor] | None = None
    history: list[tuple[int, float, float]] = field(default_factory=list)

    def check(self, agent: Agent, env: UAVNavEnv, finished: int) -> tuple[float, float]:
        """Flies the greedy policy from the validation starts; returns (success, mean gap)."""
        rolls = greedy_rollouts(agent, env, self.starts)
        rets = np.array([r["return"] for r in rolls])
        gap = float(np.mean(relative_gap(self.optimum, rets)))
        success = float(np.mean([r["reached"] for r in rolls]))
        self.history.append((finished, success, gap))
        if gap < self.best_gap:
            self.best_gap, self.best_at = gap, finished
            self.best_online = {
                k: v.detach().cpu().clone() for k, v in agent.online.state_dict().items()
            }
        return success, gap

    def state_dict(self) -> dict[str, Any]:
        return {
            "best_gap": self.best_gap,
            "best_at": self.best_at,
            "best_online": self.best_online,
            "history": list(self.history),
        }

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.best_gap, self.best_at = d["best_gap"], d["best_at"]
        self.best_online, self.history = d["best_online"], list(d["history"])


def evaluate_run_policy(
    cfg: TrainConfig, agent: Agent, env: UAVNavEnv, checks: Validation
) -> tuple[dict[str, Any], list]:
    """Evaluates the run's policy from the evaluation starts: the final network, or with
    ``keep_best`` the best on validation (loaded into ``agent``; the final network's numbers
    are then added as ``final_*``)."""
    starts = eval_starts(env, cfg.eval_starts, cfg.eval_seed)
    metrics, rolls = evaluate(agent, env, starts)
    metrics["selected_at_episode"] = cfg.dqn.episodes
    if cfg.keep_best and checks.best_online is not None and checks.best_at != cfg.dqn.episodes:
        final = metrics
        agent.online.load_state_dict(checks.best_online)
        metrics, rolls = evaluate(agent, env, starts)
        metrics["selected_at_episode"] = checks.best_at
        for key in ("success_rate", "mean_return", "mean_gap_to_optimal", "worst_gap_to_optimal"):
            metrics[f"final_{key}"] = final[key]
    return metrics, rolls


def evaluate_saved_run(run_dir: Path, device: str = "cpu") -> tuple[dict[str, Any], list, Any]:
    """Re-evaluates a saved training run: loads its ``config.toml``, ``radiomap.npz`` and
    ``checkpoint.pt`` and evaluates the policy the run reports (:func:`evaluate_run_policy`).
    Returns the metrics, the greedy flights and the environment; writes nothing."""
    run = Path(run_dir)
    for name in ("config.toml", "radiomap.npz", "checkpoint.pt"):
        if not (run / name).exists():
            raise InvalidInputError(f"{run}: missing {name}; is this a rainuav.train output?")
    cfg = load_config(run / "config.toml")
    rm = RadioMap.load(run / "radiomap.npz")
    env = make_env(cfg, rm.sir_db, rm.extent_m)
    agent = make_agent(cfg, env, pick_device(device))
    state = torch.load(run / "checkpoint.pt", weights_only=False, map_location=agent.device)
    agent.load_state_dict(state["agent"])
    checks = Validation(np.zeros((0, 2)), np.zeros(0))
    if "validation" in state:
        checks.load_state_dict(state["validation"])
    metrics, rolls = evaluate_run_policy(cfg, agent, env, checks)
    metrics["episodes"] = len(state["returns"])
    metrics["training_seconds"] = state["train_seconds"]
    return metrics, rolls, env
