"""The smaller parts of a scenario: its sites, box buildings, the latitude and longitude of its
origin, and the parabolic equation's settings ([`Scenario`][rainuav.radio.scene.scenario.Scenario]
holds them)."""

from __future__ import annotations

from dataclasses import dataclass, field

from rainuav._checks import check_choice as _choice
from rainuav._checks import check_number as _num
from rainuav.radio.scene.cell import Cell

__all__ = ["Building", "Origin", "PESettings", "Site"]


@dataclass
class Site:
    """A base-station site: a mast with one or more cells."""

    x_m: float
    """East coordinate, m."""
    y_m: float
    """North coordinate, m."""
    height_m: float = 25.0
    """Antenna height above the ground, m (the paper's 25)."""
    cells: list[Cell] = field(default_factory=lambda: [Cell()])
    """The site's cells (sectors)."""


@dataclass
class Building:
    """A box-shaped building standing on the ground."""

    x0_m: float
    """West face, m."""
    x1_m: float
    """East face, m."""
    y0_m: float
    """South face, m."""
    y1_m: float
    """North face, m."""
    height_m: float
    """Roof height, m."""


@dataclass
class PESettings:
    """How each cell's parabolic-equation march is gridded ([physics reference, section
    4][4-the-split-step-parabolic-equation])."""

    dynamic_range_db: float = 40.0
    """The grid resolves every direction where the beam is within this many dB of its peak."""
    absorber: float = 0.15
    """Fraction of each open edge of the domain given to the absorbing taper."""
    dz_m: float | None = None
    """Range step, m (default: min(resolution_m, 10))."""
    top_margin_m: float | None = None
    """Height above max(flight altitude, site) kept inside the domain (default:
    max(50, altitude / 2))."""
    propagator: str = "wide"
    """'wide' or 'narrow'."""
    budget_gpoints: float = 1.0
    """Largest march per cell the hybrid and PE engines may run, in 1e9 grid-point steps
    (nx x ny x steps): the PE's cone is the pattern's ``dynamic_range_db`` cone, narrowed
    until the march fits (about 10 s per 1e9 on 2 cores). Raise it to widen the cone."""

    def check(self, where: str = "pe") -> None:
        """Checks the parabolic equation's settings.

        Args:
            where: The name the error gives the settings ("pe").

        Raises:
            InvalidInputError: A setting outside its range, named as `where.FIELD`.
        """
        _num(f"{where}.dynamic_range_db", self.dynamic_range_db, 10.0, 120.0, " dB")
        _num(f"{where}.absorber", self.absorber, 0.05, 0.4)
        if self.dz_m is not None:
            _num(f"{where}.dz_m", self.dz_m, 0.01, 1000.0, " m")
        if self.top_margin_m is not None:
            _num(f"{where}.top_margin_m", self.top_margin_m, 1.0, 1e4, " m")
        _choice(f"{where}.propagator", self.propagator, ("wide", "narrow"))
        _num(f"{where}.budget_gpoints", self.budget_gpoints, 1e-3, 1e3, " (1e9 grid-point steps)")


@dataclass
class Origin:
    """The latitude and longitude (degrees, WGS 84) of a scenario's (0, 0)."""

    lat_deg: float = 0.0
    """Degrees north (|lat| <= 85)."""
    lon_deg: float = 0.0
    """Degrees east (-180..180)."""
