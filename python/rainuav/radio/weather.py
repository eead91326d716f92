"""The weather of a scenario: clear air, homogeneous rain, rain cells or a rain-rate map."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rainuav import medium as m
from rainuav._checks import check_choice as _choice
from rainuav._checks import check_number as _num
from rainuav.errors import InvalidInputError

__all__ = ["Medium", "RainCell"]


@dataclass
class RainCell:
    """A rain cell: a rate that peaks at a centre and falls off with distance."""

    x_m: float
    """Centre, east, m."""
    y_m: float
    """Centre, north, m."""
    radius_m: float
    """Size: the 1/e radius (gaussian), the edge (uniform), or the 1/e distance (exponential)."""
    peak_rate_mm_h: float
    """Rate at the centre, mm/h."""
    profile: str = "gaussian"
    """'gaussian' exp(-(d/r)^2), 'exponential' exp(-d/r) or 'uniform' (peak inside r)."""

    def rate(self, x: Any, y: Any) -> Any:

        d = np.hypot(np.asarray(x) - self.x_m, np.asarray(y) - self.y_m)
        if self.profile == "gaussian":
            return self.peak_rate_mm_h * np.exp(-((d / self.radius_m) ** 2))
        if self.profile == "exponential":
            return self.peak_rate_mm_h * np.exp(-d / self.radius_m)
        return np.where(d <= self.radius_m, self.peak_rate_mm_h, 0.0)


@dataclass
class Medium:
    """The weather: clear air, homogeneous rain, rain cells or a rain-rate map."""

    kind: str = "homogeneous"
    """'clear', 'homogeneous', 'cells' or 'map'."""
    rain_rate_mm_h: float = 25.0
    """Homogeneous rate ('homogeneous'), or the background rate under 'cells'."""
    cells: list[RainCell] = field(default_factory=list)
    """Rain cells ('cells'); their rates add."""
    rate_map_mm_h: list[list[float]] | None = None
    """(rows south to north, columns west to east) rates over the area ('map')."""
    model: str = "forward-scattering"
    """Effective-medium model (rainuav.medium)."""
    dsd: str = "marshall-palmer"
    """Drop-size distribution name (rainuav.medium.NAMED_DSDS)."""
    shape: str = "beard-chuang"
    """Drop shape rule."""
    temperature_c: float = 20.0
    """Water temperature, C."""
    wind_speed_m_s: float = 0.0
    """Wind across the path, m/s."""
    wind_model: str = "canting"
    """How wind acts: 'canting' (drops cant by atan(v_wind / v_t); PHYSICS.md) or 'paper' (the
    paper's 1/cos factor, for reproducing it only; rainuav.medium)."""

    def rain_medium(self, freq_hz: float, polarization: str) -> m.RainMedium:
        """The effective medium of this weather's rain (model, drops, temperature, wind) at
        one frequency and polarisation, for any rain rate."""
        return m.RainMedium(
            freq_hz,
            model=self.model,  # type: ignore[arg-type]
            polarization=polarization,  # type: ignore[arg-type]
            shape=self.shape,  # type: ignore[arg-type]
            temperature_c=self.temperature_c,
            wind_speed_m_s=self.wind_speed_m_s,
            dsd=self.dsd,
            wind_model=self.wind_model,  # type: ignore[arg-type]
        )

    def check(self, where: str = "medium") -> None:

        _choice(f"{where}.kind", self.kind, ("clear", "homogeneous", "cells", "map"))
        _num(f"{where}.rain_rate_mm_h", self.rain_rate_mm_h, 0.0, 500.0, " mm/h")
        _choice(f"{where}.model", self.model, m.MODELS)
        _choice(f"{where}.dsd", self.dsd, tuple(m.NAMED_DSDS))
        _choice(f"{where}.shape", self.shape, m.SHAPES)
        _num(f"{where}.temperature_c", self.temperature_c, 0.0, 40.0, " C")
        _num(f"{where}.wind_speed_m_s", self.wind_speed_m_s, 0.0, 60.0, " m/s")
        _choice(f"{where}.wind_model", self.wind_model, m.WIND_MODELS)
        for i, c in enumerate(self.cells):
            w = f"{where}.cells[{i}]"
            _num(f"{w}.x_m", c.x_m, -1e6, 1e6, " m")
            _num(f"{w}.y_m", c.y_m, -1e6, 1e6, " m")
            _num(f"{w}.radius_m", c.radius_m, 1.0, 1e5, " m")
            _num(f"{w}.peak_rate_mm_h", c.peak_rate_mm_h, 0.0, 500.0, " mm/h")
            _choice(f"{w}.profile", c.profile, ("gaussian", "exponential", "uniform"))
        if self.kind == "cells" and not self.cells:
            raise InvalidInputError(
                f"{where}.cells must hold at least one rain cell when kind is 'cells'"
            )
        if self.kind == "map":
            if self.rate_map_mm_h is None:
                raise InvalidInputError(f"{where}.rate_map_mm_h is required when kind is 'map'")
            arr = np.asarray(self.rate_map_mm_h, dtype=float)
            if arr.ndim != 2 or min(arr.shape) < 1:
                raise InvalidInputError(
                    f"{where}.rate_map_mm_h must be a 2-D table (got shape {arr.shape})"
                )
            if not (np.all(np.isfinite(arr)) and arr.min() >= 0 and arr.max() <= 500):
                raise InvalidInputError(f"{where}.rate_map_mm_h must be within 0..500 mm/h")
