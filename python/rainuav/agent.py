"""Deprecated: the DQN moved to :mod:`rainuav.rl.dqn` (this path goes in 0.3)."""

from __future__ import annotations

from rainuav._deprecated import moved, names

__getattr__ = moved(
    __name__,
    {
        **names(
            "rainuav.rl.dqn",
            "Agent",
            "DuelingQNet",
            "NStepWindow",
            "Replay",
            "best_action",
            "double_q_target",
        ),
        **names("rainuav.rl.config", "DQNConfig"),
    },
)
