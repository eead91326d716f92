"""What a world is built from: a [`WorldSpec`][rainuav.world.spec.WorldSpec] (the scenario, its
weather, the flight levels and the task), its checks, and the scenario it names."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from rainuav._checks import check_field_kinds
from rainuav._cli import altitude_band
from rainuav.errors import InvalidInputError
from rainuav.nav.task import NavConfig, check_task
from rainuav.radio.engines import ENGINES as RADIO_ENGINES
from rainuav.radio.scene import presets
from rainuav.radio.scene.scenario import Scenario
from rainuav.radio.scene.storms import check_storm_seed

__all__ = [
    "ENGINES",
    "MAX_POOL",
    "WorldSpec",
    "check_spec",
    "levels_of",
    "make_scenario",
    "spec_of",
    "task_of",
]

ENGINES = ("", *RADIO_ENGINES)
"""The engines a spec may name ('' the scenario's own)."""
MAX_POOL = 64
"""The most storms flown at once (each holds its maps in time: about 20 MB)."""


@dataclass
class WorldSpec:
    """What a world is built from: the scenario and its weather, then the task (one docstring
    line per field = one CLI flag of ``rainuav.train``)."""

    scenario: str = "paper"
    """Preset scenario ('paper', 'uma', 'rain_cell', 'urban' or 'storm'), unless
    --scenario-file."""
    scenario_file: str = ""
    """A scenario TOML file (overrides --scenario)."""
    rain_rate_mm_h: float | None = None
    """Homogeneous rain, mm/h, in place of the scenario's weather (0: clear air; the rain
    model, drop sizes, shape, temperature and wind stay the scenario's; for 'storm', the
    storm's background rate); unset: the scenario's own weather (the paper preset rains
    25 mm/h)."""
    engine: str = ""
    """Propagation engine: 'hybrid', 'ray' or 'pe'; '' the scenario's own."""
    freq_ghz: float | None = None
    """Carrier frequency, GHz (1-100), in place of the scenario's; unset: the scenario's."""
    storm_seed: int = 0
    """The random storm of the 'storm' scenario (seeds from 1 000 000 are reserved for
    evaluation)."""
    storm_speed_m_s: float | None = None
    """The 'storm' scenario's speed, m/s, in place of the drawn one (every cell's velocity
    scaled alike; 0: cells stay put and only grow or decay); unset: as drawn."""
    slice_s: float = 5.0
    """Time between the maps of a weather that moves, s (the signal is linear in between)."""
    observation: str = "position"
    """What the UAV observes: 'position' (and the time where the weather moves) or 'weather'
    (the SINR around it and over the area, its position, time and destination:
    rainuav.nav.views)."""
    random_goal: bool = False
    """A destination drawn per episode (rainuav.nav.views.sample_goal; needs --observation
    weather) in place of the fixed one (the storms presets set it)."""
    storm_pool: int = 0
    """Train over the storm distribution: this many storms flown at once, each renewed with
    a new training storm as training goes (the storms preset sets 16; needs --scenario storm
    and --observation weather); 0: the one storm of storm_seed."""
    calm_share: float = 0.0
    """Of a storm pool's storms, the share flown calm: the storm's uniform background rain
    alone, its cells left out (rainuav.world.pool.is_calm says which seeds)."""
    altitudes_m: tuple[float, ...] | str = ""
    """Flight levels, m: LOW:HIGH:STEP (e.g. 25:115:15) or a list of heights; altitude as a
    decision, six moves (rainuav.nav.levels: climb and descend one level, each lasting its
    duration), flights starting at the lowest level (the weather observation then shows every
    level); '' the scenario's one altitude."""
    task: NavConfig = dataclasses.field(default_factory=NavConfig)
    """The navigation task (rainuav.nav.task.NavConfig: destination, moves, reward, outage
    threshold, horizon), the [task] table of a run's file and the flags --task.NAME."""

    def __post_init__(self) -> None:
        if isinstance(self.altitudes_m, list):  # as read from a file: a tuple, so specs compare
            self.altitudes_m = tuple(self.altitudes_m)

    def __setattr__(self, name: str, value: Any) -> None:
        # A field of the task, or a misspelt one, set here would be silently ignored.
        if name not in self.__dataclass_fields__:
            hint = f": the task's, .task.{name}" if name in NavConfig.__dataclass_fields__ else ""
            raise AttributeError(f"{type(self).__name__} has no field {name!r}{hint}")
        super().__setattr__(name, value)


def spec_of(obj: Any) -> WorldSpec:
    """The world part of a configuration, as a [`WorldSpec`][rainuav.world.spec.WorldSpec].

    Args:
        obj: A `WorldSpec`, or a configuration that extends one (a
            [`TrainConfig`][rainuav.rl.config.TrainConfig]).

    Returns:
        A new `WorldSpec` with `obj`'s values of the spec's fields.
    """
    return WorldSpec(**{f.name: getattr(obj, f.name) for f in dataclasses.fields(WorldSpec)})


def task_of(spec: WorldSpec) -> NavConfig:
    """The navigation task a spec names.

    Args:
        spec: A [`WorldSpec`][rainuav.world.spec.WorldSpec] (or a configuration extending one).

    Returns:
        Its `task`, a [`NavConfig`][rainuav.nav.task.NavConfig].
    """
    return spec.task


def levels_of(spec: WorldSpec) -> list[float]:
    """The flight levels a spec names, in metres.

    Args:
        spec: A spec whose `altitudes_m` is a `LOW:HIGH:STEP` band, a list of heights or ''.

    Returns:
        The heights, m, in the order given ([] for '': the scenario's one altitude).

    Raises:
        InvalidInputError: `altitudes_m` is neither a band nor a list of finite heights.
    """
    v = spec.altitudes_m
    if isinstance(v, str):
        return altitude_band(v, "altitudes_m") if v else []
    if (
        isinstance(v, list | tuple)
        and v
        and all(
            isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) for x in v
        )
    ):
        return [float(x) for x in v]
    raise InvalidInputError(
        f"altitudes_m must be LOW:HIGH:STEP or a non-empty list of heights, m (got {v!r})"
    )


def check_spec(spec: WorldSpec) -> None:
    """Checks every field of a spec, its task's included, before anything is built.

    Args:
        spec: A [`WorldSpec`][rainuav.world.spec.WorldSpec] (or a configuration extending one).

    Raises:
        InvalidInputError: The first field of the wrong kind or outside its range, named with its
            allowed range (the task's fields as `task.NAME`).
    """
    check_field_kinds(spec, only=WorldSpec)  # the kinds first: a caller can hand in anything
    if not isinstance(spec.task, NavConfig):
        raise InvalidInputError(f"task must be a NavConfig (got {type(spec.task).__name__})")
    check_field_kinds(spec.task, "task.")
    check_task(spec.task, "task.")
    checks = [
        ("engine", spec.engine in ENGINES, "'', 'hybrid', 'ray' or 'pe'"),
        ("freq_ghz", spec.freq_ghz is None or 1 <= spec.freq_ghz <= 100, "unset or in [1, 100]"),
        ("storm_speed_m_s", spec.storm_speed_m_s is None or 0 <= spec.storm_speed_m_s <= 100,
         "unset or in [0, 100] m/s"),
        ("slice_s", 0.001 <= spec.slice_s <= 1e6, "in [0.001, 1e6] s"),
        ("observation", spec.observation in ("position", "weather"), "'position' or 'weather'"),
        ("random_goal", not spec.random_goal or spec.observation == "weather",
         "false unless observation = 'weather' (the position alone does not show it)"),
        ("storm_pool", 0 <= spec.storm_pool <= MAX_POOL, f"in 0..{MAX_POOL}"),
        ("storm_pool", spec.storm_pool == 0 or (spec.scenario == "storm"
         and not spec.scenario_file and spec.observation == "weather"),
         "0 unless scenario = 'storm' and observation = 'weather'"),
        ("calm_share", 0 <= spec.calm_share <= 1, "in [0, 1] (read by a storm pool alone)"),
        ("rain_rate_mm_h", spec.rain_rate_mm_h is None or 0 <= spec.rain_rate_mm_h <= 500,
         "unset or in [0, 500] mm/h"),
        ("altitudes_m", not spec.altitudes_m or spec.task.signal == "sinr",
         "'' unless task.signal = 'sinr'"),
    ]  # fmt: skip
    for name, ok, allowed in checks:
        if not ok:
            raise InvalidInputError(f"{name} must be {allowed} (got {getattr(spec, name)!r})")
    check_storm_seed(spec.storm_seed)
    levels_of(spec)


def make_scenario(spec: WorldSpec, scenario: Scenario | None = None) -> Scenario:
    """The scenario a spec names, with the spec's weather, frequency, engine and levels applied.

    The scenario is, in this order: `scenario` where given, the spec's `scenario_file`, the storm of
    `storm_seed` for the preset 'storm', or the preset named. Then `rain_rate_mm_h`, `freq_ghz`,
    `engine` and `altitudes_m` replace the scenario's own where they are set.

    Args:
        spec: A [`WorldSpec`][rainuav.world.spec.WorldSpec] (or a configuration extending one).
        scenario: A scenario in place of the spec's preset or file.

    Returns:
        The [`Scenario`][rainuav.radio.scene.scenario.Scenario] to map.

    Raises:
        InvalidInputError: An unknown preset, an unreadable scenario file or levels outside the
            area.
    """
    if scenario is not None:
        scn = scenario
    elif spec.scenario_file:
        scn = Scenario.from_toml(spec.scenario_file)
    elif spec.scenario == "storm":
        scn = presets.storm(
            spec.rain_rate_mm_h,
            seed=check_storm_seed(spec.storm_seed),
            speed_m_s=spec.storm_speed_m_s,
        )
    elif spec.scenario in presets.PRESETS:
        scn = presets.PRESETS[spec.scenario]()
    else:
        raise InvalidInputError(
            f"scenario must be one of {sorted(presets.PRESETS)} (got {spec.scenario!r})"
        )
    if spec.rain_rate_mm_h is not None and (scenario is not None or spec.scenario != "storm"):
        scn = presets.with_rain(scn, spec.rain_rate_mm_h)
    if spec.freq_ghz is not None:
        scn = dataclasses.replace(scn, freq_hz=spec.freq_ghz * 1e9)
    if spec.engine:
        scn = dataclasses.replace(scn, engine=spec.engine)
    if spec.altitudes_m:
        area = dataclasses.replace(scn.area, altitudes_m=levels_of(spec))
        area.check("altitudes_m")
        scn = scn.replace(area=area)
    return scn
