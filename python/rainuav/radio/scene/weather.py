"""The weather of a scenario: clear air, homogeneous rain, rain cells or a rain-rate map, in
time: a rain cell may move (``vx_m_s``, ``vy_m_s``) and grow or decay (``growth_s``), and
[`Medium.at()`][rainuav.radio.scene.weather.Medium.at] gives the frozen weather at any instant, to
which every static tool applies."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import medium as m
from rainuav._checks import check_choice as _choice
from rainuav._checks import check_number as _num
from rainuav.errors import InvalidInputError
from rainuav.radio.scene.stochastic import StochasticRain

__all__ = ["MAX_SPEED_M_S", "Medium", "RainCell"]

MAX_RATE_MM_H = 500.0
"""The highest rain rate the rain model takes, mm/h."""
MAX_SPEED_M_S = 60.0
"""The fastest a rain cell may move, m/s: storm motions beyond 30 m/s are rare, and 60 m/s is
above any observed; more is a mistake in the input."""
MIN_GROWTH_S = 60.0
"""The shortest growth or decay e-folding time, s (convective cells live for tens of minutes)."""


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
    vx_m_s: float = 0.0
    """Velocity of the centre, east, m/s (convective cells move with the mean wind, 5-20 m/s)."""
    vy_m_s: float = 0.0
    """Velocity of the centre, north, m/s."""
    growth_s: float = 0.0
    """E-folding time of the peak rate, s: the peak at time t is ``peak exp(t / growth_s)``
    (positive: growing, negative: decaying; 0: steady)."""

    def at(self, t_s: float) -> RainCell:
        """The cell at a later time: moved by its velocity, its peak grown or decayed.

        The peak is held within the 500 mm/h the rain model covers. Velocity and growth are kept, so
        `c.at(a).at(b)` is `c.at(a + b)` (until a peak reaches the bound).

        Args:
            t_s: Time after the weather's time 0, s.

        Returns:
            A new [`RainCell`][rainuav.radio.scene.weather.RainCell].
        """
        # The exponent is capped where the peak is past the bound anyway (no overflow).
        grow = math.exp(min(t_s / self.growth_s, 700.0)) if self.growth_s else 1.0
        return dataclasses.replace(
            self,
            x_m=self.x_m + self.vx_m_s * t_s,
            y_m=self.y_m + self.vy_m_s * t_s,
            peak_rate_mm_h=min(self.peak_rate_mm_h * grow, MAX_RATE_MM_H),
        )

    @property
    def moves(self) -> bool:
        """Whether the cell changes in time (a velocity or a growth)."""
        return bool(self.vx_m_s or self.vy_m_s or self.growth_s)

    def rate(self, x: npt.ArrayLike, y: npt.ArrayLike) -> Any:
        """The cell's rain rate at points on the ground.

        Args:
            x: East coordinates, m (any shape).
            y: North coordinates, m (the shape of `x`).

        Returns:
            The rate, mm/h, at each point: the peak times the profile of the distance from the
            centre over the radius.
        """
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
    """'clear', 'homogeneous', 'cells', 'map' or 'field' (stochastic)."""
    rain_rate_mm_h: float = 25.0
    """Homogeneous rate ('homogeneous'), or the background rate under 'cells'."""
    cells: list[RainCell] = field(default_factory=list)
    """Rain cells ('cells'); their rates add."""
    rate_map_mm_h: Any = None
    """(rows south to north, columns west to east) rates over the area ('map'), at the
    centres of a regular grid spanning it; with ``rate_times_s``, one such map per instant
    (time, rows, columns)."""
    rate_times_s: list[float] | None = None
    """The instants (s, strictly increasing) of the maps of ``rate_map_mm_h`` when it holds
    one per instant ('map'): the weather at t is interpolated linearly between the two maps
    around t (exactly a map at its own instant) and held beyond the first and the last
    ([`read_rate_grid()`][rainuav.radio.scene.rategrid.read_rate_grid] reads them from a NetCDF
    file)."""
    field: StochasticRain | None = None
    """A stochastic rain field ('field';
    [`rainuav.radio.scene.stochastic`][rainuav.radio.scene.stochastic])."""
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
    """How wind acts: 'canting' (drops cant by atan(v_wind / v_t);
    [physics reference, section 3][3-the-rain-medium]) or 'paper' (the paper's 1/cos factor, for
    reproducing it only; rainuav.medium)."""

    def at(self, t_s: float) -> Medium:
        """The weather at a time, every rain cell moved and grown.

        The rest of the weather (model, drops, temperature, wind) does not change in time; a weather
        that does not move returns itself.

        Args:
            t_s: Time, s.

        Returns:
            The [`Medium`][rainuav.radio.scene.weather.Medium] at `t_s` (each cell as
            [`RainCell.at()`][rainuav.radio.scene.weather.RainCell.at] gives it).
        """
        t = _num("t_s", t_s, -1e6, 1e6, " s")
        if self.kind == "map" and self.rate_times_s is not None:
            return self._map_at(t, *self._rate_maps())
        if not self.moves:
            return self
        if self.kind == "field" and self.field is not None:
            return dataclasses.replace(self, field=self.field.at(t))
        return dataclasses.replace(self, cells=[c.at(t) for c in self.cells])

    def clock(self) -> Callable[[float], Medium]:
        """[`at()`][rainuav.radio.scene.weather.Medium.at] for many instants of one weather.

        Returns:
            A function of the time, s, giving the weather then; a rate map in time is read into an
            array once, not at every instant.
        """
        if self.kind != "map" or self.rate_times_s is None:
            return self.at
        times, maps = self._rate_maps()
        return lambda t_s: self._map_at(_num("t_s", t_s, -1e6, 1e6, " s"), times, maps)

    def _rate_maps(self) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(self.rate_times_s, dtype=float), np.asarray(
            self.rate_map_mm_h, dtype=float
        )

    def _map_at(self, t: float, times: np.ndarray, maps: np.ndarray) -> Medium:
        """The rate map at ``t``: linear between the maps around it, held beyond the ends."""
        k = int(np.clip(np.searchsorted(times, t, side="right"), 1, max(len(times) - 1, 1)))
        if len(times) == 1 or t <= times[0]:
            now = maps[0]
        elif t >= times[-1]:
            now = maps[-1]
        else:
            w = (t - times[k - 1]) / (times[k] - times[k - 1])
            now = maps[k - 1] if w == 0.0 else (1.0 - w) * maps[k - 1] + w * maps[k]
        return dataclasses.replace(self, rate_map_mm_h=now.tolist(), rate_times_s=None)

    @property
    def varies(self) -> bool:
        """Whether the rain varies over the area (rain cells, rate maps, stochastic fields)."""
        return self.kind in ("cells", "map", "field")

    @property
    def moves(self) -> bool:
        """Whether the weather changes in time."""
        if self.kind == "map":
            return self.rate_times_s is not None and len(self.rate_times_s) > 1
        if self.kind == "field":
            return self.field is not None and self.field.moves
        return self.kind == "cells" and any(c.moves for c in self.cells)

    def rain_medium(self, freq_hz: float, polarization: str) -> m.RainMedium:
        """The effective medium of this weather's rain at one frequency and polarisation.

        Args:
            freq_hz: Carrier frequency, Hz.
            polarization: "H" or "V".

        Returns:
            A [`RainMedium`][rainuav.medium.RainMedium] of this weather's model, drops, temperature
            and wind, for any rain rate.
        """
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
        """Checks the weather: its kind and every field the kind reads.

        Args:
            where: The name the error gives the weather ("medium", or "scenario.medium").

        Raises:
            InvalidInputError: A field outside its range, named as `where.FIELD`: a kind without the
                fields it needs, a cell faster or growing faster than the model allows, a rate map
                of the wrong shape or outside 0-500 mm/h.
        """
        _choice(f"{where}.kind", self.kind, ("clear", "homogeneous", "cells", "map", "field"))
        if (self.kind == "field") != (self.field is not None):
            raise InvalidInputError(f"{where}.field is required with kind 'field' (and only then)")
        if self.field is not None:
            self.field.check(f"{where}.field")
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
            _num(f"{w}.vx_m_s", c.vx_m_s, -MAX_SPEED_M_S, MAX_SPEED_M_S, " m/s")
            _num(f"{w}.vy_m_s", c.vy_m_s, -MAX_SPEED_M_S, MAX_SPEED_M_S, " m/s")
            if math.hypot(c.vx_m_s, c.vy_m_s) > MAX_SPEED_M_S:
                raise InvalidInputError(
                    f"{w}: speed must be at most {MAX_SPEED_M_S:g} m/s "
                    f"(got {math.hypot(c.vx_m_s, c.vy_m_s):g})"
                )
            g = _num(f"{w}.growth_s", c.growth_s, -1e7, 1e7, " s")
            if g and abs(g) < MIN_GROWTH_S:
                raise InvalidInputError(
                    f"{w}.growth_s must be 0 (steady) or at least {MIN_GROWTH_S:g} s in size "
                    f"(got {g:g})"
                )
        if self.rate_times_s is not None and self.kind != "map":
            raise InvalidInputError(f"{where}.rate_times_s: only with kind 'map'")
        if self.kind == "cells" and not self.cells:
            raise InvalidInputError(
                f"{where}.cells must hold at least one rain cell when kind is 'cells'"
            )
        if self.kind == "map":
            if self.rate_map_mm_h is None:
                raise InvalidInputError(f"{where}.rate_map_mm_h is required when kind is 'map'")
            try:
                arr = np.asarray(self.rate_map_mm_h, dtype=float)
            except (TypeError, ValueError) as err:
                raise InvalidInputError(
                    f"{where}.rate_map_mm_h must be a table of numbers"
                ) from err
            dims = 2 if self.rate_times_s is None else 3
            what = "a 2-D table" if dims == 2 else "one 2-D table per rate_times_s instant"
            if arr.ndim != dims or min(arr.shape) < 1:
                raise InvalidInputError(
                    f"{where}.rate_map_mm_h must be {what} (got shape {arr.shape})"
                )
            if dims == 3:
                times = np.asarray(self.rate_times_s, dtype=float)
                if times.shape != (arr.shape[0],):
                    raise InvalidInputError(
                        f"{where}.rate_times_s must give one instant per map "
                        f"({arr.shape[0]}; got {times.size})"
                    )
                ok = np.all(np.isfinite(times)) and np.all(np.abs(times) <= 1e6)
                if not ok or np.any(np.diff(times) <= 0):
                    raise InvalidInputError(
                        f"{where}.rate_times_s must be finite, within +-1e6 s and strictly "
                        "increasing"
                    )
            if not (np.all(np.isfinite(arr)) and arr.min() >= 0 and arr.max() <= 500):
                raise InvalidInputError(f"{where}.rate_map_mm_h must be within 0..500 mm/h")
