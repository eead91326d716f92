"""What a training run carries from one step to the next, and what it does besides collecting and
learning: [`RunState`][rainuav.rl.callbacks.RunState] (saved and restored by the same code) and
the callbacks [`run_loop()`][rainuav.rl.loop.run_loop] calls, in the manner of
Stable-Baselines3's ``learn()``: per finished episode ([`Callback.on_episode()`]
[rainuav.rl.callbacks.Callback.on_episode]: the log row, the stages' rollouts, the validation
check) and after each step that finished some ([`Callback.on_step()`]
[rainuav.rl.callbacks.Callback.on_step]: the loss and the progress bar, the wall-clock budget;
one may end the run), then the [`Checkpoint`][rainuav.rl.callbacks.Checkpoint].

Adding a behaviour to training (a new check, a new log) is a new callback; the loop stays the
loop."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import torch

from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.rl import checkpoint
from rainuav.rl.collect import Lanes, greedy_rollouts
from rainuav.rl.config import TrainConfig, to_dict
from rainuav.rl.dqn import Agent
from rainuav.rl.evaluation import Validation
from rainuav.rl.runlog import RunLog
from rainuav.world.pool import StormPool

__all__ = [
    "Callback",
    "Checkpoint",
    "EpisodeLog",
    "RunState",
    "Stages",
    "TimeBudget",
    "ValidationChecks",
]


@dataclass
class RunState:
    """Everything a run carries from one step to the next: the agent (networks, optimiser, replay,
    schedules), the environment's random stream, the UAVs in flight (``lanes``), the validation
    history, the storm pool, and the counts. A checkpoint is
    [`state_dict()`][rainuav.rl.callbacks.RunState.state_dict]; resuming is
    [`load_state_dict()`][rainuav.rl.callbacks.RunState.load_state_dict]."""

    agent: Agent
    env: UAVNavEnv
    lanes: Lanes
    checks: Validation
    pool: StormPool | None
    per_storm: np.ndarray
    """Episodes started on each storm of the pool since it was drawn."""
    started: int = 0
    """Episodes launched."""
    pending: int = 0
    """Transitions not yet paid for by a gradient step."""
    returns: list[float] = field(default_factory=list)
    successes: list[bool] = field(default_factory=list)
    stages: list[Any] = field(default_factory=list)
    train_seconds: float = 0.0
    """Training time of the calls before this one, s."""
    losses: list[float] = field(default_factory=list)
    """The gradient steps' losses since the last log (not saved)."""
    t0: float = field(default_factory=time.perf_counter)

    KEYS: ClassVar[tuple[str, ...]] = (
        "agent", "env_rng", "lanes", "started", "returns", "successes", "stages", "pending",
        "validation", "train_seconds", "torch_rng", "config",
    )  # fmt: skip
    """The keys [`state_dict()`][rainuav.rl.callbacks.RunState.state_dict] writes that every
    checkpoint holds, what a resume requires (it also writes ``map_digest`` and ``pool``, which
    a checkpoint of an earlier release lacks)."""

    @property
    def done(self) -> int:
        """Finished episodes."""
        return len(self.returns)

    def seconds(self) -> float:
        """Training time so far, s, the calls before this one included.

        Returns:
            Seconds.
        """
        return time.perf_counter() - self.t0 + self.train_seconds

    def state_dict(self, cfg: TrainConfig) -> dict[str, Any]:
        """The checkpoint: tensors and plain data only.

        Args:
            cfg: The run's configuration (recorded, so that a resume or an evaluation checks it).

        Returns:
            The checkpoint's dict.
        """
        pool = self.pool
        return {
            "agent": self.agent.state_dict(),
            "env_rng": self.env.np_random.bit_generator.state,
            "lanes": self.lanes.state_dict(),
            "started": self.started,
            "returns": self.returns,
            "successes": self.successes,
            "stages": self.stages,
            "pending": self.pending,
            "validation": self.checks.state_dict(),
            "train_seconds": self.seconds(),
            "torch_rng": torch.get_rng_state(),
            "config": to_dict(cfg),
            # what the run flies (not for a storm pool, whose field changes storm by storm)
            "map_digest": None if pool is not None else self.env.digest(),
            "pool": None
            if pool is None
            else {"pool": pool.state_dict(), "per_storm": self.per_storm.copy()},
        }

    def load_state_dict(self, saved: dict[str, Any], path: Path, episodes: int) -> None:
        """Restores a checkpoint of this run.

        Args:
            saved: The checkpoint.
            path: Where it was read (for the messages).
            episodes: The run's episodes.

        Raises:
            InvalidInputError: A checkpoint that does not fit this run (named why).
        """
        try:
            self.agent.load_state_dict(saved["agent"])
            self.env.np_random.bit_generator.state = saved["env_rng"]
            self.lanes.load_state_dict(saved["lanes"])
            self.checks.load_state_dict(saved["validation"])
            torch.set_rng_state(saved["torch_rng"])
            self.started, self.pending = int(saved["started"]), int(saved["pending"])
            self.stages = saved["stages"]
            self.returns, self.successes = list(saved["returns"]), list(saved["successes"])
            self.train_seconds = float(saved["train_seconds"])
            if self.pool is not None:
                self.pool.load_state_dict(saved["pool"]["pool"])
                self.per_storm[:] = np.asarray(saved["pool"]["per_storm"], dtype=np.int64)
        except (KeyError, TypeError, ValueError, RuntimeError, AttributeError, IndexError) as err:
            raise InvalidInputError(
                f"checkpoint {path}: refused (does not fit this run: "
                f"{type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''})"
            ) from err
        n = len(self.returns)
        if not (0 <= n <= self.started <= episodes and len(self.successes) == n):
            raise InvalidInputError(
                f"checkpoint {path}: refused (its episode counts are inconsistent)"
            )


class Callback:
    """A behaviour of training besides collecting and learning."""

    def on_episode(self, run: RunState, lane: int) -> None:
        """Called after one lane's episode finished (`run.done` counts it).

        Args:
            run: The run's state.
            lane: The lane whose episode finished.
        """

    def on_step(self, run: RunState, before: int) -> bool:
        """Called after a step that finished episodes.

        Args:
            run: The run's state.
            before: The episodes finished before the step.

        Returns:
            True to end the call.
        """
        return False


@dataclass
class EpisodeLog(Callback):
    """A row of ``log.csv`` per finished episode; the mean loss to TensorBoard and the
    progress bar after each step that finished some."""

    log: RunLog

    def on_episode(self, run: RunState, lane: int) -> None:
        lanes = run.lanes
        eps = float(run.agent.epsilon(lanes.episode[lane]))
        row = (int(lanes.episode[lane]), float(lanes.ret[lane]), int(lanes.t[lane]))
        self.log.episode(run.done, (*row, run.successes[-1], eps, run.seconds()))

    def on_step(self, run: RunState, before: int) -> bool:
        if run.losses:
            self.log.tb.add_scalar("loss", float(np.mean(run.losses)), run.done)
            run.losses.clear()
        if self.log.bar is not None:
            self.log.bar.set_postfix(
                ret=f"{np.mean(run.returns[-100:]):.0f}",
                success=f"{np.mean(run.successes[-100:]):.2f}",
                eps=f"{run.agent.epsilon(run.started - 1):.3f}",
            )
            self.log.bar.update(run.done - before)
        return False


@dataclass
class Stages(Callback):
    """Every ``every`` finished episodes, greedy rollouts of the reported network from
    ``starts`` on ``env`` (for ``stages.png``; they draw nothing from the training stream)."""

    every: int
    env: UAVNavEnv
    starts: np.ndarray

    def on_episode(self, run: RunState, lane: int) -> None:
        if run.done % self.every == 0:
            with run.agent.reporting():
                run.stages.append((run.done, greedy_rollouts(run.agent, self.env, self.starts)))


@dataclass
class ValidationChecks(Callback):
    """Every ``every`` finished episodes (0: never), the greedy check on the validation starts,
    to TensorBoard."""

    every: int
    env: UAVNavEnv
    log: RunLog

    def on_episode(self, run: RunState, lane: int) -> None:
        if self.every and run.done % self.every == 0:
            with run.agent.reporting():
                success, excess = run.checks.check(run.agent, self.env, run.done)
            self.log.tb.add_scalar("validation/success", success, run.done)
            self.log.tb.add_scalar("validation/mean_excess_cost", excess, run.done)


@dataclass
class TimeBudget(Callback):
    """Ends training at the first finished episode past ``budget_s`` of training (0: none)."""

    budget_s: float

    def on_step(self, run: RunState, before: int) -> bool:
        return bool(self.budget_s) and run.seconds() >= self.budget_s


@dataclass
class Checkpoint:
    """The run's state to ``path`` every ``checkpoint_every`` finished episodes, at the last one,
    and when a callback ends training (the budget's or a user's), so a resumed run continues
    from there; ``stop_after``: end the call, as an interruption would, at the first checkpoint
    with at least that many finished episodes. The loop calls it after the callbacks."""

    path: Path
    cfg: TrainConfig
    log: RunLog
    stop_after: int | None = None

    def after(self, run: RunState, before: int, stopping: bool) -> bool:
        """Saves the checkpoint if it is due.

        Args:
            run: The run's state.
            before: The episodes finished before the step.
            stopping: A callback ends training (the checkpoint is then written).

        Returns:
            True where `stop_after` ends the call.
        """
        n, every, episodes = run.done, self.cfg.checkpoint_every, self.cfg.dqn.episodes
        if n // every > before // every or n == episodes or stopping:
            self.log.fh.flush()
            checkpoint.save(self.path, run.state_dict(self.cfg))
            return self.stop_after is not None and self.stop_after <= n < episodes
        return False
