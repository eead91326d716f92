"""Navigation: the task ([`task`][rainuav.nav.task]), the signal field
([`field`][rainuav.nav.field]), the Gymnasium environment ([`env`][rainuav.nav.env],
``rainuav/UAVNav-v0``), the batched stepper ([`batch`][rainuav.nav.batch]), the exact planner and
baselines ([`planner`][rainuav.nav.planner]), the shield ([`shield`][rainuav.nav.shield]) and the
task with altitude as a decision ([`levels`][rainuav.nav.levels], six moves among flight levels).

Works on any (H, W) map in dB (a RadioMap is read through its attributes); knows nothing of how maps
are built ([`rainuav.radio`][rainuav.radio]; ``rainuav.envs`` joins the two for ``gym.make``) and
does not import torch."""

from __future__ import annotations

from rainuav.nav.batch import BatchStepper
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.levels import UAVLevelsEnv
from rainuav.nav.planner import Plan, optimal, optimal_many, straight_line
from rainuav.nav.shield import shield_moves
from rainuav.nav.task import (
    MOVES,
    REWARDS,
    SIGNALS,
    LoiteringWarning,
    NavConfig,
    base_reward,
    flight_cost,
)

__all__ = [
    "MOVES",
    "REWARDS",
    "SIGNALS",
    "BatchStepper",
    "LoiteringWarning",
    "NavConfig",
    "Plan",
    "SignalField",
    "UAVLevelsEnv",
    "UAVNavEnv",
    "base_reward",
    "flight_cost",
    "optimal",
    "optimal_many",
    "shield_moves",
    "straight_line",
]
