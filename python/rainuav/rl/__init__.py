"""Learning to fly: the dueling double DQN (:mod:`~rainuav.rl.dqn`), its configuration
(:mod:`~rainuav.rl.config`), what it learns from (:mod:`~rainuav.rl.learner`), flights
(:mod:`~rainuav.rl.collect`), measurement (:mod:`~rainuav.rl.evaluation`), the training loop
(:mod:`~rainuav.rl.loop`) and its figures (:mod:`~rainuav.rl.plots`). The design choices and
what they measured: ``docs/guide/learning.md``.
"""

from __future__ import annotations

from rainuav.rl.config import DQNConfig, TrainConfig
from rainuav.rl.dqn import Agent
from rainuav.rl.loop import train

__all__ = ["Agent", "DQNConfig", "TrainConfig", "train"]
