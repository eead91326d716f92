"""The registered environment ``rainuav/UAVNav-v0``: a map joined to the navigation task.

``gym.make("rainuav/UAVNav-v0", ...)`` calls :func:`make_nav_env` and
``gym.make_vec("rainuav/UAVNav-v0", num_envs=N, vectorization_mode="vector_entry_point")``
calls :func:`make_nav_vector_env`. Either takes one map source:

- ``radio_map=`` a :class:`rainuav.radio.RadioMap`;
- ``scenario=`` a preset name (``"paper"``, ``"uma"``, ``"rain_cell"``, ``"urban"``) or a
  :class:`rainuav.radio.Scenario`, with ``rain_rate_mm_h`` (homogeneous rain in place of its
  weather), ``freq_hz`` and ``engine`` optional: the map is built, or taken from the cache
  (``engine="ray"`` builds any preset in about a second; the default hybrid takes longer);
- a raw ``sinr_db`` or ``sir_db`` array with ``extent_m``;

and the task's fields as keywords (:class:`rainuav.nav.UAVNavEnv`: ``signal``, ``min_db``,
``goal_m``, ``step_m``, ...). Without ``min_db`` a preset's map uses the preset's documented
SINR threshold (``rainuav.radio.presets.SINR_THRESHOLDS_DB``).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.vector import UAVNavVectorEnv, check_num_envs
from rainuav.radio import presets
from rainuav.radio.radiomap import RadioMap, build_radio_map
from rainuav.radio.scenario import Scenario

__all__ = ["make_nav_env", "make_nav_vector_env", "scenario_map"]


def scenario_map(
    scenario: str | Scenario,
    rain_rate_mm_h: float | None = None,
    freq_hz: float | None = None,
    engine: str | None = None,
    progress: bool = False,
) -> RadioMap:
    """The radio map of a preset (by name) or a Scenario, with homogeneous rain at
    ``rain_rate_mm_h`` (0: clear air), the carrier ``freq_hz`` and the propagation ``engine``
    (``"hybrid"``, ``"ray"`` or ``"pe"``) in place of its own when given; built, or taken from
    the cache."""
    if isinstance(scenario, str):
        if scenario not in presets.PRESETS:
            raise InvalidInputError(
                f"scenario must be one of {sorted(presets.PRESETS)} or a Scenario "
                f"(got {scenario!r})"
            )
        scn = presets.PRESETS[scenario]()
    elif isinstance(scenario, Scenario):
        scn = scenario
    else:
        raise InvalidInputError(
            f"scenario must be a preset name or a Scenario (got {type(scenario).__name__})"
        )
    if freq_hz is not None:
        scn = dataclasses.replace(scn, freq_hz=freq_hz)
    if engine is not None:
        scn = dataclasses.replace(scn, engine=engine)
    if rain_rate_mm_h is not None:
        scn = presets.with_rain(scn, rain_rate_mm_h)
    return build_radio_map(scn, progress=progress)


def _map_kwargs(radio_map: Any, scenario: Any, weather: dict[str, Any]) -> dict[str, Any]:
    if scenario is None:
        given = sorted(k for k, v in weather.items() if v is not None)
        if given:
            raise InvalidInputError(f"{given[0]} needs scenario=")
        return {"radio_map": radio_map} if radio_map is not None else {}
    if radio_map is not None:
        raise InvalidInputError("give radio_map or scenario, not both")
    return {"radio_map": scenario_map(scenario, **weather)}


def make_nav_env(
    radio_map: RadioMap | None = None,
    *,
    scenario: str | Scenario | None = None,
    rain_rate_mm_h: float | None = None,
    freq_hz: float | None = None,
    engine: str | None = None,
    **task: Any,
) -> UAVNavEnv:
    """The navigation environment over a map, a scenario's map or a raw array (module
    docstring)."""
    weather = {"rain_rate_mm_h": rain_rate_mm_h, "freq_hz": freq_hz, "engine": engine}
    return UAVNavEnv(**_map_kwargs(radio_map, scenario, weather), **task)


def make_nav_vector_env(
    num_envs: int = 1,
    radio_map: RadioMap | None = None,
    *,
    scenario: str | Scenario | None = None,
    rain_rate_mm_h: float | None = None,
    freq_hz: float | None = None,
    engine: str | None = None,
    autoreset_mode: Any = "NextStep",
    **task: Any,
) -> UAVNavVectorEnv:
    """``num_envs`` UAVs on one map, batched (:class:`rainuav.nav.vector.UAVNavVectorEnv`)."""
    check_num_envs(num_envs)  # before the map is built
    env = make_nav_env(
        radio_map,
        scenario=scenario,
        rain_rate_mm_h=rain_rate_mm_h,
        freq_hz=freq_hz,
        engine=engine,
        **task,
    )
    return UAVNavVectorEnv(env, num_envs, autoreset_mode)
