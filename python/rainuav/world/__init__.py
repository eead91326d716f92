"""The world a UAV flies: a signal field in time joined to a navigation task, built from one spec
([`WorldSpec`][rainuav.world.WorldSpec]) for every entry point: ``gym.make("rainuav/UAVNav-v0")``,
``python -m rainuav.train``, ``rainuav.evaluate`` and the studies.

Where things go: a new weather is a [`rainuav.radio.Medium`][rainuav.radio.scene.weather.Medium]
kind (``radio``); a new task rule goes in [`rainuav.nav`][rainuav.nav] (``NavConfig`` and
``UAVNavEnv``); a new learner goes in [`rainuav.rl`][rainuav.rl] and receives a built
[`World`][rainuav.world.World] (or its env), the way Stable-Baselines3's ``DQN(env).learn()`` does.
This module is the only place where a scenario, its weather and a task become something to fly; it
sits above ``radio`` and ``nav`` and below ``rl``.

A spec names the scenario (a preset, or a scenario file), its weather (the scenario's own,
homogeneous rain at ``rain_rate_mm_h``, or the random storm ``storm_seed`` of the ``storm``
preset), the propagation engine, the flight levels and the task
([`NavConfig`][rainuav.nav.task.NavConfig], its ``task``). A weather that moves is mapped at
instants ``slice_s`` apart over the task's horizon (``max_steps`` moves of ``step_m /
speed_m_s`` seconds; [`rainuav.radio.outputs.timemap`][rainuav.radio.outputs.timemap]), and the UAV
flies the series ([`rainuav.nav.field.SignalSeries`][rainuav.nav.field.SignalSeries])"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tomllib

from rainuav._checks import check_field_kinds
from rainuav._cli import altitude_band
from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.levelfield import field_of
from rainuav.nav.task import NavConfig, check_config, check_task
from rainuav.nav.vector import UAVNavVectorEnv
from rainuav.radio.engines import ENGINES as RADIO_ENGINES
from rainuav.radio.engines import for_time
from rainuav.radio.outputs.levelmaps import LevelStack
from rainuav.radio.outputs.mapdata import RadioMap, default_min_db
from rainuav.radio.outputs.maps import build_radio_map
from rainuav.radio.outputs.signals import signal_of
from rainuav.radio.outputs.timemap import RadioMapSeries, build_radio_map_series, series_times
from rainuav.radio.scene import presets
from rainuav.radio.scene.scenario import Scenario
from rainuav.radio.scene.storms import check_storm_seed
from rainuav.signals import Signal

__all__ = [
    "MAP_FILES",
    "SLICE_S",
    "World",
    "WorldSpec",
    "build_source",
    "build_world",
    "check_spec",
    "in_world",
    "level_field",
    "levels_of",
    "load_world",
    "make_scenario",
    "saved_world",
    "source_key",
    "spec_of",
    "task_of",
    "world_from",
]

MAP_FILES = ("radiomap.npz", "radiomap_series.npz", "radiolevels.npz", "signal.npz")
"""The files a world's signal is saved in: a single map, maps in time, the maps of every
flight level
([`rainuav.radio.outputs.levelmaps.LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack]), or
a world made of a [`Signal`][rainuav.signals.Signal]."""
_SOURCES = (RadioMap, RadioMapSeries, LevelStack, Signal)
ENGINES = ("", *RADIO_ENGINES)
MAX_POOL = 64
"""The most storms flown at once (each holds its maps in time: about 20 MB)."""
SLICE_S = 5.0
"""Time between the maps ``fly`` makes of a weather file with several instants, s."""


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
    """The world part of ``obj`` (a WorldSpec, or a configuration that extends one)."""
    return WorldSpec(**{f.name: getattr(obj, f.name) for f in dataclasses.fields(WorldSpec)})


def task_of(spec: WorldSpec) -> NavConfig:
    """The navigation task a spec names (its ``task``)."""
    return spec.task


def levels_of(spec: Any) -> list[float]:
    """The flight levels a spec names, m (``altitudes_m``: a LOW:HIGH:STEP band or a list of
    heights; [] for none), else one line naming the field."""
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


def check_spec(spec: Any) -> None:
    """Raises InvalidInputError naming the first field of the spec of the wrong kind or
    outside its range (the task's as ``task.NAME``)."""
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


def make_scenario(spec: Any, scenario: Scenario | None = None) -> Scenario:
    """The scenario of a spec: the preset (the storm of ``storm_seed`` for 'storm') or the
    file, or ``scenario`` where given, with ``rain_rate_mm_h``, ``freq_ghz`` and ``engine`` applied
    if set."""
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


@dataclass
class World:
    """A signal (one map, or maps in time) and the task flown on it (``min_db`` resolved)."""

    source: RadioMap | RadioMapSeries | LevelStack | Signal | None
    """What the signal is read from (saved with a run; None for a storm pool's bank)."""
    field: SignalField
    """The signal the UAV flies through (with flight levels where altitude is a decision)."""
    task: NavConfig
    """The navigation task."""
    observation: str = "position"
    """What the UAV observes (``UAVNavEnv``'s ``observation``)."""
    random_goal: bool = False
    """A destination drawn per episode."""
    pool: Any = None
    """The [`StormPool`][rainuav.world.pool.StormPool] whose bank is the field, where the world is
    one."""

    @property
    def varies(self) -> bool:
        """Whether the signal changes in time."""
        return self.field.varies

    def env(self) -> Any:
        """A Gymnasium environment of this world (a fresh one per call): a
        [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv], on one level or among several."""
        return UAVNavEnv(
            field=self.field,
            config=self.task,
            observation=self.observation,
            random_goal=self.random_goal,
        )

    def vector_env(self, num_envs: int, autoreset_mode: Any = "NextStep") -> UAVNavVectorEnv:
        """``num_envs`` UAVs in this world, batched."""
        return UAVNavVectorEnv(self.env(), num_envs, autoreset_mode)

    def save(self, folder: Path) -> Path | None:
        """Writes the signal's source into ``folder`` ([`MAP_FILES`][rainuav.world.MAP_FILES]),
        atomically (a storm pool's storms are not saved: their seeds rebuild them)."""
        if self.source is None:
            return None
        kind = next(k for k in _SOURCES if isinstance(self.source, k))
        name = MAP_FILES[_SOURCES.index(kind)]
        return self.source.save(Path(folder) / name)


def world_from(source: Any, task: NavConfig) -> World:
    """The world of a built map, series or stack of levels, or of a
    [`Signal`][rainuav.signals.Signal], and a task (``min_db`` unset: the scenario's documented
    threshold for the signal flown). Every kind is read as one signal
    ([`signal_of()`][rainuav.radio.outputs.signals.signal_of]) and flown through the field its
    axes ask for ([`field_of()`][rainuav.nav.levelfield.field_of])."""
    signal = task.signal
    if isinstance(source, Signal):
        if source.name != f"{signal}_db":
            raise InvalidInputError(
                f"task.signal is {signal!r} but the signal given is {source.name}"
            )
        sig = source
    elif isinstance(source, RadioMap | RadioMapSeries | LevelStack):
        sig = signal_of(source, signal, scenario_toml=False)
    else:
        raise InvalidInputError(
            "a world needs a RadioMap, RadioMapSeries, LevelStack or Signal (got "
            f"{type(source).__name__})"
        )
    field = field_of(sig)
    min_db = task.min_db
    if min_db is None:  # the same rule for every kind (by the scenario's name)
        min_db = default_min_db(_scenario_name(source), signal)
    if task.reward == "chance":  # outage as a probability, from the map's spreads
        if not isinstance(field, SignalField) or not isinstance(source, RadioMap):
            raise InvalidInputError(
                "task.reward 'chance' flies one radio map (a physics map with its prior's "
                "spreads, or one corrected by measurements: rainuav.radio.measured.correct_map)"
            )
        if signal != "sinr":
            raise InvalidInputError("task.reward 'chance' is the SINR's outage: task.signal sinr")
        from rainuav.radio.measured.outage import outage_probability

        field.outage_p = outage_probability(source, min_db)
    return World(source, field, dataclasses.replace(task, min_db=min_db))


def series_instants(spec: Any) -> Any:
    """The instants a moving weather is mapped at: every ``slice_s`` from 0 over the task's
    horizon (rounded up to a whole slice)."""
    task = spec.task
    horizon = task.max_steps * task.step_m / task.speed_m_s
    return series_times(math.ceil(horizon / spec.slice_s - 1e-9) * spec.slice_s, spec.slice_s)


def level_field(
    scn: Scenario, times_s: Any = None, *, progress: bool = False, cache: bool = True
) -> tuple[Any, Any]:
    """The signal at every level of ``scn``'s ``area.altitudes_m`` as a
    [`SignalField`][rainuav.nav.field.SignalField] with those altitudes (what the flights among
    levels read), and the maps it came from:
    [`rainuav.radio.outputs.levelmaps.build_radio_levels()`][rainuav.radio.outputs.levelmaps.build_radio_levels],
    or where ``times_s`` are given
    [`build_radio_level_series()`][rainuav.radio.outputs.levelmaps.build_radio_level_series] (engine
    'pe' then becomes 'hybrid': a march per cell and instant is refused). ``cache=False``: maps
    flown once (a storm pool's), not kept in the map cache."""
    from rainuav.radio.outputs.levelmaps import build_radio_level_series, build_radio_levels

    if times_s is None:
        stack = build_radio_levels(scn, progress=progress, cache=cache)
    else:
        stack = build_radio_level_series(for_time(scn), times_s, progress=progress, cache=cache)
    return field_of(signal_of(stack, scenario_toml=False), levels=True), stack


def build_world(
    spec: Any,
    *,
    task: NavConfig | None = None,
    scenario: Scenario | None = None,
    progress: bool = False,
    cache: bool = True,
) -> World:
    """Builds the world a configuration describes: its map (or maps in time) and its task.

    Args:
        spec: A [`WorldSpec`][rainuav.world.WorldSpec], or a configuration extending one
            ([`TrainConfig`][rainuav.rl.config.TrainConfig]).
        task: A task in place of the spec's.
        scenario: A scenario in place of the spec's preset.
        progress: A line on standard error per map built.
        cache: Read and keep the maps in the map cache (False: a storm flown once).

    Returns:
        The [`World`][rainuav.world.World]: the map, or maps in time where the weather moves.

    Raises:
        InvalidInputError: A scenario, weather or task that cannot be built (names the field).
    """
    check_spec(spec)
    scn = make_scenario(spec, scenario)
    task = task_of(spec) if task is None else task
    check_config(task, _extent(scn), "task.")  # a destination off the area: before any map
    source = build_source(spec, scn, progress=progress, cache=cache)
    return _observed(world_from(source, task), spec)


def _observed(world: World, spec: Any) -> World:
    """``world`` with the spec's observation and destinations."""
    return dataclasses.replace(world, observation=spec.observation, random_goal=spec.random_goal)


def build_source(spec: Any, scn: Scenario, *, progress: bool = False, cache: bool = True) -> Any:
    """The signal's source for the scenario ``scn`` of ``spec``: its map, or where its weather moves
    its maps at [`series_instants()`][rainuav.world.series_instants] (engine 'pe' then becomes
    'hybrid': a march per cell and instant is refused); built, or taken from the cache."""
    if spec.altitudes_m:  # every level's maps (in time where the weather moves)
        times = series_instants(spec) if scn.medium.moves else None
        return LevelStack.of(level_field(scn, times, progress=progress, cache=cache)[1], scn)
    if scn.medium.moves:
        scn = for_time(scn)
        return build_radio_map_series(scn, series_instants(spec), progress=progress, cache=cache)
    return build_radio_map(scn, progress=progress)


def source_key(spec: Any, scn: Scenario) -> str:
    """What identifies the source [`build_source()`][rainuav.world.build_source] gives (the
    scenario, and for a weather that moves its instants)."""
    if not scn.medium.moves:
        return scn.digest()
    t = series_instants(spec)
    return f"{scn.digest()}-{t[-1]:g}-{len(t)}"


def load_world(folder: Path, spec: Any) -> World | None:
    """The world saved in a run's ``folder`` ([`World.save()`][rainuav.world.World.save]) with the
    task of ``spec``, or None where the folder holds none."""
    for name, kind in zip(MAP_FILES, _SOURCES, strict=True):
        if (Path(folder) / name).exists():
            return _observed(world_from(kind.load(Path(folder) / name), task_of(spec)), spec)
    return None


def _extent(scn: Scenario) -> tuple[float, float, float, float]:
    return (scn.area.x_min_m, scn.area.x_max_m, scn.area.y_min_m, scn.area.y_max_m)


def _scenario_name(source: Any) -> str:
    """The name of the scenario a source was built from ('' where a signal carries none)."""
    if isinstance(source, Signal):
        if not source.scenario_toml:
            return ""
        try:
            name = tomllib.loads(source.scenario_toml).get("name", "")
        except tomllib.TOMLDecodeError:
            return ""
        return name if isinstance(name, str) else ""
    return str(source.scenario.name)


def in_world(spec: Any, source: Any) -> tuple[Any, World]:
    """``(spec, world)``: the spec and the world of its task on a map or series already built
    (tests and scripts that hand ``rainuav.rl.loop.train`` a small synthetic map:
    ``train(*in_world(cfg, my_map))``)."""
    return spec, _observed(world_from(source, task_of(spec)), spec)


def saved_world(cfg: Any) -> tuple[Any, World | None]:
    """``(cfg, world)``: a run's configuration and the world saved in its folder ``cfg.out``
    (None where it holds none), to resume it: ``train(*saved_world(cfg), resume=True)``."""
    return cfg, load_world(Path(cfg.out), cfg)
