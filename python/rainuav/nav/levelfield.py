"""The signal of every flight level and the stepping rules among levels (the task is in
[`rainuav.nav.levels`][rainuav.nav.levels]): [`LevelField`][rainuav.nav.levelfield.LevelField] (one
signal a level: maps, maps in time, or a bank of storms in time),
[`level_durations()`][rainuav.nav.levelfield.level_durations] (how long a climb and a descent last)
and [`LevelStepper`][rainuav.nav.levelfield.LevelStepper] (many UAVs moved at once, as the exact
planner replays a plan)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav._checks import as_real_array
from rainuav.errors import InvalidInputError
from rainuav.nav.field import SignalBank, SignalField, SignalSeries, blocked_at, read_signal
from rainuav.nav.task import MOVES, NavConfig, base_reward
from rainuav.signals import Signal

__all__ = [
    "CLIMB_M_S",
    "DESCEND_M_S",
    "LEVEL_ACTIONS",
    "LevelField",
    "LevelStepper",
    "field_of",
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
    """The signal of every level: one [`SignalField`][rainuav.nav.field.SignalField],
    [`SignalSeries`][rainuav.nav.field.SignalSeries] or [`SignalBank`][rainuav.nav.field.SignalBank]
    a level (all of one kind, over one area), lowest first, at ``altitudes_m``. A field of banks
    holds many storms' levels at once (a storm pool among levels): each UAV reads its own world's
    (``world``), and [`put()`][rainuav.nav.field.SignalField.put] renews one."""

    def __init__(
        self,
        fields: Sequence[SignalField],
        altitudes_m: npt.ArrayLike,
    ) -> None:
        alts = as_real_array("altitudes_m", altitudes_m).reshape(-1)
        if len(fields) != alts.size or alts.size == 0:
            raise InvalidInputError(
                f"altitudes_m must hold one altitude a level ({len(fields)} levels, got "
                f"{alts.size})"
            )
        if alts.size > 1 and not np.all(np.diff(alts) > 0):
            raise InvalidInputError(f"altitudes_m must increase (got {alts.tolist()})")
        if not all(isinstance(f, SignalField) for f in fields):
            raise InvalidInputError("fields must be SignalFields")
        kinds = {(f.banked, f.varies) for f in fields}
        if len(kinds) != 1:
            raise InvalidInputError(
                "fields must be all maps, all maps in time (SignalSeries) or all banks (SignalBank)"
            )
        if fields[0].banked and len({f.db.shape for f in fields}) != 1:
            raise InvalidInputError("the levels' banks must hold as many worlds and instants")
        if len({f.extent for f in fields}) != 1:
            raise InvalidInputError("the levels' fields must cover one area (one extent)")
        self.fields = tuple(fields)
        self.altitudes_m = alts
        self.extent = fields[0].extent
        self.varies = bool(fields[0].varies)
        self.banked = fields[0].banked

    @classmethod
    def bank(
        cls,
        stacks: npt.ArrayLike,
        t_s: npt.ArrayLike,
        extent_m: tuple[float, float, float, float],
        altitudes_m: npt.ArrayLike,
    ) -> LevelField:
        """Many worlds' levels in time: ``stacks`` (P, T, L, H, W), the P worlds' signal at
        every level at the instants ``t_s`` (T,) (flat open ground: no pixel closed)."""
        v = np.asarray(stacks, dtype=np.float64)
        if v.ndim != 5:
            raise InvalidInputError(f"stacks must be (P, T, L, H, W) (got {v.shape})")
        return cls([SignalBank(v[:, :, k], t_s, extent_m) for k in range(v.shape[2])],
                   altitudes_m)  # fmt: skip

    @property
    def worlds(self) -> int:
        """Worlds held (1 but for a field of banks)."""
        return self.fields[0].worlds

    def put(self, world: int, stack: npt.ArrayLike) -> None:
        """Replaces world ``world`` of a field of banks by ``stack`` (T, L, H, W)."""
        if not self.banked:
            raise InvalidInputError("put renews a world of a field of banks only")
        v = np.asarray(stack, dtype=np.float64)
        if v.ndim != 4 or v.shape[1] != self.levels:
            raise InvalidInputError(f"stack must be (T, {self.levels}, H, W) (got {v.shape})")
        for k, f in enumerate(self.fields):
            f.put(world, v[:, k])

    def at_points(self, points: np.ndarray, t_s: Any, world: Any) -> np.ndarray:
        """(N, L, M): every level's signal at the fixed points (M, 2), UAV n at ``t_s[n]``
        in world ``world[n]`` (each slice sampled once per set of points)."""
        return np.stack([f.at_points(points, t_s, world) for f in self.fields], axis=1)

    def every_level(self, x: Any, y: Any, t_s: Any, world: Any = None) -> np.ndarray:
        """(N, L, M): every level's signal at the points ``(x, y)`` (N, M), row n at
        ``t_s[n]`` (N, 1) in world ``world[n]`` (N, 1; a field of banks)."""
        return np.stack([read_signal(f, x, y, t_s, world) for f in self.fields], axis=1)

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
        fields: list[SignalField] = []
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

    def __call__(self, x: Any, y: Any, t_s: Any, level: Any, world: Any = 0) -> np.ndarray:
        """The signal at ``(x, y)`` on ``level`` at ``t_s`` (in a field of banks, of world
        ``world``; arrays of one shape, or numbers)."""
        x, y, t, lv, w = np.broadcast_arrays(*(np.asarray(v) for v in (x, y, t_s, level, world)))
        out = np.empty(x.shape)
        for k in np.unique(lv):
            on = lv == k
            out[on] = read_signal(self.fields[int(k)], x[on], y[on], t[on], w[on])
        return out

    def serving_cell(self, x: Any, y: Any, t_s: Any, level: Any) -> np.ndarray:
        """The serving cell at ``(x, y)`` on ``level`` at ``t_s`` (-1 where none is named)."""
        x, y, t, lv = np.broadcast_arrays(*(np.asarray(v) for v in (x, y, t_s, level)))
        out = np.full(x.shape, -1, dtype=np.int64)
        for k in np.unique(lv):
            on = lv == k
            serving = getattr(self.fields[int(k)], "serving_cell", None)
            if callable(serving):
                out[on] = serving(x[on], y[on], t[on])
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
    ``rainuav_core::planlevels`` replays a plan: the one batched stepper (the plane's,
    [`rainuav.nav.batch.BatchStepper`][rainuav.nav.batch.BatchStepper], is this one over its
    single level). The field it reads has ``extent``, ``levels``, ``blocked(x, y, level)`` and
    is called ``field(x, y, t_s, level[, world])``.

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
        goal: np.ndarray | None = None,
        world: np.ndarray | None = None,
    ) -> dict[str, np.ndarray]:
        """One move for every UAV: new ``offset``, ``level``, ``tick``, ``position``
        (clamped), ``reward``, ``terminated``, ``truncated``, ``signal_db``, ``out``,
        ``arrived``, ``duration`` (ticks) and ``t_s`` (the landing instant). ``goal``
        (N, 2): each UAV's destination (default the task's); ``world`` (N,): in a field of
        banks, the world each UAV flies."""
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
        if world is None:
            signal = f(qc[:, 0], qc[:, 1], t_s, new_level)
        else:
            signal = f(qc[:, 0], qc[:, 1], t_s, new_level, world)
        chance = None
        if cfg.reward == "chance":  # the probability of outage where the move ends
            if not hasattr(f, "chance"):
                raise InvalidInputError("reward 'chance' flies one map with outage_p")
            chance = f.chance(
                qc[:, 0], qc[:, 1], t_s, new_level, *([] if world is None else [world])
            )
        base = base_reward(signal, cfg, chance)
        b = np.where(flat, base, duration * base)  # a vertical move: its duration times b
        g = self.goal[None] if goal is None else np.asarray(goal, dtype=np.float64)
        arrived = flat & ~out & (np.hypot(q[:, 0] - g[:, 0], q[:, 1] - g[:, 1]) <= cfg.tol_m)
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
            "base": base,
            "out": out,
            "arrived": arrived,
            "duration": duration,
            "t_s": t_s,
        }


def field_of(signal: Signal, *, levels: bool = False) -> SignalField | LevelField:
    """The field the environment and the planner read of one signal, by its axes' sizes.

    For a [`Signal`][rainuav.signals.Signal], one level gives a map
    ([`SignalField`][rainuav.nav.field.SignalField]), maps in time
    ([`SignalSeries`][rainuav.nav.field.SignalSeries]) or, with several worlds, a bank
    ([`SignalBank`][rainuav.nav.field.SignalBank]); several levels give a
    [`LevelField`][rainuav.nav.levelfield.LevelField] of those (``levels=True``: whatever their
    number, a band of one level flown with six moves). The values are the signal's, bit for bit.
    A bank flies over open ground: a signal of several worlds with a closed pixel is refused."""
    if not isinstance(signal, Signal):
        raise InvalidInputError(f"signal must be a rainuav.signals.Signal (got {type(signal)})")
    v, name, mask, srv = signal.values, signal.name, signal.not_flyable, signal.serving_cell
    p, t, lv = v.shape[:3]
    t_s = signal.t_s
    if p > 1:
        if mask is not None and mask.any():
            raise InvalidInputError(
                "not_flyable: a signal of several worlds (a bank of storms) flies over open "
                "ground, with no pixel closed"
            )
        if lv > 1 or levels:
            return LevelField.bank(v, t_s, signal.extent_m, signal.altitudes_m)
        return SignalBank(v[:, :, 0], t_s, signal.extent_m, name)
    if lv > 1 or levels:
        return LevelField.from_stack(
            v[0, 0] if t == 1 else v[0], signal.altitudes_m, signal.extent_m,
            t_s=None if t == 1 else t_s, not_flyable=mask,
            serving_cell=None if srv is None else (srv[0, 0] if t == 1 else srv[0]),
        )  # fmt: skip
    m = None if mask is None else mask[0]
    if t == 1:
        s = None if srv is None else srv[0, 0, 0]
        return SignalField(v[0, 0, 0], signal.extent_m, name, s, m)
    s = None if srv is None else srv[0, :, 0]
    return SignalSeries(v[0, :, 0], t_s, signal.extent_m, name, s, m)
