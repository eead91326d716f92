"""Measuring a policy: the network's greedy flights from fixed starts against the exact
planner and the baselines (the straight line; where the weather moves, the plan of the weather
at take-off and re-planning: :mod:`rainuav.nav.baselines`), by success and excess cost
(:func:`evaluate`), the
run's evaluation (:func:`evaluate_run_policy`) and the greedy checks on held-out validation
starts during training (:class:`Validation`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from rainuav._checks import check_integer
from rainuav.errors import InvalidInputError
from rainuav.nav import baselines, planner
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.task import flight_cost
from rainuav.radio.radiomap import RadioMap
from rainuav.rl import checkpoint
from rainuav.rl.collect import greedy_rollouts
from rainuav.rl.config import (
    MAX_SEED,
    MAX_STARTS,
    TrainConfig,
    check_config,
    load_config,
)
from rainuav.rl.dqn import Agent
from rainuav.rl.setup import make_agent, pick_device
from rainuav.world import World, load_world, task_of, world_from

__all__ = [
    "Validation",
    "eval_starts",
    "evaluate",
    "evaluate_run_policy",
    "evaluate_saved_run",
    "flights",
    "reference_flights",
    "relative_gap",
    "summarise",
]


PLAN_CHUNK = 1000
"""Starts planned per call of the exact planner: evaluations over more show a progress bar."""


def eval_starts(env: UAVNavEnv, n: int, seed: int) -> np.ndarray:
    """``n`` starts drawn uniformly (farther than the tolerance from the goal) from ``seed``."""
    rng = np.random.default_rng(seed)
    return np.array([env.sample_start(rng) for _ in range(n)], dtype=np.float64).reshape(-1, 2)


def relative_gap(optimum: np.ndarray, returns: np.ndarray) -> np.ndarray:
    """Per start, the share of the exact optimum's return the policy gave up (a secondary
    figure: the arrival reward in both returns makes it look about 4x smaller than the extra
    cost it stands for, PHYSICS.md section 6)."""
    return (optimum - returns) / np.maximum(np.abs(optimum), 1e-9)


def _arrived(env: UAVNavEnv, path: np.ndarray) -> bool:
    """Whether a planner's path ends at the destination (inside the area)."""
    x0, x1, y0, y1 = env.field.extent
    p, g = path[-1], np.asarray(env.cfg.goal_m)
    inside = x0 <= p[0] <= x1 and y0 <= p[1] <= y1
    return bool(inside and np.hypot(*(p - g)) <= env.cfg.tol_m and len(path) > 1)


def flights(env: UAVNavEnv, returns: Any, arrived: Any, paths: list) -> dict[str, Any]:
    """Per flight: ``return``, ``arrived``, ``cost`` (:func:`rainuav.nav.task.flight_cost`),
    ``steps``, the signal along the path (every position after the start): its mean and the
    share of it below ``min_db``, and the ``paths`` themselves (for figures)."""
    time_s = env.stepper.time_s  # the instant of each move, for a signal that changes
    signal = [env.field(p[1:, 0], p[1:, 1], time_s(np.arange(1, len(p)))) for p in paths]
    rets = np.asarray(returns, dtype=np.float64)
    ok = np.asarray(arrived, dtype=bool)
    return {
        "return": rets,
        "arrived": ok,
        "cost": flight_cost(rets, ok, env.cfg),
        "steps": np.array([len(p) - 1 for p in paths], dtype=np.float64),
        "signal_sum": np.array([s.sum() for s in signal]),
        "outage_sum": np.array([np.sum(s < env.cfg.min_db) for s in signal], dtype=np.float64),
        "paths": paths,
    }


def summarise(f: dict[str, np.ndarray], optimum: dict[str, np.ndarray]) -> dict[str, Any]:
    """Success, excess cost ``(C - C*) / C*`` over the flights that arrived where the optimum
    did too (None where none did), return gap, flight time in moves, and the mean signal and
    outage share over every position flown."""
    both = f["arrived"] & optimum["arrived"]
    excess = (f["cost"][both] - optimum["cost"][both]) / optimum["cost"][both]
    gap = relative_gap(optimum["return"], f["return"])
    moves = max(float(f["steps"].sum()), 1.0)
    return {
        "success_rate": float(f["arrived"].mean()),
        "mean_excess_cost": float(excess.mean()) if both.any() else None,
        "median_excess_cost": float(np.median(excess)) if both.any() else None,
        "worst_excess_cost": float(excess.max()) if both.any() else None,
        "mean_cost": float(f["cost"][f["arrived"]].mean()) if f["arrived"].any() else None,
        "mean_steps": float(f["steps"].mean()),
        "mean_signal_db": float(f["signal_sum"].sum() / moves),
        "outage_share": float(f["outage_sum"].sum() / moves),
        "mean_gap_to_optimal": float(gap.mean()),
        "worst_gap_to_optimal": float(gap.max()),
        "mean_return": float(f["return"].mean()),
    }


def reference_flights(
    env: UAVNavEnv, starts: np.ndarray, replan_every: int = baselines.DEFAULT_REPLAN_EVERY
) -> dict[str, dict[str, Any]]:
    """The exact planner's flights (the yardstick) and the baselines': the straight line, and
    where the signal changes in time the plan of the weather at take-off (``frozen_plan``) and
    re-planning every ``replan_every`` moves (``replan``), each flown through the moving
    weather."""
    plans = []
    chunks = range(0, len(starts), PLAN_CHUNK)
    if len(starts) > PLAN_CHUNK:  # a long evaluation shows its progress
        from tqdm.auto import tqdm

        chunks = tqdm(chunks, desc="exact plans", unit="chunk", total=len(chunks))
    for i in chunks:
        plans += planner.optimal_many(env, starts[i : i + PLAN_CHUNK])
    flown = {"optimal": plans, "straight_line": [planner.straight_line(env, s) for s in starts]}
    if env.field.varies:
        flown["frozen_plan"] = baselines.frozen_plans(env, starts)
        flown["replan"] = baselines.replans(env, starts, replan_every)
    return {
        name: flights(
            env,
            [p.return_ for p in ps],
            [_arrived(env, p.path_m) for p in ps],
            [p.path_m for p in ps],
        )
        for name, ps in flown.items()
    }


def _policy_flights(
    agent: Agent, env: UAVNavEnv, starts: np.ndarray, shield: bool
) -> tuple[dict[str, np.ndarray], list]:
    rolls = greedy_rollouts(agent, env, starts, shield=shield)
    f = flights(
        env, [r["return"] for r in rolls], [r["reached"] for r in rolls], [r["path"] for r in rolls]
    )
    return f, rolls


def evaluate(
    agent: Agent,
    env: UAVNavEnv,
    starts: np.ndarray,
    references: dict[str, dict[str, np.ndarray]] | None = None,
) -> tuple[dict[str, Any], list]:
    """The greedy network alone from every start, against the exact planner, beside the
    baselines (``straight_line_*``; ``frozen_plan_*`` and ``replan_*`` where the weather
    moves) and the optimum (``optimal_*``). With the
    agent's shield on, the shielded flights are reported beside them as ``shielded_*`` (the
    headline stays the network's own). Returns the metrics and the network's flights."""
    refs = references or reference_flights(env, starts)
    opt = refs["optimal"]
    f, rolls = _policy_flights(agent, env, starts, shield=False)
    metrics: dict[str, Any] = {
        "signal": env.cfg.signal,
        "min_db": env.cfg.min_db,
        **summarise(f, opt),
    }
    for name, ref in refs.items():
        for key, value in summarise(ref, opt).items():
            if name != "optimal" or key not in ("mean_excess_cost", "worst_excess_cost"):
                metrics[f"{name}_{key}"] = value
    if agent.cfg.shield:
        fs, rolls_s = _policy_flights(agent, env, starts, shield=True)
        s = summarise(fs, opt)
        keys = ("success_rate", "mean_excess_cost", "worst_excess_cost")
        metrics.update({f"shielded_{k}": s[k] for k in keys})
        metrics["shielded_flights"] = float(np.mean([r["overridden"] > 0 for r in rolls_s]))
    metrics["eval_starts"] = len(starts)
    return metrics, rolls


@dataclass
class Validation:
    """Greedy checks during training: every ``validate_every`` finished episodes the network
    alone flies from held-out validation starts (never the evaluation starts), and the history
    of (episodes, success, mean excess cost over the optimum) and the online weights with the
    best score are kept (highest success, then lowest mean excess cost: ``score``). With
    ``keep_best`` those weights are the run's result (early stopping; when that pays:
    ``docs/learner.md``)."""

    starts: np.ndarray
    optimum: dict[str, np.ndarray]
    best_gap: float = math.inf
    """The best score so far (:meth:`score`; lower is better)."""
    best_at: int = 0
    best_online: dict[str, torch.Tensor] | None = None
    history: list[tuple[int, float, float]] = field(default_factory=list)

    @staticmethod
    def score(success: float, excess: float | None) -> float:
        """Lower is better: each missed flight weighs as much as 100% excess cost."""
        return (1.0 - success) + (1.0 if excess is None else excess)

    def check(self, agent: Agent, env: UAVNavEnv, finished: int) -> tuple[float, float]:
        """Flies the network alone from the validation starts; returns (success, mean excess
        cost; 1 where no flight arrived)."""
        f, _ = _policy_flights(agent, env, self.starts, shield=False)
        m = summarise(f, self.optimum)
        success = m["success_rate"]
        excess = 1.0 if m["mean_excess_cost"] is None else m["mean_excess_cost"]
        self.history.append((finished, success, excess))
        score = self.score(success, excess)
        if score < self.best_gap:
            self.best_gap, self.best_at = score, finished
            self.best_online = {
                k: v.detach().cpu().clone() for k, v in agent.online.state_dict().items()
            }
        return success, excess

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
    """Evaluates the run's policy from the evaluation starts and leaves it in ``agent``.

    ``agent`` comes with its last online weights. The reported network is their mean where the
    run averaged them (``average_from`` < 1; the last online network is then flown first and
    reported beside the mean as ``online_*``), else the last online network; with
    ``keep_best``, the best on validation (the reported network's numbers are then added as
    ``final_*``)."""
    starts = eval_starts(env, cfg.eval_starts, cfg.eval_seed)
    refs = reference_flights(env, starts, cfg.replan_every)
    keys = ("success_rate", "mean_excess_cost", "worst_excess_cost", "mean_return")
    online: dict[str, Any] = {}
    if agent.average is not None:
        own, _ = evaluate(agent, env, starts, refs)
        online = {f"online_{k}": own[k] for k in keys}
        agent.online.load_state_dict(agent.reported_weights())
    metrics, rolls = evaluate(agent, env, starts, refs)
    metrics["selected_at_episode"] = cfg.dqn.episodes
    if cfg.keep_best and checks.best_online is not None and checks.best_at != cfg.dqn.episodes:
        final = metrics
        agent.online.load_state_dict(checks.best_online)
        metrics, rolls = evaluate(agent, env, starts, refs)
        metrics["selected_at_episode"] = checks.best_at
        metrics.update({f"final_{k}": final[k] for k in keys})
    metrics.update(online)
    return metrics, rolls


def load_agent(
    path: Path, state: dict[str, Any], cfg: TrainConfig, env: UAVNavEnv, device: str, online: bool
) -> tuple[Agent, int, float]:
    """The agent of a run's checkpoint ``state`` (read from ``path``) for ``env``, holding the
    network the run reports (or with ``online`` its last online one); with its episodes and
    training seconds. A checkpoint that does not fit is refused in one line."""
    agent = make_agent(cfg, env, pick_device(device))
    checks = Validation(np.zeros((0, 2)), {})
    try:
        agent.load_state_dict(state["agent"])
        if "validation" in state:
            checks.load_state_dict(state["validation"])
        if not online:  # else: load_state_dict left the last online weights in agent.online
            best = cfg.keep_best and checks.best_online is not None
            if best and checks.best_at != cfg.dqn.episodes:
                agent.online.load_state_dict(checks.best_online)
            else:
                agent.online.load_state_dict(agent.reported_weights())  # the mean, if averaged
        episodes, seconds = len(state["returns"]), float(state["train_seconds"])
    except (KeyError, TypeError, ValueError, RuntimeError, AttributeError) as err:
        why = str(err).splitlines()[0] if str(err) else repr(err)
        raise InvalidInputError(
            f"checkpoint {path}: refused (does not fit the network its config.toml describes; "
            f"a run from an incompatible version?): {why}"
        ) from err
    return agent, episodes, seconds


def evaluate_saved_run(
    run_dir: Path,
    device: str = "cpu",
    *,
    world: World | Callable[[TrainConfig], World] | None = None,
    radio_map: RadioMap | None = None,
    starts: int | None = None,
    seed: int | None = None,
    shield: bool = False,
    references: dict[Any, Any] | None = None,
    online: bool = False,
) -> tuple[dict[str, Any], list, Any]:
    """Flies a saved training run's policy (the network the run reports: the final one, the
    weight average with ``average_from``, or with ``keep_best`` the best on validation). In
    the run's own world by default; ``world`` (built by the caller, e.g. another scenario,
    rain rate or storm: :func:`rainuav.world.build_world`; or a function of the run's
    configuration that builds it, called once the run's files are read) or ``radio_map``
    (another map, with the run's task) fly it elsewhere. ``starts``/``seed``: the number and
    seed of the fixed starts (default: the run's evaluation starts); ``shield``: report
    shielded flights beside the network's own; ``online``: fly the last online network
    instead of the one the run reports (they differ with ``average_from`` < 1 or
    ``keep_best``; ``metrics["network"]`` says which flew). ``references``: a dict the caller
    keeps to reuse the exact planner's flights between calls on the same world and task.
    Returns the metrics, the flights and the environment; writes nothing."""
    run = Path(run_dir)
    if starts is not None:
        check_integer("starts", starts, 1, MAX_STARTS)
    if seed is not None:
        check_integer("seed", seed, 0, MAX_SEED)
    for name in ("config.toml", "checkpoint.pt"):
        if not (run / name).exists():
            raise InvalidInputError(f"{run}: missing {name}; is this a rainuav.train output?")
    cfg = load_config(run / "config.toml")
    check_config(cfg)
    # Read (as data, never code) before any map is read: a bad file is refused at once.
    path = run / "checkpoint.pt"
    state = checkpoint.load(path, ("agent", "returns", "train_seconds"))
    if world is not None and radio_map is not None:
        raise InvalidInputError("give world or radio_map, not both")
    if callable(world):
        world = world(cfg)
    try:
        if radio_map is not None:
            world = world_from(radio_map, task_of(cfg))
        elif world is None:
            if cfg.storm_pool:
                raise InvalidInputError(
                    f"{run}: a run over the storm distribution has no world of its own; "
                    "fly it with --storm-seed K or --storm-seeds A-B"
                )
            world = load_world(run, cfg)
            if world is None:
                raise InvalidInputError(
                    f"{run}: missing radiomap.npz; is this a rainuav.train output?"
                )
        env = world.env()
    except InvalidInputError as err:
        where = run / "config.toml"
        raise InvalidInputError(f"{where}: does not fit the world flown: {err}") from err
    agent, episodes, seconds = load_agent(path, state, cfg, env, device, online)
    agent.cfg.shield = shield
    n = cfg.eval_starts if starts is None else starts
    pts = eval_starts(env, n, cfg.eval_seed if seed is None else seed)
    refs = None
    if references is not None:
        key = (id(world.source), repr(env.cfg), pts.tobytes())
        if key not in references:
            references[key] = reference_flights(env, pts, cfg.replan_every)
        refs = references[key]
    else:
        refs = reference_flights(env, pts, cfg.replan_every)
    metrics, rolls = evaluate(agent, env, pts, refs)
    scn = world.source.scenario
    metrics["scenario"] = scn.name
    metrics["rain_rate_mm_h"] = scn.medium.rain_rate_mm_h
    metrics["trained_on"] = {
        "scenario": cfg.scenario,
        "rain_rate": cfg.rain_rate,
        **({"storm_seed": cfg.storm_seed} if cfg.scenario == "storm" else {}),
    }
    metrics["network"] = "last online" if online else "reported"
    metrics["episodes"] = episodes
    metrics["training_seconds"] = seconds
    return metrics, rolls, env
