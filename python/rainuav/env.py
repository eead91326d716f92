"""Gymnasium environment: fly a UAV on a lattice over a SIR map to a destination.

Semantics (the planner and the tests rely on them; PHYSICS.md section 6):

- SIR at a position: bilinear interpolation of ``sir_db`` (H, W) whose sample [i, j] sits at
  ``x = x_min + (j + 0.5) (x_max - x_min) / W``, ``y = y_min + (i + 0.5) (y_max - y_min) / H``;
  beyond the outermost centres the edge values hold.
- Observation: position scaled to [0, 1]^2 (float32). Actions: 0 = +x, 1 = +y, 2 = -x, 3 = -y.
- A move ``q' = q + step_m e_a`` earns ``b(q')``: ``"shortfall"`` (default)
  ``-1 - mu max(0, sir_min_db - SIR)``, ``"outage"`` ``-1 - mu [SIR < sir_min_db]`` or
  ``"linear"`` ``-1 + mu 10^(SIR/10)`` (the paper's literal form: it pays to loiter near a base
  station). Leaving the area (a coordinate beyond the bounds): ``b(clamp(q')) -
  out_of_bounds_penalty``, terminated, the UAV stays at ``clamp(q')``. Reaching the goal
  (``|q' - goal| <= tol_m``): ``b(q') + goal_reward``, terminated. Truncated after
  ``max_steps`` steps (unless terminated on that step).
- Positions are kept as the start plus an integer number of steps in x and y, so every visited
  point lies exactly on the start's lattice (the exact planner's state space).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError

__all__ = ["BatchStepper", "LoiteringWarning", "NavConfig", "SirField", "UAVNavEnv"]

REWARDS = ("shortfall", "outage", "linear")
#: Unit steps of the four actions: +x, +y, -x, -y.
MOVES = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]], dtype=np.int64)


class LoiteringWarning(UserWarning):
    """The 'linear' reward pays the UAV to hover near a base station."""


@dataclass
class NavConfig:
    """The navigation task (defaults: the paper's Table I and PHYSICS.md section 6)."""

    goal_m: tuple[float, float] = (1400.0, 1600.0)
    """Destination, m."""
    step_m: float = 10.0
    """Length of one move, m."""
    tol_m: float = 10.0
    """Arrival tolerance D_tol, m."""
    max_steps: int = 300
    """Episode length limit."""
    mu: float = 10.0 / 43.0
    """Weight of the SIR term."""
    reward: str = "shortfall"
    """'shortfall', 'outage' or 'linear'."""
    sir_min_db: float = 10.0
    """Minimum SIR, dB."""
    goal_reward: float = 2000.0
    """R_des, paid on arrival."""
    out_of_bounds_penalty: float = 10000.0
    """P_ob, charged on leaving the area."""
    start_m: tuple[float, float] | None = None
    """Fixed start (None: uniform in the area, farther than tol_m from the goal)."""


def _check_cfg(cfg: NavConfig, extent: tuple[float, float, float, float]) -> None:
    x0, x1, y0, y1 = extent
    g = np.asarray(cfg.goal_m, dtype=float)
    if g.shape != (2,) or not np.all(np.isfinite(g)):
        raise InvalidInputError(f"goal_m must be two finite numbers (got {cfg.goal_m!r})")
    if not (x0 <= g[0] <= x1 and y0 <= g[1] <= y1):
        raise InvalidInputError(f"goal_m must lie inside the area {extent} (got {cfg.goal_m!r})")
    for name in ("step_m", "tol_m"):
        v = getattr(cfg, name)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise InvalidInputError(f"{name} must be finite and > 0 (got {v!r})")
    if not (isinstance(cfg.max_steps, (int, np.integer)) and cfg.max_steps >= 1):
        raise InvalidInputError(f"max_steps must be an integer >= 1 (got {cfg.max_steps!r})")
    for name in ("mu", "sir_min_db", "goal_reward", "out_of_bounds_penalty"):
        v = getattr(cfg, name)
        if not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise InvalidInputError(f"{name} must be a finite number (got {v!r})")
    if cfg.reward not in REWARDS:
        raise InvalidInputError(f"reward must be one of {REWARDS} (got {cfg.reward!r})")
    if cfg.start_m is not None:
        s = np.asarray(cfg.start_m, dtype=float)
        if s.shape != (2,) or not (x0 <= s[0] <= x1 and y0 <= s[1] <= y1):
            raise InvalidInputError(f"start_m must lie inside the area (got {cfg.start_m!r})")


class SirField:
    """Bilinear, edge-clamped interpolation of a SIR map (see the module docs)."""

    def __init__(self, sir_db: npt.ArrayLike, extent_m: tuple[float, float, float, float]):
        s = np.asarray(sir_db, dtype=np.float64)
        if s.ndim != 2 or min(s.shape) < 1:
            raise InvalidInputError(f"sir_db must be a 2-D (H, W) array (got shape {s.shape})")
        if not np.all(np.isfinite(s)):
            raise InvalidInputError("sir_db must be finite everywhere (no NaN or inf)")
        e = np.asarray(extent_m, dtype=np.float64)
        if e.shape != (4,) or not np.all(np.isfinite(e)):
            raise InvalidInputError(
                f"extent_m must be (x_min, x_max, y_min, y_max) (got {extent_m!r})"
            )
        if not (e[1] > e[0] and e[3] > e[2]):
            raise InvalidInputError(
                f"extent_m must have x_max > x_min and y_max > y_min (got {extent_m!r})"
            )
        self.sir_db = np.ascontiguousarray(s)
        self.extent = (float(e[0]), float(e[1]), float(e[2]), float(e[3]))

    def __call__(self, x: Any, y: Any) -> Any:
        x0, x1, y0, y1 = self.extent
        h, w = self.sir_db.shape
        fx = np.clip((np.asarray(x, dtype=np.float64) - x0) / (x1 - x0) * w - 0.5, 0.0, w - 1.0)
        fy = np.clip((np.asarray(y, dtype=np.float64) - y0) / (y1 - y0) * h - 0.5, 0.0, h - 1.0)
        j0 = np.minimum(np.floor(fx), max(w - 2, 0)).astype(np.int64)
        i0 = np.minimum(np.floor(fy), max(h - 2, 0)).astype(np.int64)
        tx = fx - j0
        ty = fy - i0
        j1 = np.minimum(j0 + 1, w - 1)
        i1 = np.minimum(i0 + 1, h - 1)
        s = self.sir_db
        return (
            s[i0, j0] * (1.0 - tx) * (1.0 - ty)
            + s[i0, j1] * tx * (1.0 - ty)
            + s[i1, j0] * (1.0 - tx) * ty
            + s[i1, j1] * tx * ty
        )


def base_reward(sir_db: Any, cfg: NavConfig) -> Any:
    """b(q') from the SIR at the new position."""
    if cfg.reward == "shortfall":
        return -1.0 - cfg.mu * np.maximum(0.0, cfg.sir_min_db - sir_db)
    if cfg.reward == "outage":
        return -1.0 - cfg.mu * (sir_db < cfg.sir_min_db)
    return -1.0 + cfg.mu * 10.0 ** (sir_db / 10.0)


class BatchStepper:
    """Steps many UAVs at once with exactly the scalar environment's transitions.

    State per UAV: ``start`` (N, 2) float, ``offset`` (N, 2) int (steps taken in x and y) and
    ``t`` (N,) steps so far; position = start + step_m * offset.
    """

    def __init__(self, field: SirField, cfg: NavConfig):
        self.field = field
        self.cfg = cfg
        self.goal = np.asarray(cfg.goal_m, dtype=np.float64)

    def step(
        self, start: np.ndarray, offset: np.ndarray, t: np.ndarray, action: np.ndarray
    ) -> dict[str, np.ndarray]:
        """One move for every UAV. Returns new ``offset``, ``t``, ``position`` (after clamping),
        ``reward``, ``terminated``, ``truncated``, ``sir_db``, ``out`` (left the area) and
        ``arrived`` (reached the goal)."""
        cfg = self.cfg
        x0, x1, y0, y1 = self.field.extent
        new_off = offset + MOVES[action]
        q = start + cfg.step_m * new_off
        out = (q[:, 0] < x0) | (q[:, 0] > x1) | (q[:, 1] < y0) | (q[:, 1] > y1)
        qc = np.stack([np.clip(q[:, 0], x0, x1), np.clip(q[:, 1], y0, y1)], axis=1)
        sir = self.field(qc[:, 0], qc[:, 1])
        b = base_reward(sir, cfg)
        arrived = ~out & (np.hypot(q[:, 0] - self.goal[0], q[:, 1] - self.goal[1]) <= cfg.tol_m)
        reward = (
            b
            - np.where(out, cfg.out_of_bounds_penalty, 0.0)
            + np.where(arrived, cfg.goal_reward, 0.0)
        )
        terminated = out | arrived
        t_new = t + 1
        truncated = ~terminated & (t_new >= cfg.max_steps)
        return {
            "offset": new_off,
            "t": t_new,
            "position": qc,
            "reward": reward,
            "terminated": terminated,
            "truncated": truncated,
            "sir_db": sir,
            "out": out,
            "arrived": arrived,
        }

    def moves_to_goal(self, position: np.ndarray) -> np.ndarray:
        """Fewest moves from each (N, 2) position to a point of its lattice within ``tol_m``
        of the destination and inside the area (a monotone lattice path between two points of
        the rectangle stays in it); ``inf`` where the lattice has no such point."""
        cfg = self.cfg
        x0, x1, y0, y1 = self.field.extent
        s = cfg.step_m
        p = np.asarray(position, dtype=np.float64).reshape(-1, 1, 2)
        m = int(np.ceil(cfg.tol_m / s)) + 1
        grid = np.stack(np.meshgrid(np.arange(-m, m + 1), np.arange(-m, m + 1)), -1).reshape(-1, 2)
        # Every lattice offset within m of the one nearest the goal: (N, (2m+1)^2, 2).
        k = np.round((self.goal - p) / s) + grid
        q = p + s * k
        ok = (
            (np.hypot(q[..., 0] - self.goal[0], q[..., 1] - self.goal[1]) <= cfg.tol_m)
            & (q[..., 0] >= x0) & (q[..., 0] <= x1) & (q[..., 1] >= y0) & (q[..., 1] <= y1)
        )  # fmt: skip
        return np.where(ok, np.abs(k).sum(axis=-1), np.inf).min(axis=-1)

    def safe_actions(self, position: np.ndarray, t: np.ndarray) -> np.ndarray:
        """(N, 4) bool: the moves after which the UAV is still in the area and can still
        arrive within ``max_steps`` (a shield: Alshiekh et al., AAAI 2018). Where no move
        qualifies (a start too far to arrive in time) every move is allowed."""
        p = np.asarray(position, dtype=np.float64).reshape(-1, 1, 2)
        left = self.cfg.max_steps - np.asarray(t).reshape(-1, 1) - 1  # moves left after this one
        x0, x1, y0, y1 = self.field.extent
        q = p + self.cfg.step_m * MOVES  # (N, 4, 2): the position after each move
        inside = (q[..., 0] >= x0) & (q[..., 0] <= x1) & (q[..., 1] >= y0) & (q[..., 1] <= y1)
        ok = inside & (self.moves_to_goal(q).reshape(-1, 4) <= left)
        ok[~ok.any(axis=1)] = True
        return ok


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
        _check_cfg(self.cfg, self.field.extent)
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


def make_config(**kw: Any) -> NavConfig:
    """A NavConfig from keywords (unknown names are errors)."""
    names = {f.name for f in dataclasses.fields(NavConfig)}
    bad = set(kw) - names
    if bad:
        raise InvalidInputError(f"unknown NavConfig field(s) {sorted(bad)}")
    return NavConfig(**kw)
