"""The ``altitudes`` figures of a study case (``compute = ["altitudes"]``): which height to
fly on the case's network and weather.

The case's scenario is mapped at each of its ``altitudes_m``
([`rainuav.radio.outputs.levelmaps`][rainuav.radio.outputs.levelmaps]); for the evaluation starts
(seeded from the case's seed) the exact plan held at each level (the planner in the plane), the best
single level of each flight (chosen with hindsight) and the exact plan among the levels (free to
climb at 5 m/s and descend at 3 m/s, its start level chosen:
[`rainuav.nav.planner.optimal_levels()`][rainuav.nav.planner.optimal_levels]) are computed, each as
mean cost (the task's: time plus the outage penalty; ``cost_by_altitude`` gives each level's mean
over the flights that arrive and, in brackets, their share: a start inside a building a low level
cannot fly) and share of moves in outage. The excess of a baseline over the plan among levels is the
mean over the flights both arrive on."""

from __future__ import annotations

from typing import Any

import numpy as np

from rainuav.nav import planner
from rainuav.nav.field import SignalField
from rainuav.nav.task import NavConfig
from rainuav.radio.outputs.levelmaps import build_radio_levels, sample_levels
from rainuav.radio.scene.scenario import Scenario

__all__ = ["ALTITUDE_COLUMNS", "altitude_row"]

ALTITUDE_COLUMNS = (
    "outage_by_altitude", "cost_by_altitude", "best_fixed_altitude_m",
    "best_fixed_mean_cost", "levels_optimal_mean_cost", "levels_outage_share",
    "fixed_100m_excess_cost", "best_fixed_excess_cost", "best_single_excess_cost",
    "straight_line_100m_excess_cost", "straight_line_100m_arrives",
)  # fmt: skip
"""The columns this adds to a study's ``results.csv``."""


def _outage(sinr: np.ndarray, extent: Any, path: np.ndarray, lv: np.ndarray, thr: float) -> float:
    """The share of a flight's moves that land below ``thr``, each on its level."""
    if len(path) < 2:
        return 0.0
    s = sample_levels(sinr, extent, path[1:, 0], path[1:, 1], lv[1:])
    return float(np.mean(s < thr))


def altitude_row(
    scn: Scenario, cfg: NavConfig, starts: np.ndarray, env_100m: Any = None
) -> dict[str, Any]:
    """A case's altitude figures (the module's docstring).

    Args:
        scn: The case's scenario.
        cfg: Its task.
        starts: The starts (N, 2), m.
        env_100m: The case's environment at 100 m, for the straight line there; None: left out.

    Returns:
        The figures by column name.
    """
    stack = build_radio_levels(scn)
    sinr, blocked, ext = stack.sinr_db, stack.not_flyable, stack.extent
    alts = stack.altitudes_m
    assert cfg.min_db is not None
    thr = float(cfg.min_db)

    def cost(r: float, path: np.ndarray) -> float:
        arrived = np.hypot(*(path[-1] - np.asarray(cfg.goal_m))) <= cfg.tol_m
        return cfg.goal_reward - r if arrived else np.nan

    c_lv = np.full((len(alts), len(starts)), np.nan)
    o_lv = np.full_like(c_lv, np.nan)
    for k in range(len(alts)):
        field = SignalField(sinr[k], ext, not_flyable=blocked[k])
        for n, p in enumerate(planner.plan_on(field, cfg, starts)):
            c_lv[k, n] = cost(p.return_, p.path_m)
            o_lv[k, n] = _outage(sinr, ext, p.path_m, np.full(len(p.path_m), k), thr)
    free = planner.optimal_levels(sinr, alts, ext, cfg, starts, np.full(len(starts), -1),
                                  not_flyable=blocked)  # fmt: skip
    c_free = np.array([cost(p.return_, p.path_m) for p in free])
    o_free = np.array([_outage(sinr, ext, p.path_m, p.levels, thr) for p in free])
    arrive = np.mean(np.isfinite(c_lv), axis=1)
    mean_by_level = np.array([np.nanmean(c) if np.isfinite(c).any() else np.nan for c in c_lv])
    # The best fixed level: the cheapest of those every flight arrives at (else of those
    # most flights arrive at).
    full = np.flatnonzero(arrive == arrive.max())
    best_fixed = int(full[np.nanargmin(mean_by_level[full])])
    single = np.nanmin(np.where(np.isfinite(c_lv), c_lv, np.inf), axis=0)
    single[~np.isfinite(single)] = np.nan

    def excess(c: np.ndarray) -> float:
        # Over the flights both arrive on (a level some flights cannot fly shows in its
        # arrival share in cost_by_altitude).
        both = np.isfinite(c) & np.isfinite(c_free)
        return float(np.mean((c[both] - c_free[both]) / c_free[both])) if both.any() else np.nan

    near_100 = int(np.argmin(np.abs(alts - 100.0)))
    line_excess, line_arrives = None, None
    if env_100m is not None:
        lines = [planner.straight_line(env_100m, p) for p in starts]
        c_line = np.array([cost(p.return_, p.path_m) for p in lines])
        line_excess, line_arrives = excess(c_line), float(np.mean(np.isfinite(c_line)))
    return {
        "straight_line_100m_excess_cost": line_excess,
        "straight_line_100m_arrives": line_arrives,
        "outage_by_altitude": " ".join(
            f"{a:g}:{np.mean(s < thr):.3f}" for a, s in zip(alts, sinr, strict=True)
        ),
        "cost_by_altitude": " ".join(
            f"{a:g}:{c:.1f}({r:.0%})" for a, c, r in zip(alts, mean_by_level, arrive, strict=True)
        ),
        "best_fixed_altitude_m": float(alts[best_fixed]),
        "best_fixed_mean_cost": float(mean_by_level[best_fixed]),
        "levels_optimal_mean_cost": float(np.nanmean(c_free)),
        "levels_outage_share": float(np.mean(o_free)),
        "fixed_100m_excess_cost": excess(c_lv[near_100]) if alts[near_100] == 100.0 else None,
        "best_fixed_excess_cost": excess(c_lv[best_fixed]),
        "best_single_excess_cost": excess(single),
    }
