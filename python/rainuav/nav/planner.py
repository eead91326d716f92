"""Exact and baseline planners for :class:`rainuav.nav.env.UAVNavEnv`.

The moves are deterministic on the start's lattice, so the exact finite-horizon optimum of the
undiscounted return is a dynamic programme (in Rust; many starts run in parallel). It is the
yardstick for learned policies. Where the signal changes in time (a
:class:`rainuav.nav.field.SignalSeries`) the programme's rewards depend on the step: it is then
the exact optimum on the space-time lattice, the storm's motion known
(``rainuav_core::plantime``). The baselines a user would try instead (the plan of the weather at
take-off, re-planning on the weather of the moment) are in :mod:`rainuav.nav.baselines`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import _core
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.task import NavConfig

__all__ = ["Plan", "optimal", "optimal_many", "straight_line"]


@dataclass(frozen=True)
class Plan:
    """A trajectory and its undiscounted return."""

    return_: float
    """Sum of the rewards."""
    path_m: npt.NDArray[np.float64]
    """(T + 1, 2) positions, from the start."""
    actions: npt.NDArray[np.int64]
    """(T,) actions."""


def _as_env(env: UAVNavEnv) -> UAVNavEnv:
    if not isinstance(env, UAVNavEnv):
        raise InvalidInputError(f"env must be a rainuav.nav.UAVNavEnv (got {type(env).__name__})")
    return env


def optimal_many(env: UAVNavEnv, starts_m: npt.ArrayLike) -> list[Plan]:
    """Exact optimal plans from each start (N, 2), computed in parallel; in space-time where
    the env's signal changes in time (every flight taking off at time 0)."""
    env = _as_env(env)
    return plan_on(env.field, env.cfg, starts_m)


def plan_on(field: Any, cfg: NavConfig, starts_m: npt.ArrayLike) -> list[Plan]:
    """Exact optimal plans of the task ``cfg`` (``min_db`` resolved) on ``field`` (a
    :class:`SignalField`, or a series in time) from each start."""
    starts = np.ascontiguousarray(np.asarray(starts_m, dtype=np.float64).reshape(-1, 2))
    task = {
        "step_m": float(cfg.step_m),
        "tol_m": float(cfg.tol_m),
        "max_steps": int(cfg.max_steps),
        "mu": float(cfg.mu),
        "reward": cfg.reward,
        "sir_min_db": float(cfg.min_db),  # the Rust planner's name for the threshold
        "goal_reward": float(cfg.goal_reward),
        "out_of_bounds_penalty": float(cfg.out_of_bounds_penalty),
    }
    mask = getattr(field, "not_flyable", None)
    if mask is not None:
        task["blocked"] = np.ascontiguousarray(mask, dtype=np.uint8)
    goal = (float(cfg.goal_m[0]), float(cfg.goal_m[1]))
    if isinstance(field, SignalField):
        raw = _core.plan_optimal(field.db, field.extent, goal, starts, **task)
    else:
        raw = _core.plan_optimal_in_time(
            field.db, field.t_s, field.extent, goal, starts, t0_s=0.0, dt_s=cfg.move_s, **task
        )
    return [Plan(float(r), np.asarray(path), np.asarray(a, dtype=np.int64)) for r, a, path in raw]


def optimal(env: UAVNavEnv, start_m: npt.ArrayLike) -> Plan:
    """The exact optimal plan from ``start_m``."""
    return optimal_many(env, np.asarray(start_m, dtype=np.float64)[None])[0]


def straight_line(env: UAVNavEnv, start_m: npt.ArrayLike) -> Plan:
    """The straight-line baseline: every move reduces the larger remaining coordinate gap to
    the goal (x first on ties), ignoring the signal."""
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
        r = env.stepper.step(start, off, t, np.array([a]))
        off, t = r["offset"], r["t"]
        actions.append(a)
        path.append(r["position"][0].copy())
        ret += float(r["reward"][0])
        if r["terminated"][0] or r["truncated"][0]:
            break
    return Plan(ret, np.array(path), np.array(actions, dtype=np.int64))
