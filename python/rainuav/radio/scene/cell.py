"""A cell (one sector of a site) and its antenna: which pattern it radiates with, where it
points, and its gain toward any direction in the global frame.

Conventions ([physics reference, section 7][7-antennas]): ``azimuth_deg`` is the boresight direction
counter-clockwise from +x (east); ``tilt_deg`` is the mechanical tilt, the boresight elevation
(positive up). A cell's gain toward a global direction (azimuth ``a``, elevation ``e``) is its
pattern's gain at ``(a - azimuth_deg, e - tilt_deg)``: the tilt shifts the pattern in elevation
(exact in the boresight's vertical plane, and what the PE source does with a tilt).

Antennas (``Cell.antenna``; [`rainuav.antenna`][rainuav.antenna] holds the patterns):

- ``"gaussian"``: the paper's beam, half-power widths ``beamwidth_deg`` / ``beamwidth_v_deg``,
  optionally with a sidelobe floor ``floor_db`` below the peak (``None``: the pure beam).
- ``"tr38901"``: the 3GPP TR 38.901 sector element alone (65 degrees, 8 dBi).
- ``"array"``: a uniform array of that element, ``rows`` x ``columns`` at ``spacing``
  wavelengths, electrically tilted to ``electrical_tilt_deg`` (positive up).
- ``"table"``: ``pattern``, a table relative to boresight (normalised to 4 pi).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from rainuav import antenna
from rainuav._checks import check_choice as _choice
from rainuav._checks import check_number as _num
from rainuav.errors import InvalidInputError

__all__ = [
    "ANTENNAS",
    "Cell",
    "Pattern",
    "Weight",
    "cell_pattern",
    "gain_linear",
    "pattern_by_key",
    "weight_at",
]

#: A weight on a pattern: direction cosines (cross-range, height, range) in the cell's frame
#: -> factor in 0..1.
Weight = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]

ANTENNAS = ("gaussian", "tr38901", "array", "table")
"""The antenna kinds a cell can name."""


@dataclass
class Pattern:
    """A tabulated antenna power pattern relative to boresight (dB)."""

    azimuth_deg: list[float]
    """Cross-range angles, increasing."""
    elevation_deg: list[float]
    """Elevation angles relative to the tilt, increasing."""
    gain_db: list[list[float]]
    """``gain_db[i][j]`` at (``azimuth_deg[i]``, ``elevation_deg[j]``), 0 at boresight."""


@dataclass
class Cell:
    """One sector of a site: an antenna, where it points, and its power."""

    azimuth_deg: float = 0.0
    """Boresight direction, degrees counter-clockwise from +x (east)."""
    tilt_deg: float = 5.0
    """Mechanical tilt: boresight elevation, degrees (positive up); the paper's beams 5."""
    antenna: str = "gaussian"
    """'gaussian', 'tr38901', 'array' or 'table' (module docstring)."""
    beamwidth_deg: float = 4.333
    """'gaussian': horizontal half-power beamwidth, degrees; the paper's 4.333."""
    beamwidth_v_deg: float | None = None
    """'gaussian': vertical half-power beamwidth, degrees (default: beamwidth_deg)."""
    floor_db: float | None = None
    """'gaussian': sidelobe floor, dB below the peak (None: the pure beam, no sidelobes)."""
    rows: int = 8
    """'array': elements in the vertical column."""
    columns: int = 1
    """'array': columns side by side."""
    spacing: float = 0.5
    """'array': element spacing, wavelengths."""
    electrical_tilt_deg: float = -10.0
    """'array': electrical tilt by phase progression, degrees (positive up: -10 is a 10
    degree downtilt)."""
    tx_power_dbm: float = 46.0
    """Transmit power, dBm."""
    pattern: Pattern | None = None
    """'table': the tabulated pattern (giving one selects 'table')."""

    def __post_init__(self) -> None:
        if self.pattern is not None and self.antenna == "gaussian":
            self.antenna = "table"  # scenarios written before antennas had a kind

    def check(self, where: str) -> None:
        """Checks the cell's site, antenna and power.

        Args:
            where: The name the error gives the cell (e.g. "cells[3]").

        Raises:
            InvalidInputError: A field outside its range, named as `where.FIELD`, or an antenna
                table of the wrong shape.
        """
        _num(f"{where}.azimuth_deg", self.azimuth_deg, -360.0, 360.0, " degrees")
        _num(f"{where}.tilt_deg", self.tilt_deg, -45.0, 45.0, " degrees")
        _choice(f"{where}.antenna", self.antenna, ANTENNAS)
        _num(f"{where}.beamwidth_deg", self.beamwidth_deg, 0.5, 60.0, " degrees")
        if self.beamwidth_v_deg is not None:
            _num(f"{where}.beamwidth_v_deg", self.beamwidth_v_deg, 0.5, 60.0, " degrees")
        if self.floor_db is not None:
            _num(f"{where}.floor_db", self.floor_db, 3.0, 200.0, " dB below the peak")
        for name in ("rows", "columns"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 1 <= v <= 64:
                raise InvalidInputError(
                    f"{where}.{name} must be an integer within 1..64 (got {v!r})"
                )
        _num(f"{where}.spacing", self.spacing, 0.05, 4.0, " wavelengths")
        _num(f"{where}.electrical_tilt_deg", self.electrical_tilt_deg, -90.0, 90.0, " degrees")
        _num(f"{where}.tx_power_dbm", self.tx_power_dbm, -30.0, 80.0, " dBm")
        if self.antenna == "table" and self.pattern is None:
            raise InvalidInputError(f"{where}.pattern is required when antenna is 'table'")
        if self.pattern is not None:
            p = self.pattern
            if len(p.gain_db) != len(p.azimuth_deg) or any(
                len(row) != len(p.elevation_deg) for row in p.gain_db
            ):
                raise InvalidInputError(
                    f"{where}.pattern.gain_db must have shape "
                    "(len(azimuth_deg), len(elevation_deg))"
                )
            try:
                cell_pattern(self)
            except InvalidInputError as err:
                raise InvalidInputError(f"{where}.pattern: {err}") from err

    @property
    def beamwidths_deg(self) -> tuple[float, float]:
        """(horizontal, vertical) half-power beamwidths of the 'gaussian' antenna."""
        v = self.beamwidth_deg if self.beamwidth_v_deg is None else self.beamwidth_v_deg
        return self.beamwidth_deg, v

    def key(self) -> tuple[Any, ...]:
        """What the cell's antenna pattern depends on.

        Returns:
            A tuple of the pattern's parameters: cells with equal keys share one pattern object.
        """
        if self.antenna == "gaussian":
            return ("gaussian", *self.beamwidths_deg, self.floor_db)
        if self.antenna == "tr38901":
            return ("tr38901",)
        if self.antenna == "array":
            return ("array", self.rows, self.columns, self.spacing, self.electrical_tilt_deg)
        p = self.pattern
        assert p is not None
        g = tuple(tuple(float(v) for v in row) for row in p.gain_db)
        return ("table", tuple(p.azimuth_deg), tuple(p.elevation_deg), g)


@functools.lru_cache(maxsize=64)
def pattern_by_key(key: tuple[Any, ...]) -> antenna.Pattern:
    """The pattern of any cell whose `Cell.key()` is a key (built once, cached).

    Args:
        key: The key.

    Returns:
        The pattern.
    """
    kind = key[0]
    if kind == "gaussian":
        _, bh, bv, floor = key
        return antenna.gaussian(bh, beamwidth_v_deg=bv, tilt_deg=0.0, floor_db=floor)
    if kind == "tr38901":
        return antenna.tr38901_element()
    if kind == "array":
        _, rows, columns, spacing, tilt = key
        return antenna.uniform_array(rows, spacing, tilt, columns=columns)
    _, az, el, g = key
    return antenna.tabulated(az, el, g, normalise=True)


def cell_pattern(cell: Cell) -> antenna.Pattern:
    """The cell's pattern in its own frame, dBi (shared between cells with equal antennas).

    Args:
        cell: The cell.

    Returns:
        The pattern.
    """
    return pattern_by_key(cell.key())


def gain_linear(cell: Cell, azimuth_deg: npt.ArrayLike, elevation_deg: npt.ArrayLike) -> np.ndarray:
    """The cell's linear gain toward global directions (the module's docstring).

    Args:
        cell: The cell.
        azimuth_deg: Global azimuths, degrees.
        elevation_deg: Elevations, degrees.

    Returns:
        The linear gain, of the broadcast shape.
    """
    el = np.clip(np.asarray(elevation_deg, dtype=float) - cell.tilt_deg, -90.0, 90.0)
    az = np.asarray(azimuth_deg, dtype=float) - cell.azimuth_deg
    return np.asarray(10.0 ** (cell_pattern(cell).gain_dbi(az, el) / 10.0))


def weight_at(weight: Weight, cell: Cell, az: np.ndarray, el: np.ndarray) -> np.ndarray:
    """A weight in global directions from a cell.

    Args:
        weight: The weight.
        cell: The cell.
        az: Global azimuths, degrees.
        el: Elevations, degrees.

    Returns:
        The weight, of the broadcast shape.
    """
    e = np.radians(el)
    a = np.radians(az - cell.azimuth_deg)
    return weight(np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a))
