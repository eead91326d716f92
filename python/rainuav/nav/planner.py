"""Exact and baseline planners for [`rainuav.nav.env.UAVNavEnv`][rainuav.nav.env.UAVNavEnv].

The moves are deterministic on the start's lattice, so the exact finite-horizon optimum of the
undiscounted return is a dynamic programme (in Rust; many starts run in parallel). It is the
yardstick for learned policies. Where the signal changes in time (a
[`SignalField.series`][rainuav.nav.fieldmakers.FieldMakers.series]) the programme's rewards depend
on the step: it is then the exact optimum on the space-time lattice, the storm's motion known.
One programme in Rust (``rainuav_core::planning::planlevels``) solves every case: the plane in
space, in space and time, and among flight levels (the plane is its case of one level). The
baselines a user would try instead (the plan of the weather at take-off, re-planning on the weather
of the moment) are in [`rainuav.nav.baselines`][rainuav.nav.baselines]."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import _core
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.levelfield import CLIMB_M_S, DESCEND_M_S, level_durations
from rainuav.nav.task import NavConfig

__all__ = [
    "LevelPlan",
    "Plan",
    "level_durations",
    "optimal",
    "optimal_among_levels",
    "optimal_levels",
    "optimal_many",
    "rust_task",
    "straight_line",
]


@dataclass(frozen=True)
class Plan:
    """A trajectory and its undiscounted return."""

    return_: float
    """Sum of the rewards."""
    path_m: npt.NDArray[np.float64]
    """(T + 1, 2) positions, from the start."""
    actions: npt.NDArray[np.int64]
    """(T,) actions."""


def rust_task(
    cfg: NavConfig,
    extent_m: Any,
    climb: list[int] | None = None,
    descend: list[int] | None = None,
) -> dict[str, Any]:
    """The task the Rust planner solves, built from a task's configuration once.

    Args:
        cfg: The task, ``min_db`` resolved.
        extent_m: ``(x_min, x_max, y_min, y_max)`` of the signal, m.
        climb: Ticks of the climb between each two neighbouring levels (none: one level).
        descend: Ticks of the descent between each two neighbouring levels.

    Returns:
        The items ``rainuav._core.plan_optimal_levels`` reads as its ``task``: the geometry,
        rewards and horizon, the clock (every flight taking off at 0, one tick a move of
        ``cfg.move_s``) and the climbs and descents.
    """
    return {
        "extent_m": tuple(float(v) for v in extent_m),
        "goal_m": (float(cfg.goal_m[0]), float(cfg.goal_m[1])),
        "step_m": float(cfg.step_m),
        "tol_m": float(cfg.tol_m),
        "max_steps": int(cfg.max_steps),
        "mu": float(cfg.mu),
        "reward": cfg.reward,
        "sir_min_db": float(cfg.min_db),  # the Rust planner's name for the threshold
        "goal_reward": float(cfg.goal_reward),
        "out_of_bounds_penalty": float(cfg.out_of_bounds_penalty),
        "t0_s": 0.0,
        "dt_s": float(cfg.move_s),
        "climb": list(climb or []),
        "descend": list(descend or []),
    }


def _as_env(env: UAVNavEnv) -> UAVNavEnv:
    if not isinstance(env, UAVNavEnv):
        raise InvalidInputError(f"env must be a rainuav.nav.UAVNavEnv (got {type(env).__name__})")
    if env.level_axis:
        raise InvalidInputError("env flies among levels: plan with optimal_among_levels")
    return env


def optimal_many(env: UAVNavEnv, starts_m: npt.ArrayLike) -> list[Plan]:
    """Exact optimal plans from many starts, computed in parallel.

    In space and time where the env's signal changes in time (every flight taking off at 0).

    Args:
        env: The environment on one level.
        starts_m: The starts, (N, 2), m.

    Returns:
        One [`Plan`][rainuav.nav.planner.Plan] a start, in their order.

    Raises:
        InvalidInputError: ``env`` is not a [`UAVNavEnv`][rainuav.nav.UAVNavEnv] on one level.
    """
    env = _as_env(env)
    return plan_on(env.field, env.cfg, starts_m)


def plan_on(field: Any, cfg: NavConfig, starts_m: npt.ArrayLike) -> list[Plan]:
    """Exact optimal plans of a task on a field, without an environment.

    Args:
        field: A [`SignalField`][rainuav.nav.field.SignalField]: a map or a series in time.
        cfg: The task, ``min_db`` resolved. With ``cfg.reward == "chance"`` the plan reads the
            field's ``outage_p`` (a move costs ``1 + mu P`` where it ends).
        starts_m: The starts, (N, 2), m.

    Returns:
        One [`Plan`][rainuav.nav.planner.Plan] a start.

    Raises:
        InvalidInputError: A reward or a field the planner cannot plan on (a bank of worlds,
            several levels, ``"chance"`` without ``outage_p``).
    """
    starts = np.ascontiguousarray(np.asarray(starts_m, dtype=np.float64).reshape(-1, 2))
    # The plane is the programme among levels with one level: (K, 1, H, W) slices (one slice
    # for a signal that does not change), every start on level 0, no climbs.
    mask = getattr(field, "not_flyable", None)
    blocked = None if mask is None else np.ascontiguousarray(np.asarray(mask, dtype=np.uint8)[None])
    if cfg.reward == "chance":
        if getattr(field, "outage_p", None) is None:
            raise InvalidInputError("reward 'chance' plans on one map with outage_p")
        slices, times = field.outage_p[None, None], np.zeros(1)
    elif getattr(field, "banked", False):
        raise InvalidInputError("the planner plans on one world: take a bank's member(world)")
    else:  # a map is a series of one slice at t = 0, on its one level
        slices, times = field.values[0], field.t_s
    raw = _core.plan_optimal_levels(
        np.ascontiguousarray(slices, dtype=np.float64), np.ascontiguousarray(times),
        np.ascontiguousarray(np.column_stack([starts, np.zeros(len(starts))])),
        rust_task(cfg, field.extent), blocked,
    )  # fmt: skip
    return [
        Plan(float(r), np.ascontiguousarray(np.asarray(path)[:, :2]), np.asarray(a, dtype=np.int64))
        for r, a, path, _ in raw
    ]


def optimal(env: UAVNavEnv, start_m: npt.ArrayLike) -> Plan:
    """The exact optimal plan from one start, by dynamic programming.

    The task's moves are deterministic on a lattice, so the plan that maximises the return
    (the fewest moves, the least outage) is found exactly: over the map, or in space and time
    where the env's signal moves (the flight taking off at time 0). It is the yardstick a
    learned policy is scored against, never its teacher.

    Args:
        env: The environment on one level (among levels:
            [`optimal_among_levels()`][rainuav.nav.planner.optimal_among_levels]).
        start_m: The start ``(x, y)``, m, inside the area.

    Returns:
        The [`Plan`][rainuav.nav.planner.Plan]: its return, its positions and its actions.

    Raises:
        InvalidInputError: ``env`` is not a [`UAVNavEnv`][rainuav.nav.UAVNavEnv] on one level,
            or its reward or world cannot be planned on.

    Examples:
        ```python
        from rainuav.nav import UAVNavEnv, planner
        from rainuav.radio import build_radio_map, presets

        env = UAVNavEnv(build_radio_map(presets.uma(engine="ray")), goal_m=(1400.0, 1600.0))
        plan = planner.optimal(env, (200.0, 300.0))
        print(len(plan.actions), "moves, return", round(plan.return_, 1))
        ```
    """
    return optimal_many(env, np.asarray(start_m, dtype=np.float64)[None])[0]


def straight_line(env: UAVNavEnv, start_m: npt.ArrayLike) -> Plan:
    """The straight-line baseline, flown in the environment.

    Every move reduces the larger remaining coordinate gap to the goal (x first on ties),
    ignoring the signal, until the flight arrives, leaves the area or runs out of moves.

    Args:
        env: The environment on one level.
        start_m: The start ``(x, y)``, m.

    Returns:
        The [`Plan`][rainuav.nav.planner.Plan] flown, with the return the task gave it.

    Raises:
        InvalidInputError: ``env`` is not a [`UAVNavEnv`][rainuav.nav.UAVNavEnv] on one level.
    """
    env = _as_env(env)
    start = np.asarray(start_m, dtype=np.float64).reshape(1, 2)
    goal = np.asarray(env.cfg.goal_m)
    off = np.zeros((1, 2), dtype=np.int64)
    t = np.zeros(1, dtype=np.int64)
    path, actions, ret = [start[0].copy()], [], 0.0
    while True:
        pos = start[0] + env.cfg.step_m * off[0]
        dx, dy = goal - pos
        a = (0 if dx > 0 else 2) if abs(dx) >= abs(dy) else (1 if dy > 0 else 3)
        r = env.step_batch(start, off, np.zeros(1, dtype=np.int64), t, np.array([a]))
        off, t = r["offset"], r["t"]
        actions.append(a)
        path.append(r["position"][0].copy())
        ret += float(r["reward"][0])
        if r["terminated"][0] or r["truncated"][0]:
            break
    return Plan(ret, np.array(path), np.array(actions, dtype=np.int64))


@dataclass(frozen=True)
class LevelPlan:
    """A trajectory among flight levels and its undiscounted return."""

    return_: float
    """Sum of the rewards."""
    path_m: npt.NDArray[np.float64]
    """(T + 1, 2) positions, from the start."""
    levels: npt.NDArray[np.int64]
    """(T + 1,) the level of each position."""
    actions: npt.NDArray[np.int64]
    """(T,) actions: 0-3 the plane's moves, 4 climb, 5 descend."""
    ticks: npt.NDArray[np.int64]
    """(T + 1,) the flight's clock at each position, in horizontal moves (``move_s`` each)."""


def optimal_levels(
    signal_db: npt.ArrayLike,
    altitudes_m: npt.ArrayLike,
    extent_m: tuple[float, float, float, float],
    cfg: NavConfig,
    starts_m: npt.ArrayLike,
    start_levels: npt.ArrayLike,
    *,
    t_s: npt.ArrayLike | None = None,
    not_flyable: npt.ArrayLike | None = None,
    climb_m_s: float = CLIMB_M_S,
    descend_m_s: float = DESCEND_M_S,
) -> list[LevelPlan]:
    """Exact optimal plans with altitude as a decision (``rainuav_core::planning::planlevels``).

    Six moves: the plane's four, and a climb or descent of one level, which lasts its duration
    in ticks ([`level_durations()`][rainuav.nav.levelfield.level_durations]) and earns that many
    times the base reward where and when it lands. The horizon ``cfg.max_steps`` is in ticks. A
    flight arrives at the destination's horizontal position at any level; leaving the band or
    entering a not-flyable cell ends it as leaving the area does.

    Args:
        signal_db: The signal of each level, (L, H, W), or in time, (T, L, H, W), dB.
        altitudes_m: The levels' heights, (L,), m.
        extent_m: ``(x_min, x_max, y_min, y_max)`` of the maps, m.
        cfg: The task, ``min_db`` resolved.
        starts_m: The starts, (N, 2), m.
        start_levels: The level of each start, (N,) indices; -1: the level whose optimum is
            best (the take-off's climb left to the autopilot).
        t_s: The instants of a signal in time, (T,), s (every flight taking off at 0).
        not_flyable: Cells the UAV may not enter, (L, H', W') booleans.
        climb_m_s: The climb speed, m/s.
        descend_m_s: The descent speed, m/s.

    Returns:
        One [`LevelPlan`][rainuav.nav.planner.LevelPlan] a start.

    Raises:
        InvalidInputError: Shapes that do not match, a signal that is not finite, a start or
            level outside the band (the message names it).
    """
    sig = np.asarray(signal_db, dtype=np.float64)
    alts = np.asarray(altitudes_m, dtype=np.float64).reshape(-1)
    if sig.ndim == 3:
        sig, times = sig[None], np.zeros(1)
    else:
        times = np.zeros(0) if t_s is None else np.asarray(t_s, dtype=np.float64).reshape(-1)
    if sig.ndim != 4 or sig.shape[1] != alts.size or not np.all(np.isfinite(sig)):
        raise InvalidInputError(
            f"signal_db must be finite with shape (L, H, W) or (T, L, H, W), L = {alts.size} "
            f"levels (got {sig.shape})"
        )
    if times.size != sig.shape[0]:
        raise InvalidInputError(
            f"t_s must hold one instant a slice ({sig.shape[0]}; got {times.size})"
        )
    if cfg.min_db is None:
        raise InvalidInputError("cfg.min_db must be resolved (a threshold in dB)")
    starts = np.asarray(starts_m, dtype=np.float64).reshape(-1, 2)
    lv = np.asarray(start_levels, dtype=np.float64).reshape(-1)
    if lv.size != starts.shape[0]:
        raise InvalidInputError("start_levels must hold one level a start")
    climb, descend = level_durations(alts, cfg, climb_m_s, descend_m_s)
    blocked = None
    if not_flyable is not None:
        blocked = np.ascontiguousarray(np.asarray(not_flyable, dtype=np.uint8))
    raw = _core.plan_optimal_levels(
        np.ascontiguousarray(sig), np.ascontiguousarray(times),
        np.ascontiguousarray(np.column_stack([starts, lv])),
        rust_task(cfg, extent_m, climb, descend), blocked,
    )  # fmt: skip
    out = []
    for r, a, p, ticks in raw:
        path = np.asarray(p)
        out.append(
            LevelPlan(
                float(r),
                path[:, :2],
                path[:, 2].astype(np.int64),
                np.asarray(a, dtype=np.int64),
                np.asarray(ticks, dtype=np.int64),
            )
        )
    return out


def optimal_among_levels(
    env: UAVNavEnv, starts_m: npt.ArrayLike, start_levels: npt.ArrayLike | None = None
) -> list[LevelPlan]:
    """Exact optimal plans among flight levels, on an environment's levels and task.

    [`optimal_levels()`][rainuav.nav.planner.optimal_levels] on the environment's signal (its
    levels' maps, or maps in time, and masks), task and vertical speeds.

    Args:
        env: The environment among flight levels.
        starts_m: The starts, (N, 2), m.
        start_levels: The level of each start, (N,) indices (-1: the best level); default
            where the environment starts a flight there
            ([`UAVNavEnv.start_level_at()`][rainuav.nav.batched.BatchedFlights.start_level_at]).

    Returns:
        One [`LevelPlan`][rainuav.nav.planner.LevelPlan] a start.

    Raises:
        InvalidInputError: ``env`` does not fly among levels.
    """
    if not (isinstance(env, UAVNavEnv) and env.level_axis):
        raise InvalidInputError(f"env must be a UAVNavEnv among levels (got {type(env).__name__})")
    starts = np.asarray(starts_m, dtype=np.float64).reshape(-1, 2)
    if start_levels is None:
        start_levels = [env.start_level_at(p) for p in starts]
    f = env.field
    return optimal_levels(
        f.db, f.altitudes_m, f.extent, env.cfg, starts, start_levels,
        t_s=f.t_s if f.varies else None, not_flyable=f.not_flyable, climb_m_s=env.climb_m_s,
        descend_m_s=env.descend_m_s,
    )  # fmt: skip
