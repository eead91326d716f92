"""Deprecated: the scenario classes moved to :mod:`rainuav.radio.scenario` (this path goes
in 0.3)."""

from __future__ import annotations

from rainuav._deprecated import moved, names

__getattr__ = moved(
    __name__,
    names(
        "rainuav.radio.scenario",
        "Area",
        "Building",
        "Cell",
        "Medium",
        "PESettings",
        "Pattern",
        "RainCell",
        "Scenario",
        "Site",
    ),
)
