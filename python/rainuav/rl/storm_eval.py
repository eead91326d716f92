"""One saved network flown through many worlds it was not trained on (``python -m
rainuav.evaluate RUN --storm-seeds A-B``, or one other map with ``--random-goals``): per world
the network alone, the exact optimum (in space-time where the weather moves), the frozen
take-off plan, re-planning and the straight line from the same fixed starts, then the mean
over the worlds.

Destinations: the task's fixed one, or with ``random_goals`` one per start, drawn as training
draws them ([`rainuav.nav.training.random_flight()`][rainuav.nav.training.random_flight]: the
start within reach of it), each flight then planned and judged against its own destination's
optimum."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from rainuav._checks import check_integer
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.training import random_flight
from rainuav.radio.scene.storms import EVAL_SEEDS_FROM, MAX_STORM_SEED
from rainuav.rl import checkpoint
from rainuav.rl.config import check_config, load_config
from rainuav.rl.evaluation import eval_starts, evaluate, load_agent, reference_flights
from rainuav.world import build_world, spec_of

__all__ = ["MAX_STORMS", "SUMMARY_KEYS", "evaluate_storms", "evaluate_worlds", "parse_seeds"]

MAX_STORMS = 1000
"""The most storms one evaluation flies (each is mapped, about 2 s, and planned)."""
SUMMARY_KEYS = (
    "success_rate", "mean_excess_cost", "worst_excess_cost", "outage_share",
    "optimal_outage_share", "straight_line_success_rate", "straight_line_mean_excess_cost",
    "frozen_plan_success_rate", "frozen_plan_mean_excess_cost", "replan_success_rate",
    "replan_mean_excess_cost", "fixed_altitude_success_rate", "fixed_altitude_mean_excess_cost",
    "fixed_altitude_outage_share", "best_single_altitude_success_rate",
    "best_single_altitude_mean_excess_cost", "best_single_altitude_outage_share",
    "mean_altitude_m", "optimal_mean_altitude_m", "vertical_moves",
)  # fmt: skip
"""The figures averaged over the storms (``worst_excess_cost``: the worst over them); among
levels also the plans held at one altitude and the heights flown (absent on one level)."""


def parse_seeds(text: str) -> list[int]:
    """Storm seeds from `"A-B"` (inclusive) or `"K"`.

    Args:
        text: The range.

    Returns:
        The seeds, each in 0..2^63-1, at most [`MAX_STORMS`][rainuav.rl.storm_eval.MAX_STORMS].

    Raises:
        InvalidInputError: Not a range `A-B` with 0 <= A <= B, or too many storms.
    """
    parts = str(text).split("-")
    try:
        lo, hi = (int(parts[0]), int(parts[-1])) if len(parts) <= 2 else (None, None)
    except ValueError:
        lo = hi = None
    if lo is None or hi is None or not 0 <= lo <= hi <= MAX_STORM_SEED:
        raise InvalidInputError(f"--storm-seeds must be A-B with 0 <= A <= B (got {text!r})")
    if hi - lo + 1 > MAX_STORMS:
        raise InvalidInputError(f"--storm-seeds: at most {MAX_STORMS} storms (got {hi - lo + 1})")
    return list(range(lo, hi + 1))


def _flights(agent: Any, env: UAVNavEnv, pts: np.ndarray, replan_every: int) -> dict[str, Any]:
    return evaluate(agent, env, pts, reference_flights(env, pts, replan_every))[0]


def evaluate_storms(run_dir: Path, seeds: list[int], **kw: Any) -> tuple[dict[str, Any], Any]:
    """[`evaluate_worlds()`][rainuav.rl.storm_eval.evaluate_worlds] through storms.

    Args:
        run_dir: The run's folder (its scenario must be the storm's).
        seeds: The storms.
        **kw: The other arguments of `evaluate_worlds()`.

    Returns:
        As `evaluate_worlds()`.
    """
    return evaluate_worlds(run_dir, [{"storm_seed": k} for k in seeds], storms=True, **kw)


def evaluate_worlds(
    run_dir: Path,
    worlds: list[dict[str, Any]],
    *,
    starts: int = 20,
    seed: int | None = None,
    random_goals: bool = False,
    device: str = "cpu",
    progress: bool = True,
    storms: bool = False,
    online: bool = False,
) -> tuple[dict[str, Any], Any]:
    """Flies the network a run reports in each of several worlds, from the same fixed starts.

    Args:
        run_dir: The run's folder.
        worlds: The changes of the run's spec for each world, e.g. `{"storm_seed": K}` or
            `{"scenario": "uma", "rain_rate_mm_h": 0.0}`.
        starts: The fixed starts a world.
        seed: Their seed; None: the run's `eval_seed`.
        random_goals: Each start to its own destination.
        device: "cpu", "cuda" or "auto".
        progress: A line a world.
        storms: The worlds are storms (the run must be the storm's; their maps are not cached).
        online: Fly the last online network in place of the one the run reports.

    Returns:
        `({"mean": ..., "worlds": [...]}, (env, flights) of the first world)`: the rows with their
        changes, and what the figures draw.

    Raises:
        InvalidInputError: A folder that is not a run's, or storms for a run not trained on them.
    """
    check_integer("starts", starts, 1, 10_000)
    run = Path(run_dir)
    for name in ("config.toml", "checkpoint.pt"):
        if not (run / name).exists():
            raise InvalidInputError(f"{run}: missing {name}; is this a rainuav.train output?")
    cfg = load_config(run / "config.toml")
    check_config(cfg)
    if storms and cfg.scenario != "storm":
        raise InvalidInputError(f"--storm-seeds flies storms: {run} was trained on {cfg.scenario}")
    state = checkpoint.load(run / "checkpoint.pt", ("agent", "returns", "train_seconds"))
    base = dataclasses.replace(spec_of(cfg), storm_pool=0, random_goal=False)
    rows, agent, first = [], None, None
    it: Any = worlds
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(worlds, desc="worlds", unit="world")
    for changes in it:
        if "scenario" in changes:  # another preset comes in its own weather unless given
            changes = {"scenario_file": "", "rain_rate_mm_h": None, **changes}
        world = build_world(dataclasses.replace(base, **changes), cache=not storms)
        env = world.env()
        if agent is None:
            agent, _, _ = load_agent(run / "checkpoint.pt", state, cfg, env, device, online)
        rng = np.random.default_rng(cfg.eval_seed if seed is None else seed)
        if not random_goals:
            pts = eval_starts(env, starts, cfg.eval_seed if seed is None else seed)
            m = _flights(agent, env, pts, cfg.replan_every)
            if first is None:
                from rainuav.rl.collect import greedy_rollouts

                first = (env, greedy_rollouts(agent, env, pts[:6]))
        else:
            per = []
            for _ in range(starts):
                start, goal = random_flight(env, rng)
                task = dataclasses.replace(world.task, goal_m=(float(goal[0]), float(goal[1])))
                e = dataclasses.replace(world, task=task).env()
                per.append(_flights(agent, e, start[None], cfg.replan_every))
            m = _mean(per, worst=True)
        m.update(changes)
        rows.append(m)
    summary = _mean(rows, worst=True)
    summary.update(
        worlds=len(rows), starts_per_world=starts, random_goals=random_goals, online=online
    )
    summary["held_out"] = storms and all(r["storm_seed"] >= EVAL_SEEDS_FROM for r in rows)
    return {"mean": summary, "worlds": rows}, first


def _mean(rows: list[dict[str, Any]], worst: bool) -> dict[str, Any]:
    """The mean of each [`SUMMARY_KEYS`][rainuav.rl.storm_eval.SUMMARY_KEYS] figure over ``rows``
    (None values left out; ``worst_excess_cost`` the largest)."""
    out: dict[str, Any] = {}
    for key in SUMMARY_KEYS:
        if not any(key in r for r in rows):
            continue  # a figure of the other kind of task (levels or one level)
        vals = [r[key] for r in rows if r.get(key) is not None]
        if key.startswith("worst_") and worst:
            out[key] = max(vals) if vals else None
        else:
            out[key] = float(np.mean(vals)) if vals else None
    return out
