"""The stepping rules among flight levels, and the field of a signal or of a radio map.

The task among levels is in [`rainuav.nav.levels`][rainuav.nav.levels]; the levels' signal is a
[`SignalField`][rainuav.nav.field.SignalField] with a level axis.
[`level_durations()`][rainuav.nav.levelfield.level_durations]: how long a climb and a descent
last; [`LevelStepper`][rainuav.nav.levelfield.LevelStepper]: many UAVs moved at once, as the exact
planner replays a plan; [`field_of()`][rainuav.nav.levelfield.field_of]: the field of a signal;
[`signal_field()`][rainuav.nav.levelfield.signal_field]: the field of a radio map."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.nav.field import SignalField
from rainuav.nav.task import MOVES, SIGNALS, NavConfig, base_reward
from rainuav.signals import Signal

__all__ = [
    "CLIMB_M_S",
    "DESCEND_M_S",
    "LEVEL_ACTIONS",
    "LevelStepper",
    "field_of",
    "level_durations",
    "signal_field",
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
    """How long each climb and each descent between neighbouring levels lasts, in ticks of the
    clock.

    A tick is one horizontal move, `cfg.move_s`: the gap over the climb or descent speed, rounded up
    to whole moves (at least one). With the defaults, 15 m gaps and 1 s moves: 3 and 5 exactly.

    Args:
        altitudes_m: The levels, m, increasing.
        cfg: The task.
        climb_m_s: The climb speed, m/s.
        descend_m_s: The descent speed, m/s.

    Returns:
        `(climbs, descents)`, one a gap, lowest first.

    Raises:
        InvalidInputError: A speed outside 0.1-100 m/s.
    """
    gaps = np.diff(np.asarray(altitudes_m, dtype=np.float64))
    for name, v in (("climb_m_s", climb_m_s), ("descend_m_s", descend_m_s)):
        if not (np.isfinite(v) and 0.1 <= v <= 100.0):
            raise InvalidInputError(f"{name} must be in 0.1..100 m/s (got {v!r})")
    move = cfg.move_s

    def ticks(speed: float) -> list[int]:
        # 1e-9 absorbs the rounding of a gap that is a whole number of moves.
        return [max(1, math.ceil(g / speed / move - 1e-9)) for g in gaps]

    return ticks(climb_m_s), ticks(descend_m_s)


class LevelStepper:
    """Many UAVs among levels stepped at once (the module's rules), exactly as
    ``rainuav_core::planning::planlevels`` replays a plan: the one batched stepper (the plane's,
    [`rainuav.nav.batch.BatchStepper`][rainuav.nav.batch.BatchStepper], is this one over its
    single level). It reads a [`SignalField`][rainuav.nav.field.SignalField] (``extent``,
    ``levels``, ``blocked(x, y, level)``, ``field(x, y, t_s, world, level)``).

    State per UAV: ``start`` (N, 2), ``offset`` (N, 2) int steps in x and y, ``level`` (N,)
    and ``tick`` (N,) the clock; position = start + step_m * offset, time ``tick * move_s``.
    """

    def __init__(self, field: SignalField, cfg: NavConfig, climb: list[int], descend: list[int]):
        """Builds the stepper over a field and a task.

        Args:
            field: The signal flown.
            cfg: The navigation task (its `min_db` resolved).
            climb: The climb across each gap between neighbouring levels, lowest first, in ticks
                ([`level_durations()`][rainuav.nav.levelfield.level_durations]; []: one tick).
            descend: The descent across each gap, lowest first, in ticks ([]: one tick).
        """
        self.field, self.cfg = field, cfg
        top = field.levels - 1
        # Ticks of the climb and descent from each level (past the band: the last gap on
        # that side, one tick without one).
        self.up = np.array([climb[min(k, len(climb) - 1)] if climb else 1 for k in range(top + 1)])
        self.down = np.array([descend[max(k - 1, 0)] if descend else 1 for k in range(top + 1)])
        self.goal = np.asarray(cfg.goal_m, dtype=np.float64)

    def time_s(self, tick: npt.ArrayLike) -> np.ndarray:
        """The instant after some ticks, s (`0 + tick * move_s`, as the core).

        Args:
            tick: Ticks.

        Returns:
            Times, s, of the shape of `tick`.
        """
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
        """One move for every UAV.

        Args:
            start: Each UAV's start (N, 2), m.
            offset: Its whole moves from the start (N, 2) in x and y.
            level: Its level (N,).
            tick: Its clock (N,), ticks.
            action: Its move (N,).
            goal: Its destination (N, 2); None: the task's.
            world: In a bank, the world it flies (N,).

        Returns:
            Arrays (N,) or (N, 2): the new `offset`, `level`, `tick`, `position` (clamped),
            `reward`, `terminated`, `truncated`, `signal_db`, `out`, `arrived`, `duration` (ticks)
            and `t_s` (the landing instant).
        """
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
        signal = f(qc[:, 0], qc[:, 1], t_s, world, level=new_level)
        chance = None
        if cfg.reward == "chance":  # the probability of outage where the move ends
            chance = np.asarray(f.chance(qc[:, 0], qc[:, 1], t_s))
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


def field_of(signal: Signal, *, levels: bool = False) -> SignalField:
    """The field the environment and the planner read of one signal, by its axes' sizes.

    One level gives a map, maps in time or, with several worlds, a bank; several levels give the
    same with a level axis and `altitudes_m`. The values are the signal's, bit for bit; a bank flies
    over open ground.

    Args:
        signal: The [`Signal`][rainuav.signals.Signal].
        levels: A field among levels whatever the number of levels (a band of one level is flown
            with six moves).

    Returns:
        The [`SignalField`][rainuav.nav.field.SignalField].

    Raises:
        InvalidInputError: Not a signal, or a signal of several worlds with a closed pixel.
    """
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
            return SignalField.bank(v, t_s, signal.extent_m, signal.altitudes_m)
        return SignalField.bank(v[:, :, 0], t_s, signal.extent_m, name=name)
    if lv > 1 or levels:
        return SignalField.from_stack(
            v[0, 0] if t == 1 else v[0], signal.altitudes_m, signal.extent_m,
            t_s=None if t == 1 else t_s, not_flyable=mask,
            serving_cell=None if srv is None else (srv[0, 0] if t == 1 else srv[0]),
        )  # fmt: skip
    m = None if mask is None else mask[0]
    if t == 1:
        s = None if srv is None else srv[0, 0, 0]
        return SignalField(v[0, 0, 0], signal.extent_m, name, s, m)
    s = None if srv is None else srv[0, :, 0]
    return SignalField.series(v[0, :, 0], t_s, signal.extent_m, name, s, m)


def signal_field(
    radio_map: Any, sinr_db: npt.ArrayLike, sir_db: npt.ArrayLike, extent_m: Any, signal: str | None
) -> SignalField:
    """The field a task flies on: a map's signal, or the one raw array given.

    Args:
        radio_map: A built map of any kind or a [`Signal`][rainuav.signals.Signal] (each read
            through its `as_signal()`), or None.
        sinr_db: A raw SINR array (with `extent_m`), or None.
        sir_db: A raw SIR array (with `extent_m`), or None.
        extent_m: The raw array's `(x_min, x_max, y_min, y_max)`, m.
        signal: "sinr" or "sir"; None: the raw array's, or the SINR of a map.

    Returns:
        The [`SignalField`][rainuav.nav.field.SignalField].

    Raises:
        InvalidInputError: Neither or both of a map and an array, an array without its extent, or a
            signal the input does not hold.
    """
    if signal is not None and signal not in SIGNALS:
        raise InvalidInputError(f"signal must be one of {SIGNALS} (got {signal!r})")
    raw = {k: v for k, v in (("sinr", sinr_db), ("sir", sir_db)) if v is not None}
    if radio_map is not None:
        if raw:
            raise InvalidInputError(f"give radio_map or {next(iter(raw))}_db, not both")
        signal = signal or "sinr"
        as_signal = getattr(radio_map, "as_signal", None)
        if not callable(as_signal):
            raise InvalidInputError(
                "radio_map must be a built map (RadioMap, in time or of every level) or a Signal "
                f"(got {type(radio_map).__name__})"
            )
        return field_of(as_signal(signal, scenario_toml=False))  # every kind, by its axes
    if len(raw) != 1:
        raise InvalidInputError("give radio_map, or exactly one of sinr_db and sir_db")
    kind, values = next(iter(raw.items()))
    if signal is not None and signal != kind:
        raise InvalidInputError(f"signal={signal!r} but the map given is {kind}_db")
    if extent_m is None:
        raise InvalidInputError(f"extent_m is required with {kind}_db")
    return SignalField(values, extent_m, f"{kind}_db")
