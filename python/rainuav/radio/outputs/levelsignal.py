"""The maps of every level as one [`Signal`][rainuav.signals.Signal]: the method the three level
classes share ([`RadioLevels`][rainuav.radio.outputs.levelmaps.RadioLevels],
[`RadioLevelSeries`][rainuav.radio.outputs.levelmaps.RadioLevelSeries],
[`LevelStack`][rainuav.radio.outputs.levelmaps.LevelStack])."""

from __future__ import annotations

from typing import Any

import numpy as np

from rainuav.errors import InvalidInputError
from rainuav.signals import Signal, signal_name, toml_of

__all__ = ["LevelsAsSignal"]


class LevelsAsSignal:
    """A level class's `as_signal()`: its ``sinr_db``, ``altitudes_m``, ``extent``,
    ``not_flyable`` and, where it has them, ``t_s``, ``serving_cell`` and ``scenario``."""

    def _serving_and_scenario(self) -> tuple[Any, Any]:
        """The serving cells (the SINR's shape) and the scenario (None where not kept)."""
        return getattr(self, "serving_cell", None), getattr(self, "scenario", None)

    def as_signal(self, signal: str = "sinr", *, scenario_toml: bool = True) -> Signal:
        """The maps of every level as one signal (a level axis; a time axis where in time), bit
        for bit, with the serving cells and not-flyable pixels.

        Args:
            signal: "sinr" (the maps of every level hold SINR alone).
            scenario_toml: Carry the scenario as TOML.

        Returns:
            The signal.

        Raises:
            InvalidInputError: A signal other than SINR.
        """
        if signal_name(signal) != "sinr_db":
            raise InvalidInputError("the maps of every level hold SINR alone (signal='sinr')")
        v: Any = self
        serving, scn = self._serving_and_scenario()
        t = getattr(v, "t_s", None)
        dims = ("level", "north", "east") if t is None else ("time", "level", "north", "east")
        return Signal.from_axes(v.sinr_db, dims, v.extent, t_s=(0.0,) if t is None else t,
                                altitudes_m=v.altitudes_m, serving_cell=serving, name="sinr_db",
                                not_flyable=np.asarray(v.not_flyable, bool),
                                scenario_toml=toml_of(scn, scenario_toml))  # fmt: skip
