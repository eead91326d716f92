"""What a learner trains on, beside the task itself: what its network's input is
([`network_inputs()`][rainuav.nav.training.network_inputs]), where its training flights start
([`TrainingStarts`][rainuav.nav.training.TrainingStarts]) and the shaped reward it stores for a
move ([`Shaping`][rainuav.nav.training.Shaping]).

Both wrap an environment's own draws and rewards, and read it here, in the navigation layer, so
that a learner holds its numbers (shares, a discount, weights) and never the environment's
insides. Why each exists, and what it measured: ``docs/record/learning.md``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rainuav.nav.env import UAVNavEnv
from rainuav.nav.task import base_reward

__all__ = [
    "GOAL_START_MOVES",
    "NetworkInputs",
    "Shaping",
    "TrainingStarts",
    "network_inputs",
    "positions",
    "random_flight",
]

GOAL_START_MOVES = 10
"""Half side, in moves, of the square around the destination where ``goal_starts`` of the
training flights begin."""


@dataclass(frozen=True)
class NetworkInputs:
    """What a network needs to know of an environment's observations and actions, beside its
    spaces."""

    observation_dims: int
    """The length of an observation of the position (its space's shape)."""
    actions: int
    """The number of actions (its action space's)."""
    step: tuple[float, float]
    """One move east and north in the observation's units."""
    goal: tuple[float, float] | None
    """The task's destination in the observation's units (None where the environment observes
    the weather, with its destination in it)."""
    max_steps: int
    """The task's time limit, moves."""
    among_levels: bool
    """Whether the flight chooses its level (the level is in the observation)."""
    gives_time: bool
    """Whether the signal varies in time (the clock is in the observation)."""
    area_m: tuple[float, float]
    """The area's size east and north, m."""
    step_m: float
    """One move, m."""
    tol_m: float
    """The arrival tolerance, m."""
    view: Any = None
    """The weather view where the environment observes the weather
    ([`rainuav.nav.views`][rainuav.nav.views]); None: it observes the position."""


def network_inputs(env: UAVNavEnv) -> NetworkInputs:
    """What a network reads of an environment: its observation's and action's sizes, one move
    and the destination in the observation's units, the task's time limit and what the
    observation holds.

    Args:
        env: The environment.

    Returns:
        The [`NetworkInputs`][rainuav.nav.training.NetworkInputs].
    """
    x0, x1, y0, y1 = env.field.extent
    s = env.cfg.step_m
    among = env.altitudes_m is not None
    goal: tuple[float, float] | None = None
    if among:  # the destination scaled to the area, as the observation scales the position
        gx, gy = env.cfg.goal_m
        goal = ((gx - x0) / (x1 - x0), (gy - y0) / (y1 - y0))
    elif env.view is None:
        gx, gy = env.observe(np.asarray(env.cfg.goal_m))[:2].tolist()
        goal = (gx, gy)
    shape = env.observation_space.shape
    return NetworkInputs(
        observation_dims=int(shape[0]) if shape else 0,
        actions=int(env.action_space.n),  # type: ignore[attr-defined]
        step=(s / (x1 - x0), s / (y1 - y0)),
        goal=goal,
        max_steps=env.cfg.max_steps,
        among_levels=among,
        gives_time=bool(env.field.varies),
        area_m=(x1 - x0, y1 - y0),
        step_m=s,
        tol_m=env.cfg.tol_m,
        view=env.view,
    )


def positions(env: UAVNavEnv, starts: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Where UAVs are, from their starts and their offsets in moves (the batched interface's
    coordinates, [`rainuav.nav.batched`][rainuav.nav.batched]).

    Args:
        env: The environment.
        starts: The starts (N, 2), m.
        offsets: The offsets from them (N, 2), moves.

    Returns:
        The positions (N, 2), m.
    """
    return starts + env.cfg.step_m * offsets


def random_flight(env: UAVNavEnv, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A destination drawn in the area and a start drawn within reach of it
    ([`sample_goal()`][rainuav.nav.views.sample_goal],
    [`sample_start_for()`][rainuav.nav.views.sample_start_for]).

    Args:
        env: The environment.
        rng: The generator.

    Returns:
        `(start, destination)`, (2,) each, m.
    """
    from rainuav.nav.views import sample_goal, sample_start_for

    goal = sample_goal(rng, env.field.extent)
    return sample_start_for(rng, env.field.extent, goal, env.cfg), goal


@dataclass(frozen=True)
class TrainingStarts:
    """Where training flights start, and at which level, and to which destination."""

    goal_starts: float = 0.0
    """The share of the flights that start near the destination."""
    task_goals: float = 0.0
    """Where the destination is drawn: the share that flies to the task's own."""
    level_starts: float = 0.0
    """Among levels, the share that takes off at a level drawn among those flyable."""

    def task(self, env: UAVNavEnv, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, int]:
        """A training flight's start, destination and world.

        Where the env observes the position: the env's fixed destination and
        [`start()`][rainuav.nav.training.TrainingStarts.start] (the single-map learner's draws).
        Where it observes the weather: the env's draw
        ([`draw_task()`][rainuav.nav.batched.BatchedFlights.draw_task]: a random destination where
        the env has them; the task's own one with probability `task_goals`), its start then moved
        near the destination with probability `goal_starts`.

        Args:
            env: The environment.
            rng: The environment's training stream.

        Returns:
            `(start, destination, world)`.
        """
        if env.view is None:
            return self.start(env, rng), np.asarray(env.cfg.goal_m, dtype=np.float64), 0
        own = env.random_goal and self.task_goals > 0 and rng.random() < self.task_goals
        start, goal, world = env.draw_task(rng, env.cfg.goal_m if own else None)
        if self.goal_starts and rng.random() < self.goal_starts:
            near = near_goal(env, goal, rng)
            start = start if near is None else near
        return start, goal, world

    def start(self, env: UAVNavEnv, rng: np.random.Generator) -> np.ndarray:
        """The start of a training flight: near the destination or uniform in the area.

        Near is uniform in the square of half side
        [`GOAL_START_MOVES`][rainuav.nav.training.GOAL_START_MOVES] moves around the destination,
        clipped to the area and outside the arrival disc (uniform in the area where 100 draws
        found no such point, as when the tolerance covers the square); else uniform in the area
        (`env.sample_start`).

        Flights from uniform starts reach the destination's neighbourhood once each, at their last
        move, and late in training almost greedily: the moves into the arrival disc from the side a
        network gets wrong are then hardly ever tried, and a final network can circle one move
        from the goal (docs/record/learning.md). Starting a quarter of the flights near it gives
        those moves their own experience. Only a start is chosen: the flight, its rewards and the
        task are the environment's, and nothing here knows the radio map.

        Args:
            env: The environment.
            rng: The environment's training stream.

        Returns:
            The start (2,), m.
        """
        if self.goal_starts == 0.0 or rng.random() >= self.goal_starts:
            return env.sample_start(rng)
        p = near_goal(env, np.asarray(env.cfg.goal_m, dtype=np.float64), rng)
        return env.sample_start(rng) if p is None else p

    def level(self, env: UAVNavEnv, start: np.ndarray, rng: np.random.Generator) -> int:
        """The level a training flight takes off at.

        Among levels, with probability `level_starts` uniform among the levels flyable at the
        start, else the lowest (the task's own start); 0 on one level. Draws nothing where
        `level_starts` is 0.

        Args:
            env: The environment.
            start: The start (2,), m.
            rng: The environment's training stream.

        Returns:
            The level's index.
        """
        if env.altitudes_m is None:
            return 0
        if self.level_starts == 0.0 or rng.random() >= self.level_starts:
            return env.start_level_at(start)
        ok = np.flatnonzero(env.field.flyable(float(start[0]), float(start[1])))
        return int(ok[rng.integers(ok.size)])


def near_goal(env: UAVNavEnv, goal: np.ndarray, rng: np.random.Generator) -> np.ndarray | None:
    """A point uniform in a square around a destination, outside the arrival disc.

    The square's half side is [`GOAL_START_MOVES`][rainuav.nav.training.GOAL_START_MOVES] moves,
    clipped to the area.

    Args:
        env: The environment.
        goal: The destination (2,), m.
        rng: The generator.

    Returns:
        The point (2,), m, or None where 100 draws found none.
    """
    x0, x1, y0, y1 = env.field.extent
    half = GOAL_START_MOVES * env.cfg.step_m
    for _ in range(100):
        p = np.clip(goal + rng.uniform(-half, half, size=2), (x0, y0), (x1, y1))
        if np.hypot(*(p - goal)) > env.cfg.tol_m:
            return p
    return None


@dataclass(frozen=True)
class Shaping:
    """The reward a learner stores for a move: the env's, its SIR part weighted, plus
    potential-based shaping by the straight-line value."""

    gamma: float
    """The learner's discount."""
    shaping: float = 0.0
    """The weight of the straight-line potential (0: none)."""
    sir_weight: float = 1.0
    """The weight of the reward's SIR part."""

    def reward(
        self,
        env: UAVNavEnv,
        pos: np.ndarray,
        r: dict[str, np.ndarray],
        ended: np.ndarray,
        goal: np.ndarray | None = None,
    ) -> np.ndarray:
        """The reward the learner stores for the moves of a batch step.

        The env's reward with its SIR part `b + 1` weighted by `sir_weight`, plus the
        potential-based shaping term (zero potential where the learner's episode ends).
        Discounting and the destination reward make the learner value time above the SIR: a move
        later costs `(1 - gamma) gamma^k R_des` of the destination reward on top of its -1, several
        times the undiscounted price of a move at gamma 0.998. Weighting the SIR part up restores
        the balance of the undiscounted return the policy is judged by; a position-only policy then
        loops from a few starts, which the shield breaks (1.25 by default; see
        `docs/record/learning.md`). Among levels the shaping's potential is the plane's (the moves
        still needed on the lattice, whatever the level): a potential of the state, so the optimum
        is kept.

        Args:
            env: The environment.
            pos: The positions moved from (N, 2), m.
            r: The batch step's results (`r["position"]` the positions moved to).
            ended: Where the learner's episode ends (N,).
            goal: Each UAV's destination (N, 2); None: the task's.

        Returns:
            (N,) rewards.
        """
        reward = r["reward"]
        if self.sir_weight != 1.0:  # among levels each move's part weighs its duration
            base = r["base"] if "base" in r else base_reward(r["signal_db"], env.cfg)
            sir = (base + 1.0) * r.get("duration", 1.0)
            reward = reward + (self.sir_weight - 1.0) * sir
        return reward + self.term(env, pos, r["position"], ended, goal)

    def term(
        self,
        env: UAVNavEnv,
        pos: np.ndarray,
        new_pos: np.ndarray,
        ended: np.ndarray,
        goal: np.ndarray | None = None,
    ) -> np.ndarray:
        """Potential-based shaping `gamma Phi(s') - Phi(s)` (Ng, Harada and Russell, ICML 1999).

        `Phi(s) = shaping * V_straight(s)`: the discounted return of flying straight to the
        destination ignoring the SIR, `-(1 - gamma^k) / (1 - gamma) + gamma^k R_des` with `k` the
        moves still needed (lattice distance minus the tolerance); `Phi = 0` where the learner's
        episode ends. Summed over an episode the terms telescope to `-Phi(s_0)` (a truncation the
        learner bootstraps through keeps `gamma^T Phi(s_T)`, which its bootstrap value offsets), so
        the optimal policy is unchanged, while the learner now sees 0 for a move that keeps the
        straight-line pace and a clear loss for one that does not, instead of 2000 points at the
        end of a 300-move episode: it only has to learn how the SIR bends the straight route.

        Args:
            env: The environment.
            pos: The positions moved from (N, 2), m.
            new_pos: The positions moved to (N, 2), m.
            ended: Where the learner's episode ends (N,): after arrival or leaving the area, and
                for a time-aware learner also at the time limit.
            goal: Each UAV's destination (N, 2); None: the task's.

        Returns:
            (N,) terms.
        """
        if self.shaping == 0.0:
            return np.zeros(len(pos))
        c = env.cfg
        goal = np.asarray(c.goal_m) if goal is None else np.asarray(goal).reshape(-1, 2)
        gamma, weight = self.gamma, self.shaping

        def phi(p: np.ndarray) -> np.ndarray:
            k = np.maximum(np.abs(p - goal).sum(axis=1) - c.tol_m, 0.0) / c.step_m
            g = gamma**k
            steps = k if gamma == 1.0 else (1.0 - g) / (1.0 - gamma)
            return weight * (-steps + g * c.goal_reward)

        return gamma * np.where(ended, 0.0, phi(new_pos)) - phi(pos)
