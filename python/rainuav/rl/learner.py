"""What the learner learns from: where its training flights start, the reward it stores for a
move and where its episodes end.

The learner's settings ([`DQNConfig`][rainuav.rl.dqnconfig.DQNConfig]) choose the numbers; the
navigation layer's wrappers ([`rainuav.nav.training`][rainuav.nav.training]) draw the starts and
shape the rewards on the environment, so nothing here reads the environment's insides. A share
of the training flights starts near the destination
([`training_start()`][rainuav.rl.learner.training_start]). The environment's reward with its SIR
part weighted ([`learning_reward()`][rainuav.rl.learner.learning_reward]), plus potential-based
shaping by the straight-line value ([`shaping_term()`][rainuav.rl.learner.shaping_term]). Why each,
and what it measured: ``docs/record/learning.md``."""

from __future__ import annotations

import numpy as np

from rainuav.nav.env import UAVNavEnv
from rainuav.nav.training import GOAL_START_MOVES, Shaping, TrainingStarts
from rainuav.rl.config import DQNConfig

__all__ = [
    "GOAL_START_MOVES",
    "learner_ends",
    "learning_reward",
    "shaping_of",
    "shaping_term",
    "starts_of",
    "training_level",
    "training_start",
    "training_task",
]


def starts_of(d: DQNConfig) -> TrainingStarts:
    """The learner's training starts.

    Args:
        d: The learner's settings.

    Returns:
        Its [`TrainingStarts`][rainuav.nav.training.TrainingStarts].
    """
    return TrainingStarts(d.goal_starts, d.task_goals, d.level_starts)


def shaping_of(d: DQNConfig) -> Shaping:
    """The learner's reward shaping.

    Args:
        d: The learner's settings.

    Returns:
        Its [`Shaping`][rainuav.nav.training.Shaping].
    """
    return Shaping(d.gamma, d.shaping, d.sir_weight)


def training_task(
    env: UAVNavEnv, d: DQNConfig, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, int]:
    """A training flight's start, destination and world
    ([`TrainingStarts.task()`][rainuav.nav.training.TrainingStarts.task]).

    Args:
        env: The environment.
        d: The learner's settings.
        rng: The environment's training stream.

    Returns:
        `(start, destination, world)`.
    """
    return starts_of(d).task(env, rng)


def training_start(env: UAVNavEnv, d: DQNConfig, rng: np.random.Generator) -> np.ndarray:
    """The start of a training flight: near the destination or uniform in the area
    ([`TrainingStarts.start()`][rainuav.nav.training.TrainingStarts.start]).

    Args:
        env: The environment.
        d: The learner's settings.
        rng: The environment's training stream.

    Returns:
        The start (2,), m.
    """
    return starts_of(d).start(env, rng)


def training_level(
    env: UAVNavEnv, d: DQNConfig, start: np.ndarray, rng: np.random.Generator
) -> int:
    """The level a training flight takes off at
    ([`TrainingStarts.level()`][rainuav.nav.training.TrainingStarts.level]).

    Args:
        env: The environment.
        d: The learner's settings.
        start: The start (2,), m.
        rng: The environment's training stream.

    Returns:
        The level's index.
    """
    return starts_of(d).level(env, start, rng)


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
    """The reward the learner stores for the moves of a batch step
    ([`Shaping.reward()`][rainuav.nav.training.Shaping.reward]; zero potential where
    [`learner_ends()`][rainuav.rl.learner.learner_ends]).

    Args:
        env: The environment.
        d: The learner's settings.
        pos: The positions moved from (N, 2), m.
        r: The batch step's results (`r["position"]` the positions moved to).
        goal: Each UAV's destination (N, 2); None: the task's.

    Returns:
        (N,) rewards.
    """
    return shaping_of(d).reward(env, pos, r, learner_ends(d, r), goal)


def shaping_term(
    env: UAVNavEnv,
    d: DQNConfig,
    pos: np.ndarray,
    new_pos: np.ndarray,
    ended: np.ndarray,
    goal: np.ndarray | None = None,
) -> np.ndarray:
    """Potential-based shaping `gamma Phi(s') - Phi(s)`
    ([`Shaping.term()`][rainuav.nav.training.Shaping.term]).

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
    return shaping_of(d).term(env, pos, new_pos, ended, goal)
