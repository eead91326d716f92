"""The navigation task in three dimensions: altitude as a decision.

The UAV flies on a stack of levels (one signal per flight altitude, lowest first; each a map
or maps in time, each with its not-flyable pixels) and has six moves: the plane's four on its
level (:mod:`rainuav.nav.task`) and a climb or a descent of one level.

- **Clock.** The flight's clock ticks once per horizontal move (``move_s`` seconds). A climb
  lasts the gap over ``climb_m_s`` and a descent the gap over ``descend_m_s``, rounded up to
  whole ticks (:func:`level_durations`; the defaults, 15 m gaps and 1 s moves: 3 and 5). A
  move lands at the tick its duration later and reads the signal there and then.
- **Rewards.** A move earns its duration in ticks times the base reward where and when it
  lands (``-1 - mu shortfall`` by default): the flight's cost is its time plus the weighted
  shortfall, each move weighted by how long it lasts. Leaving the area, climbing above the
  highest level or descending below the lowest, or entering a not-flyable cell of a level
  ends the flight with ``out_of_bounds_penalty`` (the UAV stays where it was, on its level,
  for a move out of the band). Arriving within ``tol_m`` of the destination's horizontal
  position, at any level, pays ``goal_reward`` (the landing is the autopilot's).
- **Horizon.** ``max_steps`` ticks: the flight is cut when its clock reaches it (one level:
  ``max_steps`` moves, the plane's task, same returns: tested).
- **Observation.** Position scaled to [0, 1]^2, the level over the highest level index (0 on
  one level), and where the signal moves the clock over ``max_steps``. ``info`` adds
  ``altitude_m`` and ``level`` to the plane's keys.

The exact optimum of this task is :func:`rainuav.nav.planner.optimal_levels`
(``rainuav_core::planlevels``), which reads the signal operation for operation as
:class:`LevelStepper` does; its plans replayed here earn its returns (tested).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from rainuav._checks import as_real_array
from rainuav.errors import InvalidInputError
from rainuav.nav.env import DEFAULT_MIN_DB
from rainuav.nav.field import SignalField, SignalSeries, blocked_at
from rainuav.nav.task import MOVES, NavConfig, base_reward, check_config

__all__ = [
    "CLIMB_M_S",
    "DESCEND_M_S",
    "LEVEL_ACTIONS",
    "LevelField",
    "LevelStepper",
    "UAVLevelsEnv",
    "level_durations",
]

CLIMB_M_S = 5.0
"""Default climb speed, m/s."""
DESCEND_M_S = 3.0
"""Default descent speed, m/s."""
LEVEL_ACTIONS = 6
"""0 = +x, 1 = +y, 2 = -x, 3 = -y, 4 = climb one level, 5 = descend one level."""


def level_durations(
    altitudes_m: npt.ArrayLike,
    cfg: NavConfig,
    climb_m_s: float = CLIMB_M_S,
    descend_m_s: float = DESCEND_M_S,
) -> tuple[list[int], list[int]]:
    """How long each climb and each descent between neighbouring levels lasts, in ticks of
    the flight's clock (one horizontal move, ``cfg.move_s``): the gap over the climb or
    descent speed, rounded up to whole moves (at least one). With the defaults, 15 m gaps
    and 1 s moves: 3 and 5 exactly."""
    gaps = np.diff(np.asarray(altitudes_m, dtype=np.float64))
    for name, v in (("climb_m_s", climb_m_s), ("descend_m_s", descend_m_s)):
        if not (np.isfinite(v) and 0.1 <= v <= 100.0):
            raise InvalidInputError(f"{name} must be in 0.1..100 m/s (got {v!r})")
    move = cfg.move_s

    def ticks(speed: float) -> list[int]:
        # 1e-9 absorbs the rounding of a gap that is a whole number of moves.
        return [max(1, math.ceil(g / speed / move - 1e-9)) for g in gaps]

    return ticks(climb_m_s), ticks(descend_m_s)


class LevelField:
    """The signal of every level: one :class:`SignalField` or :class:`SignalSeries` a level
    (all maps or all series, over one area), lowest first, at ``altitudes_m``."""

    def __init__(
        self, fields: Sequence[SignalField | SignalSeries], altitudes_m: npt.ArrayLike
    ) -> None:
        alts = as_real_array("altitudes_m", altitudes_m).reshape(-1)
        if len(fields) != alts.size or alts.size == 0:
            raise InvalidInputError(
                f"altitudes_m must hold one altitude a level ({len(fields)} levels, got "
                f"{alts.size})"
            )
        if alts.size > 1 and not np.all(np.diff(alts) > 0):
            raise InvalidInputError(f"altitudes_m must increase (got {alts.tolist()})")
        kinds = {type(f) for f in fields}
        if not kinds <= {SignalField, SignalSeries} or len(kinds) != 1:
            raise InvalidInputError("fields must be all SignalField or all SignalSeries")
        if len({f.extent for f in fields}) != 1:
            raise InvalidInputError("the levels' fields must cover one area (one extent)")
        self.fields = tuple(fields)
        self.altitudes_m = alts
        self.extent = fields[0].extent
        self.varies = bool(fields[0].varies)

    @classmethod
    def from_stack(
        cls,
        signal_db: npt.ArrayLike,
        altitudes_m: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        *,
        t_s: npt.ArrayLike | None = None,
        not_flyable: npt.ArrayLike | None = None,
        serving_cell: npt.ArrayLike | None = None,
    ) -> LevelField:
        """From a stack (L, H, W), or (T, L, H, W) at the instants ``t_s``; ``not_flyable``
        (L, H', W') and ``serving_cell`` (the stack's shape) optional."""
        sig = np.asarray(signal_db, dtype=np.float64)
        if sig.ndim not in (3, 4):
            raise InvalidInputError(
                f"signal_db must be (L, H, W) or (T, L, H, W) (got {sig.shape})"
            )
        if (sig.ndim == 4) != (t_s is not None):
            raise InvalidInputError("t_s goes with a (T, L, H, W) stack, and only with one")
        mask = None if not_flyable is None else np.asarray(not_flyable)
        srv = None if serving_cell is None else np.asarray(serving_cell)
        axis = sig.ndim - 3  # the level axis
        fields: list[SignalField | SignalSeries] = []
        for k in range(sig.shape[axis]):
            m = None if mask is None else mask[k]
            s = None if srv is None else np.take(srv, k, axis=axis)
            if sig.ndim == 3:
                fields.append(SignalField(sig[k], extent_m, serving_cell=s, not_flyable=m))
            else:
                fields.append(SignalSeries(sig[:, k], t_s, extent_m, serving_cell=s,
                                           not_flyable=m))  # fmt: skip
        return cls(fields, altitudes_m)

    @property
    def levels(self) -> int:
        return len(self.fields)

    def __call__(self, x: Any, y: Any, t_s: Any, level: Any) -> np.ndarray:
        """The signal at ``(x, y)`` on ``level`` at ``t_s`` (arrays of one shape, or numbers)."""
        x, y, t, lv = np.broadcast_arrays(*(np.asarray(v) for v in (x, y, t_s, level)))
        out = np.empty(x.shape)
        for k in np.unique(lv):
            on = lv == k
            out[on] = self.fields[int(k)](x[on], y[on], t[on])
        return out

    def serving_cell(self, x: Any, y: Any, t_s: Any, level: Any) -> np.ndarray:
        """The serving cell at ``(x, y)`` on ``level`` at ``t_s`` (-1 where none is named)."""
        x, y, t, lv = np.broadcast_arrays(*(np.asarray(v) for v in (x, y, t_s, level)))
        out = np.empty(x.shape, dtype=np.int64)
        for k in np.unique(lv):
            on = lv == k
            out[on] = self.fields[int(k)].serving_cell(x[on], y[on], t[on])
        return out

    def flyable(self, x: float, y: float) -> np.ndarray:
        """(L,) bool: the levels a UAV may fly at over ``(x, y)``."""
        every = np.arange(self.levels)
        return ~self.blocked(np.full(self.levels, x), np.full(self.levels, y), every)

    def blocked(self, x: Any, y: Any, level: Any) -> np.ndarray:
        """Whether the pixel holding ``(x, y)`` may not be entered on ``level``."""
        x, y, lv = np.broadcast_arrays(*(np.asarray(v) for v in (x, y, level)))
        out = np.zeros(x.shape, dtype=bool)
        for k in np.unique(lv):
            on = lv == k
            out[on] = blocked_at(self.fields[int(k)], x[on], y[on])
        return out


class LevelStepper:
    """Many UAVs among levels stepped at once (the module's rules), exactly as
    ``rainuav_core::planlevels`` replays a plan.

    State per UAV: ``start`` (N, 2), ``offset`` (N, 2) int steps in x and y, ``level`` (N,)
    and ``tick`` (N,) the clock; position = start + step_m * offset, time ``tick * move_s``.
    """

    def __init__(self, field: LevelField, cfg: NavConfig, climb: list[int], descend: list[int]):
        self.field, self.cfg = field, cfg
        top = field.levels - 1
        # Ticks of the climb and descent from each level (past the band: the last gap on
        # that side, one tick without one).
        self.up = np.array([climb[min(k, len(climb) - 1)] if climb else 1 for k in range(top + 1)])
        self.down = np.array([descend[max(k - 1, 0)] if descend else 1 for k in range(top + 1)])
        self.goal = np.asarray(cfg.goal_m, dtype=np.float64)

    def time_s(self, tick: Any) -> np.ndarray:
        """The instant after ``tick`` ticks, s (``0 + tick * move_s``, as the core)."""
        return 0.0 + np.asarray(tick).astype(np.float64) * self.cfg.move_s

    def step(
        self,
        start: np.ndarray,
        offset: np.ndarray,
        level: np.ndarray,
        tick: np.ndarray,
        action: np.ndarray,
    ) -> dict[str, np.ndarray]:
        """One move for every UAV: new ``offset``, ``level``, ``tick``, ``position``
        (clamped), ``reward``, ``terminated``, ``truncated``, ``signal_db``, ``out``,
        ``arrived``, ``duration`` (ticks) and ``t_s`` (the landing instant)."""
        cfg, f = self.cfg, self.field
        a = np.asarray(action, dtype=np.int64)
        level = np.asarray(level, dtype=np.int64)
        flat = a < 4
        vert_up, vert_down = a == 4, a == 5
        new_off = offset + np.where(flat[:, None], MOVES[np.minimum(a, 3)], 0)
        dest = level + vert_up.astype(np.int64) - vert_down.astype(np.int64)
        band = (dest >= 0) & (dest < f.levels)
        new_level = np.where(band, dest, level)
        duration = np.where(vert_up, self.up[level], np.where(vert_down, self.down[level], 1))
        x0, x1, y0, y1 = f.extent
        q = start + cfg.step_m * new_off
        out = (q[:, 0] < x0) | (q[:, 0] > x1) | (q[:, 1] < y0) | (q[:, 1] > y1)
        qc = np.stack([np.clip(q[:, 0], x0, x1), np.clip(q[:, 1], y0, y1)], axis=1)
        out |= f.blocked(qc[:, 0], qc[:, 1], new_level) | ~band
        new_tick = tick + duration
        t_s = self.time_s(new_tick)
        signal = f(qc[:, 0], qc[:, 1], t_s, new_level)
        b = base_reward(signal, cfg)
        b = np.where(flat, b, duration * b)  # a vertical move: its duration times b
        arrived = (
            flat & ~out & (np.hypot(q[:, 0] - self.goal[0], q[:, 1] - self.goal[1]) <= cfg.tol_m)
        )
        reward = (
            b
            - np.where(out, cfg.out_of_bounds_penalty, 0.0)
            + np.where(arrived, cfg.goal_reward, 0.0)
        )
        terminated = out | arrived
        return {
            "offset": new_off,
            "level": new_level,
            "tick": new_tick,
            "position": qc,
            "reward": reward,
            "terminated": terminated,
            "truncated": ~terminated & (new_tick >= cfg.max_steps),
            "signal_db": signal,
            "out": out,
            "arrived": arrived,
            "duration": duration,
            "t_s": t_s,
        }


class UAVLevelsEnv(gym.Env):
    """UAV navigation with altitude as a decision (module docstring): ``Discrete(6)``."""

    metadata = {"render_modes": []}  # noqa: RUF012 - gymnasium's convention
    view = None
    """The position observation only (no weather view, as ``UAVNavEnv``'s ``view``)."""
    random_goal = False
    """The task's one destination (as ``UAVNavEnv``'s ``random_goal``)."""

    def __init__(
        self,
        field: LevelField,
        config: NavConfig | None = None,
        *,
        climb_m_s: float = CLIMB_M_S,
        descend_m_s: float = DESCEND_M_S,
        start_level: int | None = None,
    ) -> None:
        """The levels' ``field`` and the task ``config`` (``min_db`` None: 10 dB or the
        caller's); ``start_level``: where every flight starts (default: the lowest level
        flyable at the start)."""
        super().__init__()
        if not isinstance(field, LevelField):
            raise InvalidInputError(f"field must be a LevelField (got {type(field).__name__})")
        cfg = config or NavConfig()
        self.cfg = dataclasses.replace(
            cfg, min_db=DEFAULT_MIN_DB if cfg.min_db is None else cfg.min_db
        )
        check_config(self.cfg, field.extent)
        self.field = field
        self.climb, self.descend = level_durations(
            field.altitudes_m, self.cfg, climb_m_s, descend_m_s
        )
        self.climb_m_s, self.descend_m_s = float(climb_m_s), float(descend_m_s)
        if start_level is not None and not (
            isinstance(start_level, int | np.integer) and 0 <= start_level < field.levels
        ):
            raise InvalidInputError(
                f"start_level must be an integer in 0..{field.levels - 1} (got {start_level!r})"
            )
        self.start_level = start_level
        self.stepper = LevelStepper(field, self.cfg, self.climb, self.descend)
        dims = 4 if field.varies else 3
        self.observation_space = gym.spaces.Box(0.0, 1.0, shape=(dims,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(LEVEL_ACTIONS)
        self._start = np.zeros((1, 2))
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._level = np.zeros(1, dtype=np.int64)
        self._tick = np.zeros(1, dtype=np.int64)
        self._pos = np.zeros(2)
        self._ready = False

    def observe(self, pos: Any, level: Any, tick: Any = 0) -> np.ndarray:
        """Position scaled to [0, 1]^2, the level over the highest index, and where the
        signal moves the clock over ``max_steps`` (float32; works on batches)."""
        x0, x1, y0, y1 = self.field.extent
        p = np.asarray(pos, dtype=np.float64)
        xy = (p - np.array([x0, y0])) / np.array([x1 - x0, y1 - y0])
        top = max(self.field.levels - 1, 1)
        parts = [xy, (np.asarray(level, dtype=np.float64) / top)[..., None]]
        if self.field.varies:
            parts.append((np.asarray(tick, dtype=np.float64) / self.cfg.max_steps)[..., None])
        lead = np.broadcast_shapes(*(q.shape[:-1] for q in parts))
        return np.concatenate([np.broadcast_to(q, (*lead, q.shape[-1])) for q in parts], -1).astype(
            np.float32
        )

    def lowest_flyable(self, x: float, y: float) -> int:
        """The lowest level the UAV may fly at over ``(x, y)``."""
        ok = self.field.flyable(x, y)
        if not ok.any():
            raise InvalidInputError(f"({x:g}, {y:g}) is not flyable at any level")
        return int(np.flatnonzero(ok)[0])

    def sample_start(self, rng: np.random.Generator) -> np.ndarray:
        """Uniform in the area, farther than ``tol_m`` from the destination and flyable at
        some level."""
        x0, x1, y0, y1 = self.field.extent
        g = np.asarray(self.cfg.goal_m)
        for _ in range(100_000):
            p = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
            if np.hypot(*(p - g)) > self.cfg.tol_m and self.field.flyable(*p).any():
                return p
        raise InvalidInputError(
            f"no flyable start farther than tol_m = {self.cfg.tol_m} m "
            f"from the destination in the area {self.field.extent}"
        )

    def start_level_at(self, p: Any) -> int:
        """The level a flight from ``p`` starts at: ``start_level`` where given, else the
        lowest flyable there."""
        if self.start_level is not None:
            return int(self.start_level)
        return self.lowest_flyable(float(p[0]), float(p[1]))

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        opts = options or {}
        x0, x1, y0, y1 = self.field.extent
        p = opts.get("start_m", self.cfg.start_m)
        if p is None:
            p = self.sample_start(self.np_random)
        p = as_real_array("options['start_m']", p)
        if p.shape != (2,) or not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
            raise InvalidInputError(
                f"options['start_m'] must be (x, y) inside the area (got {p!r})"
            )
        level = opts.get("start_level")
        if level is None:
            level = self.start_level_at(p)
        if not (isinstance(level, int | np.integer) and 0 <= level < self.field.levels):
            raise InvalidInputError(
                f"options['start_level'] must be an integer in 0..{self.field.levels - 1}"
            )
        if self.field.blocked(p[0], p[1], level):
            raise InvalidInputError(
                f"the start ({p[0]:g}, {p[1]:g}) is not flyable at level {level} "
                f"({self.field.altitudes_m[level]:g} m); the lowest it may be flown at is level "
                f"{self.lowest_flyable(p[0], p[1])}"
            )
        self._start = p[None].copy()
        self._offset = np.zeros((1, 2), dtype=np.int64)
        self._level = np.array([int(level)])
        self._tick = np.zeros(1, dtype=np.int64)
        self._pos = p.copy()
        self._ready = True
        signal = float(self.field(p[0], p[1], 0.0, int(level)))
        return self.observe(p, level, 0), self._info(signal)

    def _info(self, signal: float, arrived: bool = False) -> dict[str, Any]:
        assert self.cfg.min_db is not None
        t_s = float(self.stepper.time_s(self._tick)[0])
        lv = int(self._level[0])
        return {
            "signal_db": signal,
            "serving_cell": int(self.field.serving_cell(self._pos[0], self._pos[1], t_s, lv)),
            "position_m": self._pos.copy(),
            "level": lv,
            "altitude_m": float(self.field.altitudes_m[lv]),
            "outage": bool(signal < self.cfg.min_db),
            "arrived": arrived,
            "t_s": t_s,
        }

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        ok = isinstance(action, int | np.integer) and not isinstance(action, bool)
        if isinstance(action, np.ndarray) and action.shape == () and action.dtype.kind in "iu":
            action, ok = int(action), True
        if not ok or not 0 <= int(action) < LEVEL_ACTIONS:
            raise InvalidInputError(f"action must be one integer in 0..5 (got {action!r})")
        if not self._ready:
            raise InvalidInputError("step() before reset(): call reset() to start an episode")
        r = self.stepper.step(self._start, self._offset, self._level, self._tick,
                              np.array([int(action)]))  # fmt: skip
        self._offset, self._level, self._tick = r["offset"], r["level"], r["tick"]
        self._pos = r["position"][0].copy()
        return (
            self.observe(self._pos, self._level[0], self._tick[0]),
            float(r["reward"][0]),
            bool(r["terminated"][0]),
            bool(r["truncated"][0]),
            self._info(float(r["signal_db"][0]), bool(r["arrived"][0])),
        )
