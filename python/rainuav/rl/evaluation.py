"""Measuring a policy: the network's greedy flights from fixed starts against the exact planner and
the baselines ([`rainuav.nav.references`][rainuav.nav.references]: the straight line; where the
weather moves, the plan of the weather at take-off and re-planning; among levels, the plans of one
altitude), by success and excess cost ([`evaluate()`][rainuav.rl.evaluation.evaluate]), the run's
evaluation ([`evaluate_run_policy()`][rainuav.rl.evaluation.evaluate_run_policy]) and the greedy
checks on held-out validation starts during training
([`Validation`][rainuav.rl.evaluation.Validation])."""

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
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import field_digest
from rainuav.nav.references import (
    eval_starts,
    flights,
    reference_flights,
    relative_gap,
    summarise,
)
from rainuav.radio.outputs.maps import RadioMap
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
from rainuav.rl.resume import RESUME_MAY_DIFFER, config_diff
from rainuav.rl.setup import make_agent, pick_device
from rainuav.world import World, load_world, task_of, world_from

__all__ = [
    "Validation",
    "check_map_digest",
    "eval_starts",
    "evaluate",
    "evaluate_run_policy",
    "evaluate_saved_run",
    "flights",
    "reference_flights",
    "relative_gap",
    "summarise",
]


def _policy_flights(
    agent: Agent, env: UAVNavEnv, starts: np.ndarray, shield: bool
) -> tuple[dict[str, np.ndarray], list]:
    rolls = greedy_rollouts(agent, env, starts, shield=shield)
    f = flights(env, *([r[k] for r in rolls] for k in ("return", "reached", "path", "levels",
                                                       "ticks")))  # fmt: skip
    return f, rolls


def evaluate(
    agent: Agent,
    env: UAVNavEnv,
    starts: np.ndarray,
    references: dict[str, dict[str, np.ndarray]] | None = None,
) -> tuple[dict[str, Any], list]:
    """The greedy network alone from every start, against the exact planner, beside the baselines.

    The baselines are the straight line (`straight_line_*`; `frozen_plan_*` and `replan_*` where the
    weather moves) and the optimum (`optimal_*`). With the agent's shield on, the shielded flights
    are reported beside them as `shielded_*` (the headline stays the network's own).

    Args:
        agent: The agent flown.
        env: The environment.
        starts: The fixed starts (N, 2), m.
        references: The exact planner's and the baselines' flights from these starts, kept by the
            caller to reuse between calls on the same world and task; None: computed here.

    Returns:
        `(metrics, flights)`: the figures by name, and the network's flights.
    """
    refs = references or reference_flights(env, starts)
    opt = refs["optimal"]
    f, rolls = _policy_flights(agent, env, starts, shield=False)
    terms = env.terms()
    metrics: dict[str, Any] = {"signal": terms.signal, "min_db": terms.min_db, **summarise(f, opt)}
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
    if terms.altitudes_m is not None:  # the heights the network flies at
        alts = np.asarray(terms.altitudes_m)
        metrics["altitudes_m"] = alts.tolist()
        for name, levels in (("", [r["levels"] for r in rolls]),
                             ("optimal_", refs["optimal"].get("levels", []))):  # fmt: skip
            if levels:
                flown = np.concatenate([alts[lv[1:]] for lv in levels])
                metrics[f"{name}mean_altitude_m"] = float(np.mean(flown))
        changes = [np.count_nonzero(np.diff(r["levels"])) for r in rolls]
        metrics["vertical_moves"] = float(np.mean(changes))  # climbs and descents a flight
    metrics["eval_starts"] = len(starts)
    return metrics, rolls


@dataclass
class Validation:
    """Greedy checks during training: every ``validate_every`` finished episodes the network
    alone flies from held-out validation starts (never the evaluation starts), and the history
    of (episodes, success, mean excess cost over the optimum) and the online weights with the
    best score are kept (highest success, then lowest mean excess cost: ``score``). With
    ``keep_best`` those weights are the run's result (early stopping; when that pays:
    ``docs/record/learning.md``)."""

    starts: np.ndarray
    optimum: dict[str, np.ndarray]
    best_gap: float = math.inf
    """The best score so far ([`score()`][rainuav.rl.evaluation.Validation.score]; lower is
    better)."""
    best_at: int = 0
    best_online: dict[str, torch.Tensor] | None = None
    history: list[tuple[int, float, float]] = field(default_factory=list)

    @staticmethod
    def score(success: float, excess: float | None) -> float:
        """A check's score: lower is better, a missed flight weighing as much as 100% excess cost.

        Args:
            success: The share of flights that arrived.
            excess: Their mean excess cost over the optimum.

        Returns:
            The score.
        """
        return (1.0 - success) + (1.0 if excess is None else excess)

    def check(self, agent: Agent, env: UAVNavEnv, finished: int) -> tuple[float, float]:
        """Flies the network alone from the validation starts.

        Args:
            agent: The agent.
            env: The environment.
            finished: The episodes finished (the check's place in the log).

        Returns:
            `(success, mean excess cost)`; the excess 1 where no flight arrived.
        """
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
        """What a checkpoint keeps of the checks: their history and the best network so far.

        Returns:
            Tensors and plain data.
        """
        return {
            "best_gap": self.best_gap,
            "best_at": self.best_at,
            "best_online": self.best_online,
            "history": list(self.history),
        }

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restores what [`state_dict()`][rainuav.rl.evaluation.Validation.state_dict] gave.

        Args:
            d: The saved state.
        """
        self.best_gap, self.best_at = d["best_gap"], d["best_at"]
        self.best_online, self.history = d["best_online"], list(d["history"])


def evaluate_run_policy(
    cfg: TrainConfig, agent: Agent, env: UAVNavEnv, checks: Validation
) -> tuple[dict[str, Any], list]:
    """Evaluates the run's policy from the evaluation starts, and leaves it in the agent.

    The agent comes with its last online weights. The reported network is their mean where the run
    averaged them (`average_from` < 1; the last online network is then flown first and reported
    beside the mean as `online_*`), else the last online network; with `keep_best`, the best on
    validation (the reported network's numbers are then added as `final_*`).

    Args:
        cfg: The run's configuration.
        agent: The agent, with its last online weights.
        env: The environment.
        checks: The run's validation checks.

    Returns:
        `(metrics, flights)`, as [`evaluate()`][rainuav.rl.evaluation.evaluate] gives them.
    """
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
    """The agent of a run's checkpoint, holding the network the run reports.

    Args:
        path: Where the checkpoint was read (for the messages).
        state: The checkpoint.
        cfg: The run's configuration.
        env: The environment it flies.
        device: "cpu", "cuda" or "auto".
        online: Hold the last online network instead.

    Returns:
        `(agent, episodes, training seconds)`.

    Raises:
        InvalidInputError: A checkpoint that does not fit the network of `cfg` and `env`.
    """
    agent = make_agent(cfg, env, pick_device(device))
    checks = Validation(np.zeros((0, 2)), {})
    try:
        agent.load_state_dict(state["agent"], to_fly=True)
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


def check_map_digest(state: dict[str, Any], field: Any, run: Path) -> None:
    """Refuses a run folder whose map is not the one its checkpoint was trained on.

    A map swapped in, or crafted ([`field_digest()`][rainuav.nav.field.field_digest]); a checkpoint
    that records none (an earlier release) passes.

    Args:
        state: The checkpoint.
        field: The field the folder's map gives.
        run: The run's folder.

    Raises:
        InvalidInputError: The map's digest differs from the checkpoint's.
    """
    want = state.get("map_digest")
    if isinstance(want, str) and want != field_digest(field):
        raise InvalidInputError(
            f"{run / 'radiomap.npz'}: refused (not the map this run was trained on: its digest "
            "differs from the checkpoint's; put the run's own map back, or fly another map with "
            "evaluate --scenario)"
        )


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
    """Flies a saved training run's policy: the network the run reports, in its own world or
    another.

    The network is the final one, the weight average with `average_from`, or with `keep_best` the
    best on validation. Nothing is written.

    Args:
        run_dir: The run's folder.
        device: "cpu", "cuda" or "auto".
        world: Another world ([`build_world()`][rainuav.world.build_world]: another scenario, rain
            rate or storm), or a function of the run's configuration that builds it, called once the
            run's files are read; None: the run's own.
        radio_map: Another map, with the run's task.
        starts: The number of fixed starts (default: the run's evaluation starts).
        seed: Their seed (default: the run's).
        shield: Report shielded flights beside the network's own.
        references: A dict the caller keeps to reuse the exact planner's flights between calls on
            the same world and task.
        online: Fly the last online network instead of the one the run reports (`metrics["network"]`
            says which flew).

    Returns:
        `(metrics, flights, env)`.

    Raises:
        InvalidInputError: A folder that is not a run's, files that do not belong together (a
            `config.toml` or map that is not the run's), both `world` and `radio_map`, or a run over
            the storm distribution without a world to fly.
    """
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
    if isinstance(state.get("config"), dict):  # the run's own record of its configuration
        diff = config_diff(state["config"], cfg, ignore=RESUME_MAY_DIFFER)
        if diff:
            raise InvalidInputError(
                f"{run / 'config.toml'}: refused (differs from the configuration {path.name} "
                f"was trained with, in {len(diff)} field(s): {'; '.join(diff[:3])}"
                f"{'; ...' if len(diff) > 3 else ''}: edited, emptied or from another run)"
            )
    if world is not None and radio_map is not None:
        raise InvalidInputError("give world or radio_map, not both")
    if callable(world):
        world = world(cfg)
    own = False
    try:
        if radio_map is not None:
            world = world_from(radio_map, task_of(cfg))
        elif world is None:
            if cfg.storm_pool:
                raise InvalidInputError(
                    f"{run}: a run over the storm distribution has no world of its own; "
                    "fly it with --storm-seed K or --storm-seeds A-B"
                )
            own = True
            world = load_world(run, cfg)
        if world is not None:
            env = world.env()
    except InvalidInputError as err:
        if own and str(run) in str(err):  # the run's own map file, named already
            raise
        if own:  # the run's own map file: name it (a damaged map, or one of another place)
            raise InvalidInputError(f"{run / 'radiomap.npz'}: refused: {err}") from err
        where = run / "config.toml"
        raise InvalidInputError(f"{where}: does not fit the world flown: {err}") from err
    if world is None:
        raise InvalidInputError(f"{run}: missing radiomap.npz; is this a rainuav.train output?")
    if own:
        check_map_digest(state, world.field, run)
    agent, episodes, seconds = load_agent(path, state, cfg, env, device, online)
    agent.cfg.shield = shield
    n = cfg.eval_starts if starts is None else starts
    pts = eval_starts(env, n, cfg.eval_seed if seed is None else seed)
    refs = None
    if references is not None:
        key = (id(world.source), repr(world.task), pts.tobytes())
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
        "rain_rate_mm_h": cfg.rain_rate_mm_h,
        **({"storm_seed": cfg.storm_seed} if cfg.scenario == "storm" else {}),
        **({"altitudes_m": cfg.altitudes_m} if cfg.altitudes_m else {}),
    }
    metrics["network"] = "last online" if online else "reported"
    metrics["episodes"] = episodes
    metrics["training_seconds"] = seconds
    return metrics, rolls, env
