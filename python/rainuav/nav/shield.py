"""A shield for greedy flights (Alshiekh et al., AAAI 2018): which moves a flight may take.

Rule 1 ([`BatchStepper.safe_actions()`][rainuav.nav.batch.BatchStepper.safe_actions]): only moves
after which the UAV is still in the area and can still arrive within ``max_steps``. Rule 2: among
those, moves onto a position the flight has not visited, where one exists. The shield is a safety
layer around a policy, not part of it: metrics report the policy alone first (see
``docs/record/learning.md``)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rainuav.nav.env import UAVNavEnv
from rainuav.nav.task import MOVES

__all__ = ["shield_moves", "unvisited_moves"]


def unvisited_moves(offset: np.ndarray, visited: Sequence[set[tuple[int, int]]]) -> np.ndarray:
    """The moves from each flight's lattice offset to an offset it has not visited.

    Args:
        offset: The flights' offsets (N, 2).
        visited: Each flight's set of visited offsets.

    Returns:
        (N, 4) bool.
    """
    steps = MOVES.tolist()
    return np.array(
        [
            [(ox + dx, oy + dy) not in seen for dx, dy in steps]
            for (ox, oy), seen in zip(offset.tolist(), visited, strict=True)
        ],
        dtype=bool,
    ).reshape(-1, 4)


def shield_moves(
    env: UAVNavEnv,
    pos: np.ndarray,
    t: np.ndarray,
    offset: np.ndarray,
    visited: Sequence[set[tuple[int, int]]],
    goal: np.ndarray | None = None,
) -> np.ndarray:
    """The moves the shield allows each UAV.

    First the safe moves (still in the area and able to arrive within `max_steps`,
    [`safe_actions()`][rainuav.nav.batch.BatchStepper.safe_actions]); among them, the moves to a
    position the flight has not visited, where there is one. The second rule applies where every
    move costs at least 1 ("shortfall" and "outage" with `mu >= 0`, "linear" with `mu <= 0`):
    cutting a loop out of a path then gains at least its length, so an optimal flight never revisits
    a position and the rule only removes moves no optimal flight makes. Elsewhere (the paper's
    "linear" with `mu > 0`: loitering can pay) only the first rule applies.

    Args:
        env: The environment flown.
        pos: Positions (N, 2), m.
        t: Moves made so far (N,).
        offset: Each flight's lattice offset from its start (N, 2).
        visited: Each flight's lattice offsets so far.
        goal: Each flight's destination (N, 2); None: the task's.

    Returns:
        (N, 4) bool, one column a move.
    """
    allowed = env.stepper.safe_actions(pos, t, goal)
    loops_can_pay = env.cfg.mu > 0 if env.cfg.reward == "linear" else env.cfg.mu < 0
    if loops_can_pay:
        return allowed
    fresh = allowed & unvisited_moves(offset, visited)
    return np.where(fresh.any(axis=1, keepdims=True), fresh, allowed)
