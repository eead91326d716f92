"""The flights a user would try instead of the exact space-time optimum, flown through the
weather as it moves (each is scored by the environment's own rewards, move by move):

- [`frozen_plans()`][rainuav.nav.baselines.frozen_plans]: the exact plan on the weather at take-off,
  held still (what a static planning tool gives), flown through the moving storm;
- [`replans()`][rainuav.nav.baselines.replans]: every ``every`` moves, the exact plan from where the
  UAV is, on the weather of that moment held still (persistence), of which the next ``every`` moves
  are flown;
- the straight line: [`rainuav.nav.planner.straight_line()`][rainuav.nav.planner.straight_line].

On a single map (nothing moves) both are the exact optimum.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import numpy.typing as npt

from rainuav._checks import check_integer
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.planner import Plan, _as_env, plan_on

__all__ = ["DEFAULT_REPLAN_EVERY", "fly_actions", "frozen_plans", "replans"]

DEFAULT_REPLAN_EVERY = 10
"""Moves between re-plans (10 moves: 10 s at the default speed)."""


def fly_actions(env: UAVNavEnv, starts_m: npt.ArrayLike, actions: list[np.ndarray]) -> list[Plan]:
    """Each start's moves flown through the env's signal, until the episode ends or they run out.

    Args:
        env: The environment.
        starts_m: The starts (N, 2), m.
        actions: Each start's moves.

    Returns:
        One [`Plan`][rainuav.nav.planner.Plan] a start: the path and the return the environment
        gives.
    """
    env = _as_env(env)
    starts = np.asarray(starts_m, dtype=np.float64).reshape(-1, 2)
    n = len(starts)
    off = np.zeros((n, 2), dtype=np.int64)
    t = np.zeros(n, dtype=np.int64)
    ret = np.zeros(n)
    paths: list[list[np.ndarray]] = [[s.copy()] for s in starts]
    done = [0] * n
    live = np.array([len(a) > 0 for a in actions], dtype=bool)
    while live.any():
        idx = np.flatnonzero(live)
        a = np.array([actions[k][done[k]] for k in idx], dtype=np.int64)
        r = env.step_batch(starts[idx], off[idx], np.zeros_like(idx), t[idx], a)
        off[idx], t[idx] = r["offset"], r["t"]
        ret[idx] += r["reward"]
        for j, k in enumerate(idx):
            paths[k].append(r["position"][j].copy())
            done[k] += 1
        ended = r["terminated"] | r["truncated"]
        for j, k in enumerate(idx):
            if ended[j] or done[k] >= len(actions[k]):
                live[k] = False
    return [
        Plan(float(ret[k]), np.array(paths[k]), np.asarray(actions[k][: done[k]], dtype=np.int64))
        for k in range(n)
    ]


def frozen_plans(env: UAVNavEnv, starts_m: npt.ArrayLike) -> list[Plan]:
    """The exact plan on the weather at take-off held still, flown through the moving weather.

    The path is the plan's (the moves do not depend on the weather); the return is the one flown.

    Args:
        env: The environment.
        starts_m: The starts (N, 2), m.

    Returns:
        One [`Plan`][rainuav.nav.planner.Plan] a start.
    """
    env = _as_env(env)
    starts = np.asarray(starts_m, dtype=np.float64).reshape(-1, 2)
    planned = plan_on(env.field.frozen(0.0), env.cfg, starts)
    return fly_actions(env, starts, [p.actions for p in planned])


def replans(
    env: UAVNavEnv, starts_m: npt.ArrayLike, every: int = DEFAULT_REPLAN_EVERY
) -> list[Plan]:
    """Plans re-made every few moves on the weather of that moment held still, flown in the storm.

    Each plan is over the moves left of the horizon (the module's docstring).

    Args:
        env: The environment.
        starts_m: The starts (N, 2), m.
        every: The moves between two plans.

    Returns:
        One [`Plan`][rainuav.nav.planner.Plan] a start.
    """
    env = _as_env(env)
    every = check_integer("replan_every", every, 1, 100_000)
    starts = np.asarray(starts_m, dtype=np.float64).reshape(-1, 2)
    n, cfg = len(starts), env.cfg
    off = np.zeros((n, 2), dtype=np.int64)
    ret = np.zeros(n)
    paths: list[list[np.ndarray]] = [[s.copy()] for s in starts]
    actions: list[list[int]] = [[] for _ in range(n)]
    live = np.ones(n, dtype=bool)
    t_now = 0  # every live flight has made the same number of moves
    while live.any() and t_now < cfg.max_steps:
        idx = np.flatnonzero(live)
        pos = starts[idx] + cfg.step_m * off[idx]
        frozen = env.field.frozen(float(env.stepper.time_s(np.array([t_now]))[0]))
        left = dataclasses.replace(cfg, max_steps=cfg.max_steps - t_now)
        plans = plan_on(frozen, left, pos)
        t = np.full(len(idx), t_now, dtype=np.int64)
        for m in range(min(every, cfg.max_steps - t_now)):
            moving = np.array([m < len(p.actions) for p in plans]) & live[idx]
            if not moving.any():
                break
            sel = np.flatnonzero(moving)
            k = idx[sel]
            a = np.array([plans[j].actions[m] for j in sel], dtype=np.int64)
            r = env.step_batch(starts[k], off[k], np.zeros_like(k), t[sel], a)
            off[k], t[sel] = r["offset"], r["t"]
            ret[k] += r["reward"]
            for j, kk in enumerate(k):
                paths[kk].append(r["position"][j].copy())
                actions[kk].append(int(a[j]))
            live[k[r["terminated"] | r["truncated"]]] = False
        t_now += every
    return [
        Plan(float(ret[k]), np.array(paths[k]), np.array(actions[k], dtype=np.int64))
        for k in range(n)
    ]
