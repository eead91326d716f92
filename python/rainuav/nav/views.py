"""What a UAV that reads the weather sees, and where its destinations come from.

[`WeatherView`][rainuav.nav.views.WeatherView] is the observation of a policy that flies any storm
it is shown (``UAVNavEnv(observation="weather")``): a Gymnasium ``Dict`` of

- ``position``, ``goal``: the UAV's position and its destination, scaled to [0, 1]^2;
- ``time``: the moves so far over ``max_steps``;
- ``level`` (among flight levels only, ``layers`` > 1): the UAV's level over the highest
  level's index;
- ``local``: the signal now on a ``window`` x ``window`` grid centred on the UAV,
  ``window_step_m`` apart (11 x 11 at 40 m by default: 200 m each way, 20 moves);
- ``area``: the signal now at the centres of an ``area`` x ``area`` grid over the whole area
  (16 x 16: 125 m cells), where the route's big detours are decided.

Among flight levels ([`rainuav.nav.levels`][rainuav.nav.levels]) the two grids have one layer a
level, lowest first (``layers``): the UAV sees the signal at every height around it and over the
area.

Signal values enter as ``tanh((S - min_db) / scale_db)`` (0 at the outage threshold, +-0.76
10 dB either side), so every storm and every map reads on one scale. "Now" is the instant of
the UAV's last move: the weather as an operator with a radar would know it; the network is not
shown the future. Grid points beyond the area read the edge values, as the field does.

Destinations ([`sample_goal()`][rainuav.nav.views.sample_goal]): uniform in the area shrunk by
[`GOAL_MARGIN_M`][rainuav.nav.views.GOAL_MARGIN_M] on every side; the start then uniform in the
area, farther than ``tol_m`` from the destination and at most [`REACH`][rainuav.nav.views.REACH] of
the horizon away (lattice moves), so every flight can arrive in time."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.nav.task import NavConfig

__all__ = ["GOAL_MARGIN_M", "REACH", "WeatherView", "sample_goal", "sample_start_for"]

GOAL_MARGIN_M = 100.0
"""Random destinations keep this far from the area's edges, m."""
REACH = 0.75
"""A start for a random destination is at most this share of the horizon's moves away."""
KEYS = ("position", "goal", "time", "level", "local", "area")
"""The observation's parts, in the order the flat encoding concatenates them (``level``
only among levels)."""


@dataclass(frozen=True)
class WeatherView:
    """The weather-reading observation (module docstring)."""

    window: int = 11
    """Side of the local grid, samples (odd: the UAV at its centre)."""
    window_step_m: float = 40.0
    """Spacing of the local grid, m."""
    area: int = 16
    """Side of the whole-area grid, samples."""
    scale_db: float = 10.0
    """Signal scale: a sample is tanh((S - min_db) / scale_db)."""
    layers: int = 1
    """Layers of the grids: 1 on one level, the number of flight levels among levels."""

    def __post_init__(self) -> None:
        if not (isinstance(self.window, int) and self.window >= 1 and self.window % 2 == 1):
            raise InvalidInputError(f"window must be an odd integer >= 1 (got {self.window!r})")
        if not (isinstance(self.area, int) and 1 <= self.area <= 256):
            raise InvalidInputError(f"area must be an integer in 1..256 (got {self.area!r})")
        if not (isinstance(self.layers, int) and 1 <= self.layers <= 64):
            raise InvalidInputError(f"layers must be an integer in 1..64 (got {self.layers!r})")
        for name in ("window_step_m", "scale_db"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and 0 < v < np.inf):
                raise InvalidInputError(f"{name} must be finite and > 0 (got {v!r})")

    @property
    def sizes(self) -> dict[str, int]:
        """Floats per part of the flat encoding ([`KEYS`][rainuav.nav.views.KEYS] order; ``level``
        among levels only)."""
        level = {"level": 1} if self.layers > 1 else {}
        n = self.layers
        return {"position": 2, "goal": 2, "time": 1, **level, "local": n * self.window**2,
                "area": n * self.area**2}  # fmt: skip

    @property
    def vector(self) -> int:
        """Floats of the flat encoding before the grids (position, goal, time, level)."""
        return 5 + int(self.layers > 1)

    def space(self) -> gym.spaces.Dict:
        """The Gymnasium observation space: a `Dict` of the view's parts.

        Returns:
            The space.
        """
        box, n = gym.spaces.Box, self.layers
        parts = {
            "position": box(0.0, 1.0, shape=(2,), dtype=np.float32),
            "goal": box(0.0, 1.0, shape=(2,), dtype=np.float32),
            "time": box(0.0, 1.0, shape=(1,), dtype=np.float32),
            "level": box(0.0, 1.0, shape=(1,), dtype=np.float32),
            "local": box(-1.0, 1.0, shape=(n, self.window, self.window), dtype=np.float32),
            "area": box(-1.0, 1.0, shape=(n, self.area, self.area), dtype=np.float32),
        }
        return gym.spaces.Dict({k: parts[k] for k in KEYS if k in self.sizes})

    def local_offsets(self) -> np.ndarray:
        """The offsets of the local grid from the UAV, m.

        Row i south to north, column j west to east, row-major; computed once per view.

        Returns:
            (window^2, 2), read-only.
        """
        return _local_offsets(self.window, self.window_step_m)

    def area_points(self, extent: tuple[float, float, float, float]) -> np.ndarray:
        """The centres of the whole-area grid's cells, m, row-major (south to north).

        Args:
            extent: The area, `(x_min, x_max, y_min, y_max)`, m.

        Returns:
            (area^2, 2), read-only (computed once per view and extent).
        """
        return _area_points(self.area, tuple(float(v) for v in extent))

    def observe(
        self,
        sample: Callable[[np.ndarray, np.ndarray], np.ndarray],
        extent: tuple[float, float, float, float],
        pos: np.ndarray,
        t_frac: np.ndarray,
        goal: np.ndarray,
        min_db: float,
        area_db: np.ndarray | None = None,
        level_frac: np.ndarray | None = None,
    ) -> dict[str, np.ndarray]:
        """The observations of N UAVs from a function that samples the signal.

        Args:
            sample: `sample(x, y)` gives the signal, dB, at points (N, M): row n is UAV n's world
                and instant ((N, layers, M) among levels, every level).
            extent: The area, `(x_min, x_max, y_min, y_max)`, m.
            pos: The UAVs' positions (N, 2), m.
            t_frac: Their time over the horizon (N,).
            goal: Their destinations (N, 2), m.
            min_db: The outage threshold, dB.
            area_db: The signal at [`area_points()`][rainuav.nav.views.WeatherView.area_points], (N,
                [layers,] area^2), where the caller has it (sampled once per map); None: sampled.
            level_frac: Among levels, each UAV's level over the highest index (N,).

        Returns:
            The observation's parts by [`KEYS`][rainuav.nav.views.KEYS], batched.

        Raises:
            InvalidInputError: A view of several levels without `level_frac`.
        """
        x0, x1, y0, y1 = extent
        lo, span = np.array([x0, y0]), np.array([x1 - x0, y1 - y0])
        pos = np.asarray(pos, dtype=np.float64).reshape(-1, 2)
        n = len(pos)
        off = self.local_offsets()
        x, y = pos[:, 0:1] + off[:, 0], pos[:, 1:2] + off[:, 1]
        if area_db is None:
            pts, a2 = self.area_points(extent), self.area**2
            x = np.concatenate([x, np.broadcast_to(pts[:, 0], (n, a2))], axis=1)
            y = np.concatenate([y, np.broadcast_to(pts[:, 1], (n, a2))], axis=1)
        nl = self.layers
        db = np.asarray(sample(x, y)).reshape(n, nl, -1)
        if area_db is not None:
            db = np.concatenate([db, np.asarray(area_db).reshape(n, nl, -1)], axis=2)
        s = np.tanh((db - min_db) / self.scale_db).astype(np.float32)
        w2 = self.window**2
        g = np.broadcast_to(np.asarray(goal, dtype=np.float64).reshape(-1, 2), (n, 2))
        obs = {
            "position": ((pos - lo) / span).astype(np.float32),
            "goal": ((g - lo) / span).astype(np.float32),
            "time": np.broadcast_to(np.asarray(t_frac, np.float32).reshape(-1, 1), (n, 1)).copy(),
            "local": s[:, :, :w2].reshape(n, nl, self.window, self.window),
            "area": s[:, :, w2:].reshape(n, nl, self.area, self.area),
        }
        if nl > 1:
            if level_frac is None:
                raise InvalidInputError("a view of several levels needs level_frac")
            lv = np.asarray(level_frac, np.float32).reshape(-1, 1)
            obs["level"] = np.broadcast_to(lv, (n, 1)).copy()
        return obs

    def observe_field(
        self,
        field: Any,
        t_s: np.ndarray,
        pos: npt.ArrayLike,
        level: npt.ArrayLike,
        t: npt.ArrayLike,
        goal: npt.ArrayLike,
        world: npt.ArrayLike,
        min_db: float,
        max_steps: int,
    ) -> dict[str, np.ndarray]:
        """The observations of UAVs flying a field
        ([`observe()`][rainuav.nav.views.WeatherView.observe]).

        Among levels, the field's levels are the view's layers.

        Args:
            field: The [`SignalField`][rainuav.nav.field.SignalField].
            t_s: The UAVs' instants (N,), s.
            pos: Their positions (N, 2), or one UAV's (2,), m.
            level: Their levels.
            t: Their clocks, in ticks.
            goal: Their destinations (N, 2), m.
            world: Their worlds in a bank; None: world 0.
            min_db: The outage threshold, dB.
            max_steps: The horizon, in moves.

        Returns:
            The observation's parts, batched (one UAV's for a (2,) position).
        """
        p = np.asarray(pos, dtype=np.float64)
        one = p.ndim == 1
        p = p.reshape(-1, 2)
        n = len(p)
        ts = np.asarray(t_s, dtype=np.float64).reshape(n, 1)
        w = np.broadcast_to(np.asarray(0 if world is None else world), (n,))[:, None]
        lv = None
        if field.altitudes_m is not None:
            top = max(field.levels - 1, 1)
            lv = np.broadcast_to(np.asarray(level, dtype=np.float32), (n,)) / np.float32(top)

            every = np.arange(field.levels)[None, :, None]

            def sample(x: np.ndarray, y: np.ndarray) -> np.ndarray:
                # (N, M) points -> (N, L, M): every level in one pass.
                return field(x[:, None], y[:, None], ts[:, :, None], w[:, :, None], level=every)
        else:

            def sample(x: np.ndarray, y: np.ndarray) -> np.ndarray:
                return field(x, y, ts, w)

        area = field.at_points(self.area_points(field.extent), ts[:, 0], w[:, 0])
        frac = np.broadcast_to(np.asarray(t), (n,)).astype(np.float32) / np.float32(max_steps)
        obs = self.observe(sample, field.extent, p, frac, goal, min_db, area, lv)
        return {k: v[0] for k, v in obs.items()} if one else obs

    def flat(self, obs: dict[str, Any]) -> np.ndarray:
        """A batch of observations (or one) as the flat rows a replay memory stores.

        Args:
            obs: The observation's parts.

        Returns:
            (N, sum of [`sizes`][rainuav.nav.views.WeatherView.sizes]) float32, in
            [`KEYS`][rainuav.nav.views.KEYS] order.
        """
        first = np.asarray(obs["position"])
        n = 1 if first.ndim == 1 else len(first)
        keys = [k for k in KEYS if k in self.sizes]
        return np.concatenate(
            [np.asarray(obs[k], dtype=np.float32).reshape(n, -1) for k in keys], axis=1
        )


@functools.lru_cache(maxsize=8)
def _local_offsets(window: int, step_m: float) -> np.ndarray:
    h = window // 2
    d = step_m * np.arange(-h, h + 1, dtype=np.float64)
    gx, gy = np.meshgrid(d, d)
    out = np.stack([gx.ravel(), gy.ravel()], axis=1)
    out.flags.writeable = False
    return out


@functools.lru_cache(maxsize=64)
def _area_points(n: int, extent: tuple[float, float, float, float]) -> np.ndarray:
    x0, x1, y0, y1 = extent
    gx, gy = np.meshgrid(
        x0 + (np.arange(n) + 0.5) * (x1 - x0) / n, y0 + (np.arange(n) + 0.5) * (y1 - y0) / n
    )
    out = np.stack([gx.ravel(), gy.ravel()], axis=1)
    out.flags.writeable = False
    return out


def sample_goal(rng: np.random.Generator, extent: tuple[float, float, float, float]) -> np.ndarray:
    """A destination uniform in the area shrunk by a margin on every side.

    The margin is [`GOAL_MARGIN_M`][rainuav.nav.views.GOAL_MARGIN_M]; the whole area where it is
    narrower than twice the margin.

    Args:
        rng: The generator.
        extent: The area, `(x_min, x_max, y_min, y_max)`, m.

    Returns:
        The destination (2,), m.
    """
    x0, x1, y0, y1 = extent
    mx = GOAL_MARGIN_M if x1 - x0 > 2 * GOAL_MARGIN_M else 0.0
    my = GOAL_MARGIN_M if y1 - y0 > 2 * GOAL_MARGIN_M else 0.0
    return np.array([rng.uniform(x0 + mx, x1 - mx), rng.uniform(y0 + my, y1 - my)])


def sample_start_for(
    rng: np.random.Generator,
    extent: tuple[float, float, float, float],
    goal: np.ndarray,
    cfg: NavConfig,
    field: Any = None,
) -> np.ndarray:
    """A start uniform in the area, within reach of a destination and flyable.

    Farther than `tol_m` from the destination and at most [`REACH`][rainuav.nav.views.REACH] of
    `max_steps` moves from it (Manhattan distance), never in a pixel of the field's not-flyable
    mask.

    Args:
        rng: The generator.
        extent: The area, `(x_min, x_max, y_min, y_max)`, m.
        goal: The destination (2,), m.
        cfg: The task.
        field: The field flown (its not-flyable mask); None: open ground.

    Returns:
        The start (2,), m.

    Raises:
        InvalidInputError: 1000 draws found none (an area the arrival disc covers).
    """
    x0, x1, y0, y1 = extent
    reach = REACH * cfg.max_steps * cfg.step_m
    for _ in range(1000):
        p = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
        d = np.abs(p - goal).sum()
        if np.hypot(*(p - goal)) > cfg.tol_m and d <= reach:
            if field is not None and field.blocked(*p):
                continue
            return p
    raise InvalidInputError(
        f"no start farther than tol_m = {cfg.tol_m} m and within {reach:g} m of the "
        f"destination {tuple(goal)} in the area {extent}"
    )
