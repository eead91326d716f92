"""What a finished training writes: its evaluation, the weights it reports (``policy.pt``), the
figures, and ``metrics.json`` last (a folder that holds it is complete)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rainuav._io import write_atomic
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.figures import plot_policy, plot_stages, plot_storm_flights
from rainuav.rl import checkpoint
from rainuav.rl.config import TrainConfig, to_dict
from rainuav.rl.dqn import Agent
from rainuav.rl.evaluation import Validation, evaluate_run_policy
from rainuav.rl.plots import plot_returns
from rainuav.world.pool import VALIDATION_SEEDS, StormPool

__all__ = ["finish"]


def finish(
    cfg: TrainConfig,
    agent: Agent,
    env: UAVNavEnv,
    returns: list[float],
    stages: list,
    train_seconds: float,
    out: Path,
    checks: Validation,
    pool: StormPool | None = None,
) -> dict[str, Any]:
    """Evaluates the run, saves its weights and figures, and writes `metrics.json` last.

    The evaluation is [`evaluate_run_policy()`][rainuav.rl.evaluation.evaluate_run_policy]; the
    weights go to `policy.pt`.

    Args:
        cfg: The run's configuration.
        agent: The agent.
        env: The environment evaluated in.
        returns: Every episode's return.
        stages: The stages' rollouts for the figures.
        train_seconds: The training time, s.
        out: The run's folder.
        checks: The validation checks.
        pool: The storm pool (its storms recorded), where the run has one.

    Returns:
        The metrics.
    """
    metrics, rolls = evaluate_run_policy(cfg, agent, env, checks)
    policy = {k: v.detach().cpu() for k, v in agent.online.state_dict().items()}
    checkpoint.save(out / "policy.pt", {"online": policy, "config": to_dict(cfg)})
    metrics["training_seconds"] = train_seconds
    metrics["episodes"] = len(returns)
    metrics["device"] = str(agent.device)
    if pool is not None:  # where the training time went, and which storms it flew
        metrics["storms_flown"] = len(pool.flown)
        metrics["storm_map_seconds"] = pool.map_seconds
        metrics["storm_wait_seconds"] = pool.wait_seconds
        metrics["evaluated_on_storm_seed"] = VALIDATION_SEEDS[0]
    plot_returns(returns, out / "returns.png", checks.history)
    plot_policy(env, metrics, rolls[:40], out / "trajectories.png")
    terms = env.terms()
    if terms.varies and terms.altitudes_m is None:  # (among levels: trajectories.png)
        plot_storm_flights(env, rolls[:6], out / "storm_flights.png")
    if stages:
        plot_stages(env, stages, out / "stages.png")
    # last: a folder that holds metrics.json is complete (a stop before it leaves none)
    text = json.dumps(metrics, indent=2)
    write_atomic(out / "metrics.json", lambda t: t.write_text(text + "\n"))
    return metrics
