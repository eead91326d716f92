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
flies the series ([`SignalField.series`][rainuav.nav.fieldmakers.FieldMakers.series])"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tomllib

from rainuav.errors import InvalidInputError
from rainuav.nav.env import UAVNavEnv
from rainuav.nav.field import SignalField
from rainuav.nav.levelfield import field_of
from rainuav.nav.task import NavConfig, check_config
from rainuav.nav.vector import UAVNavVectorEnv
from rainuav.radio.engines import for_time
from rainuav.radio.outputs.levelmaps import LevelStack
from rainuav.radio.outputs.mapdata import RadioMap, default_min_db
from rainuav.radio.outputs.maps import build_radio_map
from rainuav.radio.outputs.signals import signal_of
from rainuav.radio.outputs.timemap import RadioMapSeries, build_radio_map_series, series_times
from rainuav.radio.scene.scenario import Scenario
from rainuav.signals import Signal
from rainuav.world.spec import (
    WorldSpec,
    check_spec,
    levels_of,
    make_scenario,
    spec_of,
    task_of,
)

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
SLICE_S = 5.0
"""Time between the maps ``fly`` makes of a weather file with several instants, s."""


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
        """A Gymnasium environment of this world, a fresh one per call.

        Returns:
            A [`UAVNavEnv`][rainuav.nav.env.UAVNavEnv] on this world's field and task, on one level
            or among several.
        """
        return UAVNavEnv(
            field=self.field,
            config=self.task,
            observation=self.observation,
            random_goal=self.random_goal,
        )

    def vector_env(self, num_envs: int, autoreset_mode: Any = "NextStep") -> UAVNavVectorEnv:
        """Several UAVs in this world, stepped as one batch.

        Args:
            num_envs: How many UAVs.
            autoreset_mode: Gymnasium's autoreset mode ("NextStep", the default, "SameStep" or
                "Disabled").

        Returns:
            A [`UAVNavVectorEnv`][rainuav.nav.vector.UAVNavVectorEnv] of `num_envs` copies of
            [`env()`][rainuav.world.World.env].
        """
        return UAVNavVectorEnv(self.env(), num_envs, autoreset_mode)

    def save(self, folder: Path) -> Path | None:
        """Writes the signal's source into a folder, atomically.

        Args:
            folder: The run's folder; the file is named by the source's kind
                ([`MAP_FILES`][rainuav.world.MAP_FILES]).

        Returns:
            The file written, or None for a storm pool's bank (its seeds rebuild its storms).
        """
        if self.source is None:
            return None
        kind = next(k for k in _SOURCES if isinstance(self.source, k))
        name = MAP_FILES[_SOURCES.index(kind)]
        return self.source.save(Path(folder) / name)


def world_from(source: Any, task: NavConfig) -> World:
    """The world of a built map (or maps in time, or maps of levels) and a task.

    Every kind of source is read as one signal
    ([`signal_of()`][rainuav.radio.outputs.signals.signal_of]) and flown through the field its axes
    ask for ([`field_of()`][rainuav.nav.levelfield.field_of]).

    Args:
        source: A [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap], a
            [`RadioMapSeries`][rainuav.radio.outputs.timemap.RadioMapSeries], the maps of every
            level (a [`LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack], or built levels,
            which the world keeps as their signal) or a [`Signal`][rainuav.signals.Signal].
        task: The navigation task; its `min_db` unset takes the scenario's documented threshold for
            the signal flown.

    Returns:
        The [`World`][rainuav.world.World], with `task.min_db` resolved (and, for the reward
        "chance", each pixel's outage probability from the map's spreads).

    Raises:
        InvalidInputError: A source of another kind, a signal that is not the task's, or the reward
            "chance" on anything but one radio map's SINR.
    """
    signal = task.signal
    if not callable(getattr(source, "as_signal", None)):
        raise InvalidInputError(
            "a world needs a RadioMap, RadioMapSeries, maps of every level or a Signal (got "
            f"{type(source).__name__})"
        )
    try:  # every kind says how it is one signal: its own as_signal()
        sig = signal_of(source, signal, scenario_toml=False)
    except InvalidInputError as err:  # the source does not hold the task's signal
        raise InvalidInputError(f"task.signal is {signal!r}: {err}") from None
    field = field_of(sig)
    min_db = task.min_db
    if min_db is None:  # the same rule for every kind (by the scenario's name)
        min_db = default_min_db(_scenario_name(source), signal)
    if task.reward == "chance":  # outage as a probability, from the cells' powers and spreads
        # one radio map carries spreads (its prior's, or its measurements'), and a signal may
        # carry its cells' powers with them; maps in time and of levels do not
        from rainuav.radio.measured import signalrisk

        if sig.powers is None and not hasattr(source, "rss_std_db"):
            raise InvalidInputError(
                "task.reward 'chance' flies one radio map (a physics map with its prior's "
                "spreads, or one corrected by measurements: rainuav.radio.measured.correct_map) "
                "or the signal of one map that carries its cells' powers "
                "(rainuav.radio.measured.signalrisk.with_cell_powers)"
            )
        if signal != "sinr":
            raise InvalidInputError("task.reward 'chance' is the SINR's outage: task.signal sinr")
        if sig.powers is None:
            sig = dataclasses.replace(sig, powers=signalrisk.cell_powers(source))
        if sig.values.shape[:3] != (1, 1, 1):
            raise InvalidInputError(
                "task.reward 'chance' flies one map (one world, instant and level; got "
                f"{sig.values.shape[:3]})"
            )
        field.outage_p = signalrisk.signal_outage_probability(sig, min_db)[0, 0, 0]
    kept = source if hasattr(source, "save") else sig  # built levels are saved as their signal
    return World(kept, field, dataclasses.replace(task, min_db=min_db))


def series_instants(spec: WorldSpec) -> Any:
    """The instants a moving weather is mapped at.

    Args:
        spec: A spec whose task sets the horizon (`max_steps` moves of `step_m / speed_m_s` s).

    Returns:
        Times, s: every `slice_s` from 0 over the horizon, rounded up to a whole slice.
    """
    task = spec.task
    horizon = task.max_steps * task.step_m / task.speed_m_s
    return series_times(math.ceil(horizon / spec.slice_s - 1e-9) * spec.slice_s, spec.slice_s)


def level_field(
    scn: Scenario, times_s: Any = None, *, progress: bool = False, cache: bool = True
) -> tuple[Any, Any]:
    """The signal at every flight level of a scenario, and the maps it came from.

    Args:
        scn: A scenario whose `area.altitudes_m` lists the levels.
        times_s: Instants to map a moving weather at
            ([`build_radio_level_series()`][rainuav.radio.outputs.levelmaps.build_radio_level_series]:
            engine 'pe' then becomes 'hybrid'); None: one instant
            ([`build_radio_levels()`][rainuav.radio.outputs.levelmaps.build_radio_levels]).
        progress: A line on standard error per map built.
        cache: Read and keep the maps in the map cache (False: maps flown once, a storm pool's).

    Returns:
        `(field, maps)`: a [`SignalField`][rainuav.nav.field.SignalField] with those altitudes (what
        flights among levels read) and the levels' maps.
    """
    from rainuav.radio.outputs.levelmaps import build_radio_level_series, build_radio_levels

    if times_s is None:
        stack = build_radio_levels(scn, progress=progress, cache=cache)
    else:
        stack = build_radio_level_series(for_time(scn), times_s, progress=progress, cache=cache)
    return field_of(signal_of(stack, scenario_toml=False), levels=True), stack


def build_world(
    spec: WorldSpec,
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


def _observed(world: World, spec: WorldSpec) -> World:
    """``world`` with the spec's observation and destinations."""
    return dataclasses.replace(world, observation=spec.observation, random_goal=spec.random_goal)


def build_source(
    spec: WorldSpec, scn: Scenario, *, progress: bool = False, cache: bool = True
) -> Any:
    """The map (or maps in time, or maps of levels) a spec's scenario gives, built or from the
    cache.

    Args:
        spec: The spec (its `altitudes_m`, and its task's horizon where the weather moves).
        scn: The spec's scenario ([`make_scenario()`][rainuav.world.spec.make_scenario]).
        progress: A line on standard error per map built.
        cache: Read and keep the maps in the map cache.

    Returns:
        A [`LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack] where the spec has levels, a
        [`RadioMapSeries`][rainuav.radio.outputs.timemap.RadioMapSeries] at
        [`series_instants()`][rainuav.world.series_instants] where the weather moves (engine 'pe'
        then becomes 'hybrid'), else a [`RadioMap`][rainuav.radio.outputs.mapdata.RadioMap].
    """
    if spec.altitudes_m:  # every level's maps (in time where the weather moves)
        times = series_instants(spec) if scn.medium.moves else None
        return LevelStack.of(level_field(scn, times, progress=progress, cache=cache)[1], scn)
    if scn.medium.moves:
        scn = for_time(scn)
        return build_radio_map_series(scn, series_instants(spec), progress=progress, cache=cache)
    return build_radio_map(scn, progress=progress)


def source_key(spec: WorldSpec, scn: Scenario) -> str:
    """What identifies the source [`build_source()`][rainuav.world.build_source] gives.

    Args:
        spec: The spec (its task's horizon, where the weather moves).
        scn: The spec's scenario.

    Returns:
        The scenario's digest, and for a weather that moves its last instant and their number.
    """
    if not scn.medium.moves:
        return scn.digest()
    t = series_instants(spec)
    return f"{scn.digest()}-{t[-1]:g}-{len(t)}"


def load_world(folder: Path, spec: WorldSpec) -> World | None:
    """The world saved in a run's folder, flown with a spec's task.

    Args:
        folder: A run's folder, holding one of [`MAP_FILES`][rainuav.world.MAP_FILES]
            ([`World.save()`][rainuav.world.World.save]).
        spec: The run's spec: its task, observation and destinations.

    Returns:
        The [`World`][rainuav.world.World], or None where the folder holds no map.
    """
    for name, kind in zip(MAP_FILES, _SOURCES, strict=True):
        if (Path(folder) / name).exists():
            return _observed(world_from(kind.load(Path(folder) / name), task_of(spec)), spec)
    return None


def _extent(scn: Scenario) -> tuple[float, float, float, float]:
    return (scn.area.x_min_m, scn.area.x_max_m, scn.area.y_min_m, scn.area.y_max_m)


def _scenario_name(source: Any) -> str:
    """The name of the scenario a source was built from ('' where a signal carries none)."""
    scn = getattr(source, "scenario", None)
    if scn is None:
        if not getattr(source, "scenario_toml", ""):
            return ""
        try:
            name = tomllib.loads(source.scenario_toml).get("name", "")
        except tomllib.TOMLDecodeError:
            return ""
        return name if isinstance(name, str) else ""
    return str(scn.name)


def in_world(spec: WorldSpec, source: Any) -> tuple[Any, World]:
    """A spec and the world of its task on a map already built.

    For tests and scripts that hand the trainer a small map of their own: `train(*in_world(cfg,
    my_map))`.

    Args:
        spec: A spec (or a [`TrainConfig`][rainuav.rl.config.TrainConfig]).
        source: A map, series, stack of levels or signal
            ([`world_from()`][rainuav.world.world_from]).

    Returns:
        `(spec, world)`.
    """
    return spec, _observed(world_from(source, task_of(spec)), spec)


def saved_world(cfg: Any) -> tuple[Any, World | None]:
    """A run's configuration and the world saved in its folder, to resume it.

    `train(*saved_world(cfg), resume=True)`.

    Args:
        cfg: The run's configuration; its `out` is the run's folder.

    Returns:
        `(cfg, world)`, the world None where the folder holds none.
    """
    return cfg, load_world(Path(cfg.out), cfg)
