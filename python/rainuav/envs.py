"""The registered environments ``rainuav/UAVNav-v0``, a world ([`rainuav.world`][rainuav.world]) as
a Gymnasium environment, and ``rainuav/UAVLevels-v0``, the same with altitude as a decision
([`make_levels_env()`][rainuav.envs.make_levels_env]).

``gym.make("rainuav/UAVNav-v0", ...)`` calls [`make_nav_env()`][rainuav.envs.make_nav_env] and
``gym.make_vec("rainuav/UAVNav-v0", num_envs=N, vectorization_mode="vector_entry_point")``
calls [`make_nav_vector_env()`][rainuav.envs.make_nav_vector_env]. Either takes one signal source:

- ``radio_map=`` a [`rainuav.radio.RadioMap`][rainuav.radio.outputs.mapdata.RadioMap];
- ``scenario=`` a preset name (``"paper"``, ``"uma"``, ``"rain_cell"``, ``"urban"``, ``"storm"``) or
  a [`rainuav.radio.Scenario`][rainuav.radio.scene.scenario.Scenario], with ``rain_rate_mm_h``
  (homogeneous rain in place of its weather), ``freq_hz``, ``engine``, ``storm_seed`` (the ``storm``
  preset's storm) and ``slice_s`` (time between the maps of a weather that moves) optional: the
  world is built ([`rainuav.world.build_world()`][rainuav.world.build_world]), or taken from the
  cache (``engine="ray"`` builds any preset in about a second; the default hybrid takes longer); a
  weather that moves gives an environment whose signal changes in time;
- a raw ``sinr_db`` or ``sir_db`` array with ``extent_m``;

and the task's fields as keywords ([`rainuav.nav.task.NavConfig`][rainuav.nav.task.NavConfig]:
``signal``, ``min_db``, ``goal_m``, ``step_m``, ``speed_m_s``, ...), with ``observation="weather"``
(a ``Dict`` of the SINR around the UAV and over the area, its position, time and destination:
[`rainuav.nav.views`][rainuav.nav.views]) and ``random_goal=True`` (a destination per episode)
optional. Without ``min_db`` a preset's map uses the preset's documented SINR threshold
(``rainuav.radio.scene.presets.SINR_THRESHOLDS_DB``)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from rainuav._checks import check_number
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.task import NavConfig, make_config
from rainuav.nav.vector import UAVNavVectorEnv, check_num_envs
from rainuav.radio.outputs.maps import RadioMap
from rainuav.radio.scene.scenario import Scenario
from rainuav.world import WorldSpec, build_world

__all__ = ["make_levels_env", "make_nav_env", "make_nav_vector_env"]


def _spec(
    scenario: str | Scenario, weather: dict[str, Any], task: dict[str, Any]
) -> tuple[WorldSpec, NavConfig]:
    """The world spec of a scenario with these weather keywords and the task's fields (its
    ``task``; ``observation`` and ``random_goal`` are the spec's own), and the task."""
    if not isinstance(scenario, str | Scenario):
        raise InvalidInputError(
            f"scenario must be a preset name or a Scenario (got {type(scenario).__name__})"
        )
    shown = {k: task.pop(k) for k in ("observation", "random_goal") if k in task}
    nav = make_config(**task)
    freq = weather["freq_hz"]
    given = {
        "rain_rate_mm_h": weather["rain_rate_mm_h"],
        "engine": weather["engine"],
        "freq_ghz": None if freq is None else check_number("freq_hz", freq, 1e9, 100e9) / 1e9,
        "storm_seed": weather["storm_seed"],
        "slice_s": weather["slice_s"],
    }
    # numpy scalars (a seed from an rng, say) as the plain numbers a spec holds
    given = {k: v.item() if isinstance(v, np.generic) else v for k, v in given.items()}
    spec = WorldSpec(
        scenario=scenario if isinstance(scenario, str) else "paper",
        **{k: v for k, v in given.items() if v is not None},
        **shown,
        task=nav,
    )
    return spec, nav


def _world_env(
    scenario: str | Scenario, weather: dict[str, Any], task: dict[str, Any]
) -> UAVNavEnv:
    """The environment of a scenario's world with these weather and task keywords."""
    spec, nav = _spec(scenario, weather, task)
    scn = None if isinstance(scenario, str) else scenario
    return build_world(spec, task=nav, scenario=scn).env()


def make_nav_env(
    radio_map: RadioMap | None = None,
    *,
    scenario: str | Scenario | None = None,
    rain_rate_mm_h: float | None = None,
    freq_hz: float | None = None,
    engine: str | None = None,
    storm_seed: int | None = None,
    slice_s: float | None = None,
    **task: Any,
) -> UAVNavEnv:
    """The navigation environment over a map, a scenario's world or a raw array.

    What `gym.make("rainuav/UAVNav-v0", ...)` calls.

    Args:
        radio_map: A built map; None: a scenario's, or the raw arrays of `task`.
        scenario: A preset's name or a [`Scenario`][rainuav.radio.scene.scenario.Scenario].
        rain_rate_mm_h: Homogeneous rain, mm/h, in place of the scenario's weather.
        freq_hz: The carrier frequency, Hz, in place of the scenario's.
        engine: The propagation engine, in place of the scenario's.
        storm_seed: The storm of the 'storm' preset.
        slice_s: The time between the maps of a weather that moves, s.
        **task: [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv]'s keywords and the task's fields.

    Returns:
        The [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv].

    Raises:
        InvalidInputError: Both a map and a scenario, or a weather keyword without a scenario.
    """
    weather = {
        "rain_rate_mm_h": rain_rate_mm_h,
        "freq_hz": freq_hz,
        "engine": engine,
        "storm_seed": storm_seed,
        "slice_s": slice_s,
    }
    if scenario is None:
        given = sorted(k for k, v in weather.items() if v is not None)
        if given:
            raise InvalidInputError(f"{given[0]} needs scenario=")
        return UAVNavEnv(radio_map, **task)
    if radio_map is not None:
        raise InvalidInputError("give radio_map or scenario, not both")
    return _world_env(scenario, weather, task)


def make_nav_vector_env(
    num_envs: int = 1,
    radio_map: RadioMap | None = None,
    *,
    autoreset_mode: Any = "NextStep",
    **kw: Any,
) -> UAVNavVectorEnv:
    """Several UAVs in one world, batched ([`UAVNavVectorEnv`][rainuav.nav.vector.UAVNavVectorEnv]).

    Args:
        num_envs: How many UAVs.
        radio_map: A built map, as [`make_nav_env()`][rainuav.envs.make_nav_env]'s.
        autoreset_mode: Gymnasium's autoreset mode.
        **kw: The other keywords of `make_nav_env()`.

    Returns:
        The [`UAVNavVectorEnv`][rainuav.nav.vector.UAVNavVectorEnv].

    Raises:
        InvalidInputError: `num_envs` not allowed (checked before the map is built).
    """
    check_num_envs(num_envs)  # before the map is built
    return UAVNavVectorEnv(make_nav_env(radio_map, **kw), num_envs, autoreset_mode)


def make_levels_env(
    *,
    scenario: str | Scenario = "uma",
    altitudes_m: Any = (30.0, 45.0, 60.0, 75.0, 90.0, 105.0, 120.0),
    rain_rate_mm_h: float | None = None,
    freq_hz: float | None = None,
    engine: str | None = None,
    storm_seed: int | None = None,
    slice_s: float | None = None,
    climb_m_s: float | None = None,
    descend_m_s: float | None = None,
    start_level: int | None = None,
    observation: str = "position",
    random_goal: bool = False,
    **task: Any,
) -> Any:
    """The navigation task with altitude as a decision: `gym.make("rainuav/UAVLevels-v0", ...)`.

    Over the scenario's maps at each of `altitudes_m` (in time where its weather moves, every
    `slice_s` over the horizon); [`rainuav.nav.levels`][rainuav.nav.levels] has the task.

    Args:
        scenario: A preset's name or a [`Scenario`][rainuav.radio.scene.scenario.Scenario].
        altitudes_m: The flight levels, m, increasing.
        rain_rate_mm_h: As [`make_nav_env()`][rainuav.envs.make_nav_env]'s.
        freq_hz: As `make_nav_env()`'s.
        engine: As `make_nav_env()`'s.
        storm_seed: As `make_nav_env()`'s.
        slice_s: As `make_nav_env()`'s.
        climb_m_s: The climb speed, m/s.
        descend_m_s: The descent speed, m/s.
        start_level: The level every flight starts at (default: the lowest flyable at the start).
        observation: "position", or "weather": every level's weather
            ([`WeatherView`][rainuav.nav.views.WeatherView], one layer a level).
        random_goal: A destination drawn per episode.
        **task: The task's fields (`min_db` by default the preset's SINR threshold).

    Returns:
        The [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv] among levels.

    Raises:
        InvalidInputError: A task that does not fly the SINR, or levels not allowed.
    """
    from rainuav.nav.levels import CLIMB_M_S, DESCEND_M_S
    from rainuav.radio.scene.presets import SINR_THRESHOLDS_DB
    from rainuav.world import level_field, make_scenario, series_instants

    if "signal" in task:
        raise InvalidInputError("signal: the environment among levels flies the SINR")
    weather = {"rain_rate_mm_h": rain_rate_mm_h, "freq_hz": freq_hz, "engine": engine,
               "storm_seed": storm_seed, "slice_s": slice_s}  # fmt: skip
    spec, nav = _spec(scenario, weather, task)
    scn = make_scenario(spec, None if isinstance(scenario, str) else scenario)
    scn = scn.replace(area=dataclasses.replace(scn.area, altitudes_m=list(altitudes_m)))
    scn.area.check()
    field, _ = level_field(scn, series_instants(spec) if scn.medium.moves else None)
    if nav.min_db is None:
        nav = dataclasses.replace(nav, min_db=SINR_THRESHOLDS_DB.get(scn.name, 10.0))
    return UAVNavEnv(
        field=field,
        config=nav,
        climb_m_s=CLIMB_M_S if climb_m_s is None else climb_m_s,
        descend_m_s=DESCEND_M_S if descend_m_s is None else descend_m_s,
        start_level=start_level,
        observation=observation,
        random_goal=random_goal,
    )
