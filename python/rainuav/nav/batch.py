"""Many UAVs stepped at once with exactly the scalar environment's transitions."""

from __future__ import annotations

import numpy as np

from rainuav.nav.field import SignalField
from rainuav.nav.levelfield import LevelStepper
from rainuav.nav.task import MOVES, NavConfig

__all__ = ["BatchStepper"]


class BatchStepper(LevelStepper):
    """The one batched stepper over the plane's single level, with the plane's shield.

    The stepper is [`LevelStepper`][rainuav.nav.levelfield.LevelStepper] on one level, where every
    move lasts one tick (many UAVs are stepped through
    [`step_batch()`][rainuav.nav.batched.BatchedFlights.step_batch], every `level` 0); the shield
    gives the moves that can still arrive in time."""

    def __init__(self, field: SignalField, cfg: NavConfig):
        """Builds the stepper over a field and a task.

        Args:
            field: The signal flown (one level).
            cfg: The navigation task (its `min_db` resolved).
        """
        super().__init__(field, cfg, [], [])

    def moves_to_goal(self, position: np.ndarray, goal: np.ndarray | None = None) -> np.ndarray:
        """The fewest moves from each position to its destination.

        The destination is reached at a point of the position's lattice within `tol_m` of it and
        inside the area (a monotone lattice path between two points of the rectangle stays in it).

        Args:
            position: Positions (N, 2), m.
            goal: Destinations (N, 2); None: the task's.

        Returns:
            (N,) float: the number of moves, `inf` where the lattice has no such point.
        """
        cfg = self.cfg
        g = self.goal if goal is None else np.asarray(goal, dtype=np.float64).reshape(-1, 1, 2)
        x0, x1, y0, y1 = self.field.extent
        s = cfg.step_m
        p = np.asarray(position, dtype=np.float64).reshape(-1, 1, 2)
        m = int(np.ceil(cfg.tol_m / s)) + 1
        grid = np.stack(np.meshgrid(np.arange(-m, m + 1), np.arange(-m, m + 1)), -1).reshape(-1, 2)
        # Every lattice offset within m of the one nearest the goal: (N, (2m+1)^2, 2).
        k = np.round((g - p) / s) + grid
        q = p + s * k
        ok = (
            (np.hypot(q[..., 0] - g[..., 0], q[..., 1] - g[..., 1]) <= cfg.tol_m)
            & (q[..., 0] >= x0) & (q[..., 0] <= x1) & (q[..., 1] >= y0) & (q[..., 1] <= y1)
        )  # fmt: skip
        return np.where(ok, np.abs(k).sum(axis=-1), np.inf).min(axis=-1)

    def safe_actions(
        self, position: np.ndarray, t: np.ndarray, goal: np.ndarray | None = None
    ) -> np.ndarray:
        """The moves after which each UAV is still in the area and can still arrive in time.

        A shield (Alshiekh et al., AAAI 2018): where no move qualifies (a start too far to arrive
        within `max_steps`) every move is allowed.

        Args:
            position: Positions (N, 2), m.
            t: Moves made so far (N,).
            goal: Destinations (N, 2); None: the task's.

        Returns:
            (N, 4) bool, one column a move.
        """
        p = np.asarray(position, dtype=np.float64).reshape(-1, 1, 2)
        left = self.cfg.max_steps - np.asarray(t).reshape(-1, 1) - 1  # moves left after this one
        x0, x1, y0, y1 = self.field.extent
        q = p + self.cfg.step_m * MOVES  # (N, 4, 2): the position after each move
        inside = (q[..., 0] >= x0) & (q[..., 0] <= x1) & (q[..., 1] >= y0) & (q[..., 1] <= y1)
        gq = None if goal is None else np.repeat(np.asarray(goal, np.float64).reshape(-1, 2), 4, 0)
        ok = inside & (self.moves_to_goal(q.reshape(-1, 2), gq).reshape(-1, 4) <= left)
        ok[~ok.any(axis=1)] = True
        return ok
