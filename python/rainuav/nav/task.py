"""The navigation task: its configuration, moves and rewards ([physics reference, section
6][6-the-navigation-task]).

- Actions: 0 = +x, 1 = +y, 2 = -x, 3 = -y, each one ``step_m`` long.
- The signal S is the map's SINR (``signal="sinr"``, default) or SIR (``"sir"``, the
  paper's), in dB; ``min_db`` is the outage threshold.
- A move ``q' = q + step_m e_a`` earns ``b(q')``: ``"shortfall"`` (default)
  ``-1 - mu max(0, min_db - S)``, ``"outage"`` ``-1 - mu [S < min_db]`` or
  ``"linear"`` ``-1 + mu 10^(S/10)`` (the paper's literal form: it pays to loiter near a base
  station), or ``"chance"`` ``-1 - mu P``, ``P`` the probability of outage at ``q'`` on a map known
  with uncertainty (the ``"outage"`` reward's expectation; the field must carry ``outage_p``: a
  map corrected by measurements, through ``rainuav.world.world_from``). Leaving the area (a
  coordinate beyond the bounds): ``b(clamp(q')) - out_of_bounds_penalty``, terminated, the UAV
  stays at ``clamp(q')``. Reaching the goal (``|q' - goal| <= tol_m``): ``b(q') +
  goal_reward``, terminated. Truncated after ``max_steps`` steps (unless terminated on that
  step).
- Time: each move takes ``step_m / speed_m_s`` seconds, and the signal it earns is the field's at
  the new position and the instant the move ends ([`rainuav.nav.field`][rainuav.nav.field]; a single
  map does not change in time, so time changes nothing there).
- A flight's **cost** is its return without the arrival reward, negated: the moves plus the
  weighted shortfall ([physics reference, section 6][6-the-navigation-task],
  [`flight_cost()`][rainuav.nav.task.flight_cost]).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.signals import SIGNALS

__all__ = [
    "MAX_STEPS",
    "MOVES",
    "REWARDS",
    "SIGNALS",
    "LoiteringWarning",
    "NavConfig",
    "base_reward",
    "check_action",
    "check_config",
    "check_task",
    "flight_cost",
    "make_config",
]

REWARDS = ("shortfall", "outage", "linear", "chance")
#: Unit steps of the four actions: +x, +y, -x, -y.
MOVES = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]], dtype=np.int64)


class LoiteringWarning(UserWarning):
    """The 'linear' reward pays the UAV to hover near a base station."""


MAX_STEPS = 100_000
"""The most moves an episode may last (the exact planner's bound too: one range for every
command, checked where the task is read)."""


@dataclass
class NavConfig:
    """The navigation task (defaults: the paper's Table I and [physics reference, section
    6][6-the-navigation-task]): the one place its settings live. The environment owns it; a world
    spec holds it as ``task`` (the ``[task]`` table of a run's ``config.toml``, the flags
    ``--task.NAME`` of ``rainuav.train``)."""

    goal_m: tuple[float, float] = (1400.0, 1600.0)
    """Destination, m."""
    step_m: float = 10.0
    """Length of one move, m."""
    tol_m: float = 10.0
    """Arrival tolerance D_tol, m."""
    max_steps: int = 300
    """Episode length limit."""
    mu: float = 10.0 / 43.0
    """Weight of the signal term."""
    reward: str = "shortfall"
    """'shortfall', 'outage', 'linear' or 'chance' (module docstring)."""
    signal: str = "sinr"
    """Which map the task flies on: 'sinr' or 'sir' (the paper's)."""
    min_db: float | None = None
    """Outage threshold of the signal, dB. None: the map's default (a preset's documented SINR
    threshold, 10 dB for SIR and for maps of no preset); the environment resolves it."""
    goal_reward: float = 2000.0
    """R_des, paid on arrival."""
    out_of_bounds_penalty: float = 10000.0
    """P_ob, charged on leaving the area."""
    start_m: tuple[float, float] | None = None
    """Fixed start (None: uniform in the area, farther than tol_m from the goal)."""
    speed_m_s: float = 10.0
    """Ground speed, m/s: a move takes step_m / speed_m_s seconds."""

    def __post_init__(self) -> None:
        # A point read from a file or a flag comes as a list: held as a tuple of floats, so that
        # tasks compare equal whatever they were read from (a bad value is left for the checks).
        for name in ("goal_m", "start_m"):
            v = getattr(self, name)
            if isinstance(v, list | tuple | np.ndarray) and all(
                isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool)
                for x in v
            ):
                setattr(self, name, tuple(float(x) for x in v))

    @property
    def move_s(self) -> float:
        """Duration of one move, s."""
        return self.step_m / self.speed_m_s


def check_task(cfg: NavConfig, prefix: str = "") -> None:
    """Checks a task's fields, whatever the map.

    The area's bounds are checked by [`check_config()`][rainuav.nav.task.check_config].

    Args:
        cfg: The task.
        prefix: What the error puts before a field's name (e.g. "task.").

    Raises:
        InvalidInputError: The first field of the wrong kind or out of its range, named.
    """
    for name in ("goal_m", "start_m"):
        v = getattr(cfg, name)
        if name == "start_m" and v is None:
            continue
        if not (isinstance(v, tuple) and len(v) == 2 and all(math.isfinite(x) for x in v)):
            raise InvalidInputError(f"{prefix}{name} must be two finite numbers, m (got {v!r})")
    for name in ("step_m", "tol_m", "speed_m_s"):
        v = getattr(cfg, name)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise InvalidInputError(f"{prefix}{name} must be finite and > 0 (got {v!r})")
    if not (
        isinstance(cfg.max_steps, (int, np.integer))
        and not isinstance(cfg.max_steps, bool)
        and 1 <= cfg.max_steps <= MAX_STEPS
    ):
        v = cfg.max_steps
        raise InvalidInputError(f"{prefix}max_steps must be within 1..{MAX_STEPS} (got {v!r})")
    for name in ("mu", "min_db", "goal_reward", "out_of_bounds_penalty"):
        v = getattr(cfg, name)
        if name == "min_db" and v is None:
            continue
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)):
            raise InvalidInputError(f"{prefix}{name} must be a finite number (got {v!r})")
    if cfg.reward not in REWARDS:
        raise InvalidInputError(f"{prefix}reward must be one of {REWARDS} (got {cfg.reward!r})")
    if cfg.signal not in SIGNALS:
        raise InvalidInputError(f"{prefix}signal must be one of {SIGNALS} (got {cfg.signal!r})")


def check_config(
    cfg: NavConfig, extent: tuple[float, float, float, float], prefix: str = ""
) -> None:
    """Checks a task for a map over an area: its fields, then its points inside the area.

    Args:
        cfg: The task.
        extent: The map's `(x_min, x_max, y_min, y_max)`, m.
        prefix: What the error puts before a field's name (e.g. "task.").

    Raises:
        InvalidInputError: The first field out of range, named (a destination or start outside the
            area among them).
    """
    x0, x1, y0, y1 = extent
    check_task(cfg, prefix)
    g = cfg.goal_m
    if not (x0 <= g[0] <= x1 and y0 <= g[1] <= y1):
        raise InvalidInputError(
            f"{prefix}goal_m must lie inside the area {extent} (got {cfg.goal_m!r})"
        )
    if cfg.start_m is not None:
        s = cfg.start_m
        if not (x0 <= s[0] <= x1 and y0 <= s[1] <= y1):
            raise InvalidInputError(f"{prefix}start_m must lie inside the area (got {s!r})")


def base_reward(
    signal_db: npt.ArrayLike, cfg: NavConfig, outage_p: npt.ArrayLike | None = None
) -> Any:
    """The reward term b(q') of a move, from the signal where it lands.

    Args:
        signal_db: The signal (SINR or SIR, dB) at the new position.
        cfg: The task; its `min_db` must be resolved (not None).
        outage_p: For the reward "chance", the probability of outage there.

    Returns:
        b(q'), of the shape of `signal_db`: the shortfall below `min_db`, the outage indicator, the
        outage probability or the linear reward, as `cfg.reward` names ([physics reference, section
        6][6-the-navigation-task]).

    Raises:
        InvalidInputError: `min_db` unresolved, or the reward "chance" without `outage_p`.
    """
    if cfg.min_db is None:
        raise InvalidInputError("min_db is unresolved: build the task through UAVNavEnv")
    if cfg.reward == "chance":
        if outage_p is None:
            raise InvalidInputError("reward 'chance' needs the outage probability (outage_p)")
        return -1.0 - cfg.mu * np.asarray(outage_p, dtype=np.float64)
    if cfg.reward == "shortfall":
        return -1.0 - cfg.mu * np.maximum(0.0, cfg.min_db - signal_db)
    if cfg.reward == "outage":
        return -1.0 - cfg.mu * (signal_db < cfg.min_db)
    return -1.0 + cfg.mu * 10.0 ** (signal_db / 10.0)


def flight_cost(returns: npt.ArrayLike, arrived: npt.ArrayLike, cfg: NavConfig) -> Any:
    """The cost of flights: the return without the arrival reward, negated.

    Moves plus the weighted shortfall ([physics reference, section 6][6-the-navigation-task]).
    Meaningful for flights that arrived (a flight that left the area also pays
    `out_of_bounds_penalty`).

    Args:
        returns: The flights' undiscounted returns.
        arrived: Whether each arrived.
        cfg: The task.

    Returns:
        The costs, of the shape of `returns`.
    """
    return -(np.asarray(returns, dtype=np.float64) - cfg.goal_reward * np.asarray(arrived))


def make_config(base: NavConfig | None = None, **kw: Any) -> NavConfig:
    """A task from keywords, over a base task's fields.

    Args:
        base: The task whose fields the keywords replace; None: the defaults.
        **kw: Fields of [`NavConfig`][rainuav.nav.task.NavConfig], by name.

    Returns:
        The new [`NavConfig`][rainuav.nav.task.NavConfig].

    Raises:
        InvalidInputError: An unknown field name.
    """
    names = {f.name for f in dataclasses.fields(NavConfig)}
    bad = set(kw) - names
    if bad:
        raise InvalidInputError(f"unknown NavConfig field(s) {sorted(bad)}")
    return dataclasses.replace(base if base is not None else NavConfig(), **kw)


def check_action(action: Any, n: int = 4) -> int:
    """An action as an int, if it is one integer of the action space.

    A Python or numpy integer, or a 0-d integer array, is taken as Gymnasium's `Discrete(n)` holds
    it; anything else is refused, never silently rounded.

    Args:
        action: The action given.
        n: The number of actions (4 on one level, 6 among levels).

    Returns:
        The action, in `0..n-1`.

    Raises:
        InvalidInputError: A float such as 1.7, a string, a bool, or an integer out of range.
    """
    a = np.asarray(action) if isinstance(action, np.ndarray) else action
    if isinstance(a, np.ndarray):
        ok = a.shape == () and np.issubdtype(a.dtype, np.integer)
        a = a[()] if ok else a
    else:
        ok = isinstance(a, int | np.integer) and not isinstance(a, bool)
    if not ok or not 0 <= int(a) < n:
        allowed = "0, 1, 2 or 3" if n == 4 else f"in 0..{n - 1}"
        raise InvalidInputError(f"action must be one integer {allowed} (got {action!r})")
    return int(a)
