"""Radio maps: a scenario (network, weather, airspace) in, every cell's received power, the
serving cell, SIR and SINR at the flight altitude out. Five sub-packages, each depending only on
those before it:

- [`scene`][rainuav.radio.scene]: what is there. The scenario and its TOML form
  ([`scenario`][rainuav.radio.scene.scenario], [`area`][rainuav.radio.scene.area],
  [`cell`][rainuav.radio.scene.cell], [`presets`][rainuav.radio.scene.presets],
  [`sites`][rainuav.radio.scene.sites]), the ground ([`terrain`][rainuav.radio.scene.terrain],
  [`buildings`][rainuav.radio.scene.buildings]) and the weather
  ([`weather`][rainuav.radio.scene.weather], [`storms`][rainuav.radio.scene.storms],
  [`stochastic`][rainuav.radio.scene.stochastic], [`rategrid`][rainuav.radio.scene.rategrid],
  [`radar`][rainuav.radio.scene.radar], [`geotiff`][rainuav.radio.scene.geotiff]).
- [`engines`][rainuav.radio.engines]: how the field gets there. The registry (what each engine
  does), the PE march per cell ([`grid`][rainuav.radio.engines.grid],
  [`pe_engine`][rainuav.radio.engines.pe_engine]), the rays
  ([`ray_engine`][rainuav.radio.engines.ray_engine],
  [`wall_rays`][rainuav.radio.engines.wall_rays]), the two together
  ([`hybrid`][rainuav.radio.engines.hybrid]).
- [`outputs`][rainuav.radio.outputs]: what comes out. A map and its builder
  ([`maps`][rainuav.radio.outputs.maps], [`mapdata`][rainuav.radio.outputs.mapdata],
  [`sinr`][rainuav.radio.outputs.sinr]), maps in time and at several levels
  ([`timemap`][rainuav.radio.outputs.timemap], [`levelmaps`][rainuav.radio.outputs.levelmaps]),
  GeoTIFF ([`maptiff`][rainuav.radio.outputs.maptiff]), figures
  ([`plot`][rainuav.radio.outputs.plot]) and the map cache
  ([`cache`][rainuav.radio.outputs.cache]).
- [`measured`][rainuav.radio.measured]: what comes out corrected by measurements. A drive-test or
  flight log read into the map's frame ([`log`][rainuav.radio.measured.log]), the site parameters
  it says are wrong fitted ([`calibrate`][rainuav.radio.measured.calibrate]), what is still off as
  a field with its uncertainty ([`residual`][rainuav.radio.measured.residual]), the corrected map
  ([`correct`][rainuav.radio.measured.correct]) and logs drawn from a map taken as the truth
  ([`synthetic`][rainuav.radio.measured.synthetic]).
- [`reference`][rainuav.radio.reference]: what the engines are measured against, a full ray
  tracer on the same scene ([`tracer`][rainuav.radio.reference.tracer]).

Depends on [`rainuav.medium`][rainuav.medium], [`rainuav.antenna`][rainuav.antenna],
[`rainuav.pwe`][rainuav.pwe] and [`rainuav.ground`][rainuav.ground] only; nothing here knows
about navigation or learning."""

from __future__ import annotations

from rainuav.radio.outputs.cache import cache_dir, clear_cache
from rainuav.radio.outputs.maps import RadioMap, build_radio_map
from rainuav.radio.outputs.sinr import sir_from_power
from rainuav.radio.outputs.timemap import RadioMapSeries, build_radio_map_series
from rainuav.radio.scene import presets
from rainuav.radio.scene.scenario import (
    Area,
    Building,
    Cell,
    Medium,
    Pattern,
    PESettings,
    RainCell,
    Scenario,
    Site,
)

__all__ = [
    "Area",
    "Building",
    "Cell",
    "Medium",
    "PESettings",
    "Pattern",
    "RadioMap",
    "RadioMapSeries",
    "RainCell",
    "Scenario",
    "Site",
    "build_radio_map",
    "build_radio_map_series",
    "cache_dir",
    "clear_cache",
    "presets",
    "sir_from_power",
]
