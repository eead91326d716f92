"""What the learner and the planner fly an environment through: many UAVs at once.

[`BatchedFlights`][rainuav.nav.batched.BatchedFlights] holds the methods of
[`UAVNavEnv`][rainuav.nav.env.UAVNavEnv] that take a batch of UAVs (positions (N, 2), levels,
clocks and worlds (N,)) rather than Gymnasium's one UAV a call: the observation, one move, the
moves an exploring UAV draws from, and the drawing of a new episode's start, destination and
world. The learner ([`rainuav.rl`][rainuav.rl]) reads an environment through these and its spaces
alone, and one summary of what it flies ([`FlightTerms`][rainuav.nav.batched.FlightTerms]: the
signal, the threshold, the levels, whether the signal moves)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav.errors import InvalidInputError
from rainuav.nav.field import field_digest
from rainuav.nav.levelfield import LEVEL_ACTIONS, LevelStepper
from rainuav.nav.views import sample_goal, sample_start_for

__all__ = ["PROTOCOL", "BatchedFlights", "FlightTerms"]

PROTOCOL = (
    "observation_space", "action_space", "np_random", "reset", "step",  # Gymnasium's
    "observe_batch", "step_batch", "exploration_moves", "start_level_at", "lowest_flyable",
    "sample_start", "draw_task", "signal", "terms", "digest",  # the batches'
)  # fmt: skip
"""What of an environment the learner ([`rainuav.rl`][rainuav.rl]) reads: Gymnasium's spaces,
random stream and one-UAV calls, and the batched calls of
[`BatchedFlights`][rainuav.nav.batched.BatchedFlights] (``tests/test_layout.py`` holds ``rl/`` to
these)."""


@dataclass(frozen=True)
class FlightTerms:
    """What an environment flies, as a learner reports and checks it
    ([`BatchedFlights.terms()`][rainuav.nav.batched.BatchedFlights.terms])."""

    signal: str
    """The signal flown: "sinr" or "sir"."""
    min_db: float
    """The outage threshold, dB."""
    altitudes_m: tuple[float, ...] | None
    """The flight levels, m, where altitude is a decision (six actions); None on one plane."""
    varies: bool
    """Whether the signal moves in time."""


class BatchedFlights:
    """The batched interface of [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv], which it is mixed into
    (it reads the environment's field, task, stepper and view)."""

    field: Any
    cfg: Any
    view: Any
    stepper: Any
    level_axis: bool
    levels: int
    banked: bool
    start_level: int | None
    random_goal: bool

    def observe_batch(
        self,
        pos: npt.ArrayLike,
        level: npt.ArrayLike,
        t: npt.ArrayLike,
        goal: npt.ArrayLike | None = None,
        world: npt.ArrayLike | None = None,
    ) -> Any:
        """The observation of many UAVs at once.

        Args:
            pos: Positions, m, (N, 2) (or any (..., 2) with the position observation).
            level: Each UAV's level index (N,) (0 on one level).
            t: Each UAV's clock, in moves (N,).
            goal: Each UAV's destination (N, 2); None: the task's.
            world: Each UAV's world in a bank (N,); None: world 0.

        Returns:
            With the position observation, float32 (..., D): the position scaled to [0, 1]^2, among
            levels the level over the highest index, and where the signal moves `t` over
            `max_steps`. With the weather observation, the
            [`WeatherView`][rainuav.nav.views.WeatherView]'s dict, batched for (N, 2) positions, one
            for a (2,) position.
        """
        if self.view is not None:
            assert self.cfg.min_db is not None
            t_s = self.stepper.time_s(np.broadcast_to(t, np.shape(pos)[:-1] or (1,)))
            g = self.cfg.goal_m if goal is None else goal
            return self.view.observe_field(self.field, t_s, pos, level, t, g, world,
                                           self.cfg.min_db, self.cfg.max_steps)  # fmt: skip
        x0, x1, y0, y1 = self.field.extent
        p = np.asarray(pos, dtype=np.float64)
        parts = [(p - np.array([x0, y0])) / np.array([x1 - x0, y1 - y0])]
        if self.level_axis:
            top = max(self.levels - 1, 1)
            parts.append((np.asarray(level, dtype=np.float64) / top)[..., None])
        if self.field.varies:
            parts.append((np.asarray(t, dtype=np.float64) / self.cfg.max_steps)[..., None])
        lead = np.broadcast_shapes(*(q.shape[:-1] for q in parts))
        return np.concatenate([np.broadcast_to(q, (*lead, q.shape[-1])) for q in parts], -1).astype(
            np.float32
        )

    def observe(
        self,
        pos: npt.ArrayLike,
        t: npt.ArrayLike = 0,
        goal: npt.ArrayLike | None = None,
        world: npt.ArrayLike | None = None,
    ) -> Any:
        """The observation of UAVs on level 0.

        Args:
            pos: Positions, m, (N, 2) or (2,).
            t: Clocks, in moves.
            goal: Destinations (N, 2); None: the task's.
            world: Worlds of a bank (N,); None: world 0.

        Returns:
            [`observe_batch()`][rainuav.nav.batched.BatchedFlights.observe_batch]'s observation.
        """
        return self.observe_batch(pos, 0, t, goal, world)

    def step_batch(
        self,
        start: npt.ArrayLike,
        offset: npt.ArrayLike,
        level: npt.ArrayLike,
        t: npt.ArrayLike,
        action: npt.ArrayLike,
        goal: npt.ArrayLike | None = None,
        world: npt.ArrayLike | None = None,
    ) -> dict[str, np.ndarray]:
        """One move of every UAV.

        Args:
            start: Each UAV's start (N, 2), m: positions are kept as the start plus whole moves.
            offset: Each UAV's moves from its start so far (N, 2), integers.
            level: Each UAV's level index (N,).
            t: Each UAV's clock, in ticks (N,).
            action: Each UAV's move (N,), integers of the action space.
            goal: Each UAV's destination (N, 2); None: the task's.
            world: Each UAV's world in a bank (N,); None: world 0.

        Returns:
            The batched stepper's arrays
        ([`LevelStepper.step()`][rainuav.nav.levelfield.LevelStepper.step]): the new `offset`,
        `level`, `position` (clamped), `reward`, `terminated`, `truncated`, `signal_db`, `out`,
        `arrived`, `duration` and `t_s` (the landing instant), and `t` the new clock in ticks
        (one a move on one level).
        """
        if not self.banked:
            world = None
        r = LevelStepper.step(self.stepper, start, offset, level, t, action, goal, world)
        r["t"] = r.pop("tick")
        return r

    def exploration_moves(self, level: npt.ArrayLike) -> np.ndarray | None:
        """The moves an exploring UAV draws from.

        Random moves among levels would end a sixth of the early flights at once (a climb from the
        top or a descent from the bottom); the network's own moves are never restricted.

        Args:
            level: Each UAV's level index (N,).

        Returns:
            None on one level (every move); among levels (N, 6) bool, every move but a climb from
            the top and a descent from the bottom.
        """
        if not self.level_axis:
            return None
        level = np.asarray(level)
        ok = np.ones((len(level), LEVEL_ACTIONS), dtype=bool)
        ok[:, 4] = level < self.levels - 1
        ok[:, 5] = level > 0
        return ok

    def lowest_flyable(self, x: float, y: float) -> int:
        """The lowest level the UAV may fly at over a point.

        Args:
            x: East, m.
            y: North, m.

        Returns:
            The level's index.

        Raises:
            InvalidInputError: No level is flyable there.
        """
        ok = self.field.flyable(x, y)
        if not ok.any():
            raise InvalidInputError(f"({x:g}, {y:g}) is not flyable at any level")
        return int(np.flatnonzero(ok)[0])

    def start_level_at(self, p: npt.ArrayLike) -> int:
        """The level a flight from a point starts at.

        Args:
            p: The start (x, y), m.

        Returns:
            `start_level` where the environment was given one, 0 on one level, else the lowest
            flyable level there.
        """
        if self.start_level is not None:
            return int(self.start_level)
        return self.lowest_flyable(float(p[0]), float(p[1])) if self.level_axis else 0

    def sample_start(
        self, rng: np.random.Generator, goal: npt.ArrayLike | None = None
    ) -> np.ndarray:
        """A start drawn uniformly in the area, away from the destination and flyable.

        Args:
            rng: The generator to draw from.
            goal: The destination (2,); None: the task's.

        Returns:
            The start (2,), m: farther than `tol_m` from the destination and flyable at some level.

        Raises:
            InvalidInputError: No such start in 100 000 draws.
        """
        x0, x1, y0, y1 = self.field.extent
        g = np.asarray(self.cfg.goal_m if goal is None else goal)
        for _ in range(100_000):
            p = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
            if np.hypot(*(p - g)) > self.cfg.tol_m and self.field.flyable(*p).any():
                return p
        raise InvalidInputError(
            f"no flyable start farther than tol_m = {self.cfg.tol_m} m from the destination "
            f"in the area {self.field.extent}"
        )

    def draw_task(
        self, rng: np.random.Generator, goal: npt.ArrayLike | None = None
    ) -> tuple[np.ndarray, np.ndarray, int]:
        """A new episode's start, destination and world.

        The world is drawn uniformly among a bank's (0 otherwise); then the destination (`goal`
        where given; drawn by [`sample_goal()`][rainuav.nav.views.sample_goal] where `random_goal`;
        else the task's); then the start
        ([`sample_start()`][rainuav.nav.batched.BatchedFlights.sample_start], or within reach of a
        drawn destination, flyable at some level).

        Args:
            rng: The generator to draw from.
            goal: A destination (2,) in place of the drawn or fixed one.

        Returns:
            `(start, destination, world)`.

        Raises:
            InvalidInputError: No flyable start within reach of the destination.
        """
        world = int(rng.integers(self.field.worlds)) if self.banked else 0
        if goal is None and not self.random_goal:
            return self.sample_start(rng), np.asarray(self.cfg.goal_m, dtype=np.float64), world
        g = sample_goal(rng, self.field.extent) if goal is None else np.asarray(goal, float)
        for _ in range(1000):
            p = sample_start_for(rng, self.field.extent, g, self.cfg)
            if self.field.flyable(*p).any():
                return p, g, world
        raise InvalidInputError(f"no flyable start within reach of the destination {tuple(g)}")

    def terms(self) -> FlightTerms:
        """What this environment flies (the learner's one read of it beside the spaces).

        Returns:
            The [`FlightTerms`][rainuav.nav.batched.FlightTerms].
        """
        alts = self.field.altitudes_m
        return FlightTerms(
            signal=str(self.cfg.signal), min_db=float(self.cfg.min_db),
            altitudes_m=None if alts is None else tuple(float(a) for a in alts),
            varies=bool(self.field.varies),
        )  # fmt: skip

    def digest(self) -> str:
        """A digest of the signal this environment flies: a run records it, so that a map swapped
        into its folder is refused ([`field_digest()`][rainuav.nav.field.field_digest]; it hashes
        the whole field: once a checkpoint, not once a move).

        Returns:
            The SHA-256 digest, as hexadecimal text.
        """
        return field_digest(self.field)

    def signal(
        self,
        x: npt.ArrayLike,
        y: npt.ArrayLike,
        t_s: npt.ArrayLike,
        world: npt.ArrayLike = 0,
        level: npt.ArrayLike = 0,
    ) -> Any:
        """The signal at points and times.

        Args:
            x: East, m.
            y: North, m.
            t_s: Time, s.
            world: The world of a bank.
            level: The level index.

        Returns:
            The signal, dB, of the broadcast shape of `x`, `y` and `t_s`.
        """
        return self.field(x, y, t_s, world, level=level)
