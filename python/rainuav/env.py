"""Deprecated: the environment moved to :mod:`rainuav.nav` (this path goes in 0.3)."""

from __future__ import annotations

from rainuav._deprecated import moved, names

__getattr__ = moved(
    __name__,
    {
        **names("rainuav.nav.env", "UAVNavEnv"),
        **names("rainuav.nav.batch", "BatchStepper"),
        **names("rainuav.nav.field", "SirField"),
        **names(
            "rainuav.nav.task",
            "MOVES",
            "REWARDS",
            "LoiteringWarning",
            "NavConfig",
            "base_reward",
            "make_config",
        ),
    },
)
