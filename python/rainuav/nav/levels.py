"""The navigation task in three dimensions: altitude as a decision.

The UAV flies on a stack of levels (one signal per flight altitude, lowest first; each a map
or maps in time, each with its not-flyable pixels) and has six moves: the plane's four on its
level ([`rainuav.nav.task`][rainuav.nav.task]) and a climb or a descent of one level.

- **Clock.** The flight's clock ticks once per horizontal move (``move_s`` seconds). A climb lasts
  the gap over ``climb_m_s`` and a descent the gap over ``descend_m_s``, rounded up to whole ticks
  ([`level_durations()`][rainuav.nav.levelfield.level_durations]; the defaults, 15 m gaps and 1 s
  moves: 3 and 5). A move lands at the tick its duration later and reads the signal there and then.
- **Rewards.** A move earns its duration in ticks times the base reward where and when it
  lands (``-1 - mu shortfall`` by default): the flight's cost is its time plus the weighted
  shortfall, each move weighted by how long it lasts. Leaving the area, climbing above the
  highest level or descending below the lowest, or entering a not-flyable cell of a level
  ends the flight with ``out_of_bounds_penalty`` (the UAV stays where it was, on its level,
  for a move out of the band). Arriving within ``tol_m`` of the destination's horizontal
  position, at any level, pays ``goal_reward`` (the landing is the autopilot's).
- **Horizon.** ``max_steps`` ticks: the flight is cut when its clock reaches it (one level:
  ``max_steps`` moves, the plane's task, same returns: tested).
- **Observation.** Position scaled to [0, 1]^2, the level over the highest level index (0 on
  one level), and where the signal moves the clock over ``max_steps``. ``info`` adds
  ``altitude_m`` and ``level`` to the plane's keys. With ``observation="weather"`` the
  [`WeatherView`][rainuav.nav.views.WeatherView] of every level (one layer a level: the signal now
  around the UAV and over the area), its position, destination, clock and level; then
  ``random_goal`` draws a destination per flight, and a field of banks (a storm pool among
  levels) a world per flight, as ``UAVNavEnv`` does.

The environment is [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv] given a field with flight levels (a
[`SignalField`][rainuav.nav.field.SignalField] with ``altitudes_m``); ``UAVLevelsEnv(field, config,
...)`` is the same
class built with the arguments it has always taken. The exact optimum of this task is
[`rainuav.nav.planner.optimal_levels()`][rainuav.nav.planner.optimal_levels]
(``rainuav_core::planning::planlevels``), which reads the signal operation for operation as
[`LevelStepper`][rainuav.nav.levelfield.LevelStepper] does; its plans replayed here earn its returns
(tested)."""

from __future__ import annotations

from typing import Any

from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.levelfield import CLIMB_M_S, DESCEND_M_S
from rainuav.nav.task import NavConfig
from rainuav.nav.views import WeatherView

__all__ = ["CLIMB_M_S", "DESCEND_M_S", "UAVLevelsEnv"]


class UAVLevelsEnv(UAVNavEnv):
    """[`UAVNavEnv`][rainuav.nav.env.UAVNavEnv] built among the levels of ``field``.

    ``Discrete(6)`` (module docstring); the constructor with the arguments it has always taken,
    no behaviour of its own."""

    def __init__(
        self,
        field: SignalField,
        config: NavConfig | None = None,
        *,
        climb_m_s: float = CLIMB_M_S,
        descend_m_s: float = DESCEND_M_S,
        start_level: int | None = None,
        observation: str = "position",
        view: WeatherView | None = None,
        random_goal: bool = False,
        **task: Any,
    ) -> None:
        """Builds the environment among the levels of a field.

        Args:
            field: A [`SignalField`][rainuav.nav.field.SignalField] among flight levels (with
                `altitudes_m`).
            config: The task ([`NavConfig`][rainuav.nav.task.NavConfig]); its `min_db` None: 10 dB.
            climb_m_s: The climb speed, m/s.
            descend_m_s: The descent speed, m/s.
            start_level: The level every flight starts at (default: the lowest flyable).
            observation: As [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv]'s.
            view: As [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv]'s.
            random_goal: As [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv]'s.
            **task: Fields of [`NavConfig`][rainuav.nav.task.NavConfig], over `config`'s.

        Raises:
            InvalidInputError: A field without flight levels, or an input `UAVNavEnv` refuses.
        """
        if not isinstance(field, SignalField) or field.altitudes_m is None:
            raise InvalidInputError(
                f"field must be a SignalField among flight levels, with altitudes_m (got "
                f"{type(field).__name__})"
            )
        super().__init__(
            field=field, config=config, climb_m_s=climb_m_s, descend_m_s=descend_m_s,
            start_level=start_level, observation=observation, view=view,
            random_goal=random_goal, **task,
        )  # fmt: skip
