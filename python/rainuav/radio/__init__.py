"""Radio maps: a scenario (network, weather, airspace) in, every cell's received power, the
serving cell, SIR and SINR at the flight altitude out.

Modules, bottom up: [`cell`][rainuav.radio.cell] (a cell and its antenna),
[`scenario`][rainuav.radio.scenario] (the dataclasses and their TOML form),
[`presets`][rainuav.radio.presets] (the paper's and our scenarios), [`grid`][rainuav.radio.grid]
(one cell's PE grid and cone), [`pe_engine`][rainuav.radio.pe_engine] (the march per cell),
[`ray_engine`][rainuav.radio.ray_engine] (two rays per cell and pixel, in Rust),
[`sinr`][rainuav.radio.sinr], [`radiomap`][rainuav.radio.maps] (the map and its builder),
[`weather`][rainuav.radio.weather], [`storms`][rainuav.radio.storms],
[`rategrid`][rainuav.radio.rategrid] and [`stochastic`][rainuav.radio.stochastic] (weather in time),
[`timemap`][rainuav.radio.timemap] (maps of a moving weather at many instants),
[`cache`][rainuav.radio.cache] and [`plot`][rainuav.radio.plot]. Depends on
[`rainuav.medium`][rainuav.medium], [`rainuav.antenna`][rainuav.antenna] and
[`rainuav.pwe`][rainuav.pwe] only; nothing here knows about navigation or learning."""

from __future__ import annotations

from rainuav.radio import presets
from rainuav.radio.cache import cache_dir, clear_cache
from rainuav.radio.maps import RadioMap, build_radio_map
from rainuav.radio.scenario import (
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
from rainuav.radio.sinr import sir_from_power
from rainuav.radio.timemap import RadioMapSeries, build_radio_map_series

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
