"""The training loop's parts: one state object that a checkpoint saves and a resumed run restores
by the same code, and callbacks that a user can add (one may end training)."""

from __future__ import annotations

from pathlib import Path

import pytest
from rainuav.nav.task import NavConfig
from rainuav.rl.callbacks import Callback, RunState
from rainuav.rl.config import DQNConfig, TrainConfig
from rainuav.rl.loop import CHECKPOINT_KEYS, train
from rainuav.world import in_world
from test_nav_tasks import _map


def _cfg(out: Path, episodes: int = 9) -> TrainConfig:
    return TrainConfig(
        out=str(out), task=NavConfig(goal_m=(300.0, 350.0), max_steps=30), eval_starts=3,
        validate_every=0, checkpoint_every=3,
        dqn=DQNConfig(episodes=episodes, lanes=2, learning_starts=16, batch_size=8),
    )  # fmt: skip


class Counts(Callback):
    """Counts the finished episodes it is told of, and ends training after ``stop_at``."""

    def __init__(self, stop_at: int) -> None:
        self.episodes: list[int] = []
        self.steps = 0
        self.stop_at = stop_at

    def on_episode(self, run: RunState, lane: int) -> None:
        self.episodes.append(run.done)

    def on_step(self, run: RunState, before: int) -> bool:
        self.steps += 1
        return run.done >= self.stop_at


@pytest.mark.slow
def test_a_users_callback_sees_every_episode_and_may_end_training(tmp_path: Path) -> None:
    from rainuav.rl.checkpoint import load

    counts = Counts(stop_at=4)
    m = train(*in_world(_cfg(tmp_path), _map()), progress=False, callbacks=[counts])
    # Two UAVs at a time: the step that finishes the fourth episode may finish a fifth.
    assert counts.episodes == list(range(1, len(counts.episodes) + 1))
    assert 4 <= m["episodes"] == len(counts.episodes) <= 5 and counts.steps >= 2
    # The checkpoint holds the state where the callback ended training (all of what RunState
    # saves, in the keys a resumed run reads), so a resumed run goes on from there to the end.
    saved = load(tmp_path / "checkpoint.pt", CHECKPOINT_KEYS)
    from rainuav.rl.callbacks import RunState

    assert CHECKPOINT_KEYS == RunState.KEYS and set(saved) == {*RunState.KEYS, "map_digest", "pool"}
    assert len(saved["returns"]) == m["episodes"] and saved["started"] <= 9
    assert (tmp_path / "policy.pt").exists() and (tmp_path / "metrics.json").exists()
    resumed = train(*in_world(_cfg(tmp_path), _map()), progress=False, resume=True)
    assert resumed["episodes"] == 9
