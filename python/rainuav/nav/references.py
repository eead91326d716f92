"""The yardsticks a policy is measured against: fixed starts
([`eval_starts()`][rainuav.nav.references.eval_starts]), the exact planner's flights and the
baselines' ([`reference_flights()`][rainuav.nav.references.reference_flights]), what a set of
flights comes to ([`flights()`][rainuav.nav.references.flights]) and how it compares with the
optimum ([`summarise()`][rainuav.nav.references.summarise]).

On one level: the exact optimum, the straight line, and where the weather moves the plan of the
weather at take-off and re-planning ([`rainuav.nav.baselines`][rainuav.nav.baselines]). Among levels
([`rainuav.nav.levels`][rainuav.nav.levels]): the exact optimum among
levels from the level a flight starts at, and the baselines of one altitude (``fixed_altitude``: the
exact plan held at the level nearest [`PAPER_ALTITUDE_M`][rainuav.nav.references.PAPER_ALTITUDE_M],
the paper's; ``best_single_altitude``: the exact plan at each level, the best chosen with hindsight
per flight; ``straight_line``: the straight line at the fixed level), each flown from the start at
its own level (the take-off climb is the autopilot's, as in ``fly``)."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.nav import baselines, planner
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.task import flight_cost

__all__ = [
    "PAPER_ALTITUDE_M",
    "PLAN_CHUNK",
    "eval_starts",
    "flights",
    "level_reference_flights",
    "optimal_flights",
    "reference_flights",
    "relative_gap",
    "summarise",
]

PAPER_ALTITUDE_M = 100.0
"""The paper's one flight altitude, m: the fixed-altitude baseline among levels flies the
level nearest it."""

PLAN_CHUNK = 1000
"""Starts planned per call of the exact planner: evaluations over more show a progress bar."""


def eval_starts(env: UAVNavEnv, n: int, seed: int) -> np.ndarray:
    """Fixed starts drawn uniformly in the area, farther than the tolerance from the destination.

    Args:
        env: The environment.
        n: How many.
        seed: Their seed.

    Returns:
        (n, 2) starts, m.
    """
    rng = np.random.default_rng(seed)
    return np.array([env.sample_start(rng) for _ in range(n)], dtype=np.float64).reshape(-1, 2)


def relative_gap(optimum: np.ndarray, returns: np.ndarray) -> np.ndarray:
    """Per start, the share of the exact optimum's return the policy gave up.

    A secondary figure: the arrival reward in both returns makes it look about 4 times smaller than
    the extra cost it stands for ([physics reference, section 6][6-the-navigation-task]).

    Args:
        optimum: The optimum's returns (N,).
        returns: The policy's returns (N,).

    Returns:
        (N,) shares.
    """
    return (optimum - returns) / np.maximum(np.abs(optimum), 1e-9)


def _arrived(env: UAVNavEnv, path: np.ndarray) -> bool:
    """Whether a planner's path ends at the destination (inside the area)."""
    x0, x1, y0, y1 = env.field.extent
    p, g = path[-1], np.asarray(env.cfg.goal_m)
    inside = x0 <= p[0] <= x1 and y0 <= p[1] <= y1
    return bool(inside and np.hypot(*(p - g)) <= env.cfg.tol_m and len(path) > 1)


def flights(
    env: UAVNavEnv,
    returns: npt.ArrayLike,
    arrived: npt.ArrayLike,
    paths: list,
    levels: list | None = None,
    ticks: list | None = None,
) -> dict[str, Any]:
    """Per flight: its return, arrival, cost, moves and the signal along its path.

    The cost is [`flight_cost()`][rainuav.nav.task.flight_cost]; the signal along the path (every
    position after the start) is summed, and its moves below `min_db` counted.

    Args:
        env: The environment flown.
        returns: The flights' returns (N,).
        arrived: Whether each arrived (N,).
        paths: Each flight's positions.
        levels: Among levels, each point's level.
        ticks: Among levels, each point's clock.

    Returns:
        `return`, `arrived`, `cost`, `steps` (moves), `signal_sum` and `outage_sum` (N,) each,
        and the `paths` themselves (for figures).

    Raises:
        InvalidInputError: Flights among levels without their levels and ticks.
    """
    time_s = env.stepper.time_s  # the instant of each move, for a signal that changes
    if env.altitudes_m is not None:
        if levels is None or ticks is None:
            raise InvalidInputError("flights among levels need their levels and ticks")
        signal = [env.field(p[1:, 0], p[1:, 1], time_s(t[1:]), level=lv[1:])
                  for p, lv, t in zip(paths, levels, ticks, strict=True)]  # fmt: skip
    else:
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
    """The figures of a set of flights against the optimum's from the same starts.

    Args:
        f: The flights ([`flights()`][rainuav.nav.references.flights]).
        optimum: The optimum's flights.

    Returns:
        The success rate, the excess cost `(C - C*) / C*` over the flights that arrived where the
        optimum did too (None where none did), the return gap, the flight time in moves, and the
        mean signal and outage share over every position flown.
    """
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
    env: UAVNavEnv,
    starts: np.ndarray,
    replan_every: int = baselines.DEFAULT_REPLAN_EVERY,
) -> dict[str, dict[str, Any]]:
    """The exact planner's flights (the yardstick) and the baselines', from fixed starts.

    The baselines: the straight line and, where the signal changes in time, the plan of the weather
    at take-off (`frozen_plan`) and re-planning every `replan_every` moves (`replan`), each flown
    through the moving weather. Among levels:
    [`level_reference_flights()`][rainuav.nav.references.level_reference_flights].

    Args:
        env: The environment.
        starts: The starts (N, 2), m.
        replan_every: The moves between two plans of the re-planning baseline.

    Returns:
        Each baseline's flights by name (`optimal`, `straight_line`, ...).
    """
    if env.altitudes_m is not None:
        return level_reference_flights(env, starts)  # type: ignore[arg-type]
    flown = {"straight_line": [planner.straight_line(env, s) for s in starts]}
    if env.field.varies:
        flown["frozen_plan"] = baselines.frozen_plans(env, starts)
        flown["replan"] = baselines.replans(env, starts, replan_every)
    refs = {name: _plans(ps, env) for name, ps in flown.items()}
    return {"optimal": optimal_flights(env, starts), **refs}


def optimal_flights(env: UAVNavEnv, starts: np.ndarray) -> dict[str, Any]:
    """The exact planner's flights alone: the yardstick, for the checks during training.

    Among levels: the plan among levels from the level each flight starts at.

    Args:
        env: The environment.
        starts: The starts (N, 2), m.

    Returns:
        The flights, as [`reference_flights()`][rainuav.nav.references.reference_flights] gives
        `optimal`.
    """
    starts = np.asarray(starts, dtype=np.float64).reshape(-1, 2)
    if env.altitudes_m is not None:
        return _plans(planner.optimal_among_levels(env, starts), env)  # type: ignore[arg-type]
    plans = []
    chunks = range(0, len(starts), PLAN_CHUNK)
    if len(starts) > PLAN_CHUNK:  # a long evaluation shows its progress
        from tqdm.auto import tqdm

        chunks = tqdm(chunks, desc="exact plans", unit="chunk", total=len(chunks))
    for i in chunks:
        plans += planner.optimal_many(env, starts[i : i + PLAN_CHUNK])
    return _plans(plans, env)


def _plans(plans: list, env: UAVNavEnv) -> dict[str, Any]:
    """[`flights()`][rainuav.nav.references.flights] of planned flights (plans, or among levels
    level plans, whose levels are kept for the heights flown)."""
    among = env.altitudes_m is not None
    levels = [p.levels for p in plans] if among else None
    f = flights(
        env,
        [p.return_ for p in plans],
        [_arrived(env, p.path_m) for p in plans],
        [p.path_m for p in plans],
        levels,
        [p.ticks for p in plans] if among else None,
    )
    if among:
        f["levels"] = levels
    return f


def level_reference_flights(env: UAVNavEnv, starts: np.ndarray) -> dict[str, dict[str, Any]]:
    """The exact plan among levels and the baselines of one altitude, from fixed starts.

    `optimal` (the exact plan among levels), `fixed_altitude`, `best_single_altitude` and
    `straight_line` (the module's docstring); a level whose plane cannot hold the task (its
    destination not flyable) flies no flight that arrives.

    Args:
        env: The environment among levels.
        starts: The starts (N, 2), m.

    Returns:
        Each baseline's flights by name.

    Raises:
        InvalidInputError: The destination is not flyable at the fixed altitude.
    """
    starts = np.asarray(starts, dtype=np.float64).reshape(-1, 2)
    refs = {"optimal": optimal_flights(env, starts)}
    per_level = []
    for k in range(env.field.levels):
        try:
            plane = UAVNavEnv(field=env.field.level(k), config=env.cfg)
        except InvalidInputError:
            per_level.append(None)
            continue
        per_level.append((plane, _plans(planner.optimal_many(plane, starts), plane)))
    fixed = int(np.argmin(np.abs(env.field.altitudes_m - PAPER_ALTITUDE_M)))
    if per_level[fixed] is None:
        raise InvalidInputError(
            f"the destination is not flyable at {env.field.altitudes_m[fixed]:g} m, the "
            "fixed-altitude baseline's level"
        )
    plane, refs["fixed_altitude"] = per_level[fixed]
    line = [planner.straight_line(plane, s) for s in starts]
    refs["straight_line"] = _plans(line, plane)
    # Per flight, the level whose plan costs least (of those that arrive; among the levels
    # that hold the task).
    held = [k for k, q in enumerate(per_level) if q is not None]
    flown = [per_level[k][1] for k in held]  # type: ignore[index]
    costs = np.stack([np.where(f["arrived"], f["cost"], np.inf) for f in flown])
    pick = np.argmin(costs, axis=0)
    best: dict[str, Any] = {}
    for key in refs["fixed_altitude"]:
        values = [flown[k][key][j] for j, k in enumerate(pick)]
        best[key] = values if key == "paths" else np.asarray(values)
    best["altitude_m"] = env.field.altitudes_m[np.asarray(held)[pick]]
    refs["best_single_altitude"] = best
    return refs
