"""What the learner learns from: where its training flights start, the reward it stores for a
move and where its episodes end.

A share of the training flights starts near the destination
([`training_start()`][rainuav.rl.learner.training_start]). The environment's reward with its SIR
part weighted ([`learning_reward()`][rainuav.rl.learner.learning_reward]), plus potential-based
shaping by the straight-line value ([`shaping_term()`][rainuav.rl.learner.shaping_term]). Why each,
and what it measured: ``docs/record/learning.md``."""

from __future__ import annotations

import numpy as np

from rainuav.nav.env import UAVNavEnv
from rainuav.nav.task import base_reward
from rainuav.rl.config import DQNConfig

__all__ = [
    "GOAL_START_MOVES",
    "learner_ends",
    "learning_reward",
    "shaping_term",
    "training_level",
    "training_start",
    "training_task",
]

GOAL_START_MOVES = 10
"""Half side, in moves, of the square around the destination where ``goal_starts`` of the
training flights begin."""


def training_task(
    env: UAVNavEnv, d: DQNConfig, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, int]:
    """A training flight's start, destination and world.

    Where the env observes the position: the env's fixed destination and
    [`training_start()`][rainuav.rl.learner.training_start] (the single-map learner's draws,
    unchanged). Where it observes the weather: the env's draw
    ([`draw_task()`][rainuav.nav.batched.BatchedFlights.draw_task]: a random destination where the
    env has them; the task's own one with probability `task_goals`), its start then moved near the
    destination with probability `goal_starts`.

    Args:
        env: The environment.
        d: The learner's settings.
        rng: The environment's training stream.

    Returns:
        `(start, destination, world)`.
    """
    if env.view is None:
        return training_start(env, d, rng), np.asarray(env.cfg.goal_m, dtype=np.float64), 0
    own = env.random_goal and d.task_goals > 0 and rng.random() < d.task_goals
    start, goal, world = env.draw_task(rng, env.cfg.goal_m if own else None)
    if d.goal_starts and rng.random() < d.goal_starts:
        near = near_goal(env, goal, rng)
        start = start if near is None else near
    return start, goal, world


def near_goal(env: UAVNavEnv, goal: np.ndarray, rng: np.random.Generator) -> np.ndarray | None:
    """A point uniform in a square around a destination, outside the arrival disc.

    The square's half side is [`GOAL_START_MOVES`][rainuav.rl.learner.GOAL_START_MOVES] moves,
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


def training_start(env: UAVNavEnv, d: DQNConfig, rng: np.random.Generator) -> np.ndarray:
    """The start of a training flight: near the destination or uniform in the area.

    Near is uniform in the square of half side
    [`GOAL_START_MOVES`][rainuav.rl.learner.GOAL_START_MOVES] moves around the destination, clipped
    to the area and outside the arrival disc (uniform in the area where 100 draws found no such
    point, as when the tolerance covers the square); else uniform in the area (`env.sample_start`).

    Flights from uniform starts reach the destination's neighbourhood once each, at their last move,
    and late in training almost greedily: the moves into the arrival disc from the side a network
    gets wrong are then hardly ever tried, and a final network can circle one move from the goal
    (docs/record/learning.md). Starting a quarter of the flights near it gives those moves their own
    experience. Only a start is chosen: the flight, its rewards and the task are the environment's,
    and nothing here knows the radio map.

    Args:
        env: The environment.
        d: The learner's settings.
        rng: The environment's training stream.

    Returns:
        The start (2,), m.
    """
    if d.goal_starts == 0.0 or rng.random() >= d.goal_starts:
        return env.sample_start(rng)
    p = near_goal(env, np.asarray(env.cfg.goal_m, dtype=np.float64), rng)
    return env.sample_start(rng) if p is None else p


def training_level(
    env: UAVNavEnv, d: DQNConfig, start: np.ndarray, rng: np.random.Generator
) -> int:
    """The level a training flight takes off at.

    Among levels, with probability `level_starts` uniform among the levels flyable at the start,
    else the lowest (the task's own start); 0 on one level. Draws nothing where `level_starts` is 0.

    Args:
        env: The environment.
        d: The learner's settings.
        start: The start (2,), m.
        rng: The environment's training stream.

    Returns:
        The level's index.
    """
    if env.altitudes_m is None:
        return 0
    if d.level_starts == 0.0 or rng.random() >= d.level_starts:
        return env.start_level_at(start)
    ok = np.flatnonzero(env.field.flyable(float(start[0]), float(start[1])))
    return int(ok[rng.integers(ok.size)])


def learner_ends(d: DQNConfig, r: dict[str, np.ndarray]) -> np.ndarray:
    """Where the learner's episode ends (no bootstrap).

    Arrival or leaving the area, and for a time-aware learner, which knows there are no moves left,
    also the time limit.

    Args:
        d: The learner's settings.
        r: The batch step's results.

    Returns:
        (N,) bool.
    """
    return r["terminated"] | (r["truncated"] & d.time_aware)


def learning_reward(
    env: UAVNavEnv,
    d: DQNConfig,
    pos: np.ndarray,
    r: dict[str, np.ndarray],
    goal: np.ndarray | None = None,
) -> np.ndarray:
    """The reward the learner stores for the moves of a batch step.

    The env's reward with its SIR part `b + 1` weighted by `sir_weight`, plus the potential-based
    shaping term (zero potential where [`learner_ends()`][rainuav.rl.learner.learner_ends]).
    Discounting and the destination reward make the learner value time above the SIR: a move later
    costs `(1 - gamma) gamma^k R_des` of the destination reward on top of its -1, several times the
    undiscounted price of a move at gamma 0.998. Weighting the SIR part up restores the balance of
    the undiscounted return the policy is judged by; a position-only policy then loops from a few
    starts, which the shield breaks (1.25 by default; see `docs/record/learning.md`). Among levels
    the shaping's potential is the plane's (the moves still needed on the lattice, whatever the
    level): a potential of the state, so the optimum is kept.

    Args:
        env: The environment.
        d: The learner's settings.
        pos: The positions moved from (N, 2), m.
        r: The batch step's results (`r["position"]` the positions moved to).
        goal: Each UAV's destination (N, 2); None: the task's.

    Returns:
        (N,) rewards.
    """
    reward = r["reward"]
    if d.sir_weight != 1.0:  # among levels each move's part weighs its duration, as its reward
        base = r["base"] if "base" in r else base_reward(r["signal_db"], env.cfg)
        sir = (base + 1.0) * r.get("duration", 1.0)
        reward = reward + (d.sir_weight - 1.0) * sir
    return reward + shaping_term(env, d, pos, r["position"], learner_ends(d, r), goal)


def shaping_term(
    env: UAVNavEnv,
    d: DQNConfig,
    pos: np.ndarray,
    new_pos: np.ndarray,
    ended: np.ndarray,
    goal: np.ndarray | None = None,
) -> np.ndarray:
    """Potential-based shaping `gamma Phi(s') - Phi(s)` (Ng, Harada and Russell, ICML 1999).

    `Phi(s) = shaping * V_straight(s)`: the discounted return of flying straight to the destination
    ignoring the SIR, `-(1 - gamma^k) / (1 - gamma) + gamma^k R_des` with `k` the moves still needed
    (lattice distance minus the tolerance); `Phi = 0` where the learner's episode ends. Summed over
    an episode the terms telescope to `-Phi(s_0)` (a truncation the learner bootstraps through keeps
    `gamma^T Phi(s_T)`, which its bootstrap value offsets), so the optimal policy is unchanged,
    while the learner now sees 0 for a move that keeps the straight-line pace and a clear loss for
    one that does not, instead of 2000 points at the end of a 300-move episode: it only has to learn
    how the SIR bends the straight route.

    Args:
        env: The environment.
        d: The learner's settings.
        pos: The positions moved from (N, 2), m.
        new_pos: The positions moved to (N, 2), m.
        ended: Where the learner's episode ends (N,): after arrival or leaving the area, and for a
            time-aware learner also at the time limit.
        goal: Each UAV's destination (N, 2); None: the task's.

    Returns:
        (N,) terms.
    """
    if d.shaping == 0.0:
        return np.zeros(len(pos))
    c = env.cfg
    goal = np.asarray(c.goal_m) if goal is None else np.asarray(goal).reshape(-1, 2)

    def phi(p: np.ndarray) -> np.ndarray:
        k = np.maximum(np.abs(p - goal).sum(axis=1) - c.tol_m, 0.0) / c.step_m
        g = d.gamma**k
        steps = k if d.gamma == 1.0 else (1.0 - g) / (1.0 - d.gamma)
        return d.shaping * (-steps + g * c.goal_reward)

    return d.gamma * np.where(ended, 0.0, phi(new_pos)) - phi(pos)
