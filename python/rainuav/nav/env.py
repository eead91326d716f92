"""Gymnasium environment: fly a UAV on a lattice over a SIR map to a destination.

Semantics (the planner and the tests rely on them; PHYSICS.md section 6):

- SIR at a position: bilinear interpolation of ``sir_db`` (H, W) whose sample [i, j] sits at
  ``x = x_min + (j + 0.5) (x_max - x_min) / W``, ``y = y_min + (i + 0.5) (y_max - y_min) / H``;
  beyond the outermost centres the edge values hold.
- Observation: position scaled to [0, 1]^2 (float32). Actions: 0 = +x, 1 = +y, 2 = -x, 3 = -y.
- Moves and rewards: :mod:`rainuav.nav.task` (shortfall below ``sir_min_db`` by default,
  ``goal_reward`` on arrival, ``out_of_bounds_penalty`` on leaving the area, truncated after
  ``max_steps``).
- Positions are kept as the start plus an integer number of steps in x and y, so every visited
  point lies exactly on the start's lattice (the exact planner's state space).
"""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.nav.batch import BatchStepper
from rainuav.nav.field import SirField
from rainuav.nav.task import LoiteringWarning, NavConfig, check_config

__all__ = ["UAVNavEnv"]


class UAVNavEnv(gym.Env):
    """UAV navigation over a SIR map (registered as ``rainuav/UAVNav-v0``)."""

    metadata = {"render_modes": []}  # noqa: RUF012 - gymnasium's convention

    def __init__(
        self,
        radio_map: Any = None,
        sir_db: npt.ArrayLike | None = None,
        extent_m: tuple[float, float, float, float] | None = None,
        goal_m: tuple[float, float] = (1400.0, 1600.0),
        step_m: float = 10.0,
        tol_m: float = 10.0,
        max_steps: int = 300,
        mu: float = 10.0 / 43.0,
        reward: str = "shortfall",
        sir_min_db: float = 10.0,
        goal_reward: float = 2000.0,
        out_of_bounds_penalty: float = 10000.0,
        start_m: tuple[float, float] | None = None,
        config: NavConfig | None = None,
    ) -> None:
        super().__init__()
        if radio_map is not None:
            if sir_db is not None:
                raise InvalidInputError("give radio_map or sir_db, not both")
            sir_db, extent_m = radio_map.sir_db, radio_map.extent_m
        if sir_db is None or extent_m is None:
            raise InvalidInputError("sir_db and extent_m are required when radio_map is None")
        self.field = SirField(sir_db, extent_m)
        self.cfg = config or NavConfig(
            goal_m=tuple(goal_m),
            step_m=step_m,
            tol_m=tol_m,
            max_steps=max_steps,
            mu=mu,
            reward=reward,
            sir_min_db=sir_min_db,
            goal_reward=goal_reward,
            out_of_bounds_penalty=out_of_bounds_penalty,
            start_m=None if start_m is None else tuple(start_m),
        )
        check_config(self.cfg, self.field.extent)
        if self.cfg.reward == "linear":
            warnings.warn(
                "reward='linear' (-1 + mu * SIR) is positive near a base station: the UAV "
                "can earn more by loitering than by arriving",
                LoiteringWarning,
                stacklevel=2,
            )
        self.stepper = BatchStepper(self.field, self.cfg)
        self.observation_space = gym.spaces.Box(0.0, 1.0, shape=(2,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(4)
        self._start = np.zeros((1, 2))
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._t = np.zeros(1, dtype=np.int64)
        self._pos = np.zeros(2)

    # -- helpers ----------------------------------------------------------------------------
    def observe(self, pos: np.ndarray) -> np.ndarray:
        """Position scaled to [0, 1]^2, float32 (works on (..., 2) arrays)."""
        x0, x1, y0, y1 = self.field.extent
        lo = np.array([x0, y0])
        return ((np.asarray(pos) - lo) / np.array([x1 - x0, y1 - y0])).astype(np.float32)

    def sample_start(self, rng: np.random.Generator) -> np.ndarray:
        """Uniform in the area, farther than tol_m from the goal."""
        x0, x1, y0, y1 = self.field.extent
        g = np.asarray(self.cfg.goal_m)
        while True:
            p = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
            if np.hypot(*(p - g)) > self.cfg.tol_m:
                return p

    @property
    def position_m(self) -> np.ndarray:
        return self._pos.copy()

    # -- gymnasium API ----------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        start = (options or {}).get("start_m", self.cfg.start_m)
        if start is None:
            p = self.sample_start(self.np_random)
        else:
            p = np.asarray(start, dtype=np.float64)
            x0, x1, y0, y1 = self.field.extent
            if p.shape != (2,) or not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
                raise InvalidInputError(f"start_m must lie inside the area (got {start!r})")
        self._start = p[None].copy()
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._t = np.zeros(1, dtype=np.int64)
        self._pos = p.copy()
        sir = float(self.field(p[0], p[1]))
        return self.observe(p), self._info(sir)

    def _info(self, sir: float, arrived: bool = False) -> dict[str, Any]:
        return {
            "sir_db": sir,
            "position_m": self._pos.copy(),
            "outage": bool(sir < self.cfg.sir_min_db),
            "arrived": arrived,
        }

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        a = int(action)
        if not 0 <= a < 4:
            raise InvalidInputError(f"action must be 0, 1, 2 or 3 (got {action!r})")
        r = self.stepper.step(self._start, self._offset, self._t, np.array([a]))
        self._offset, self._t = r["offset"], r["t"]
        self._pos = r["position"][0].copy()
        sir = float(r["sir_db"][0])
        return (
            self.observe(self._pos),
            float(r["reward"][0]),
            bool(r["terminated"][0]),
            bool(r["truncated"][0]),
            self._info(sir, bool(r["arrived"][0])),
        )
