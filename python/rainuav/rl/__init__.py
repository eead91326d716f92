"""Learning to fly: the dueling double DQN ([`dqn`][rainuav.rl.dqn]), its configuration
([`config`][rainuav.rl.config]), what it learns from ([`learner`][rainuav.rl.learner]), flights
([`collect`][rainuav.rl.collect]), measurement ([`evaluation`][rainuav.rl.evaluation]), the training
loop ([`loop`][rainuav.rl.loop]) and its figures ([`plots`][rainuav.rl.plots]). The design choices
and what they measured: ``docs/record/learning.md``."""

from __future__ import annotations

from rainuav.rl.config import DQNConfig, TrainConfig
from rainuav.rl.dqn import Agent
from rainuav.rl.loop import train

__all__ = ["Agent", "DQNConfig", "TrainConfig", "train"]
