"""The airspace of a scenario ([`Area`][rainuav.radio.scene.area.Area]) and the terrain under it
([`TerrainFile`][rainuav.radio.scene.area.TerrainFile]), as dataclasses validated by
[`rainuav.radio.scene.scenario.Scenario`][rainuav.radio.scene.scenario.Scenario]."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from rainuav._checks import check_choice as _choice
from rainuav._checks import check_number as _num
from rainuav.errors import InvalidInputError

__all__ = ["DEFAULT_MIN_CLEARANCE_M", "Area", "TerrainFile"]

DEFAULT_MIN_CLEARANCE_M = 10.0
"""The least height kept above terrain and obstacles, m (``area.min_clearance_m``)."""


@dataclass
class Area:
    """The airspace: a rectangle at one flight altitude, mapped at one resolution."""

    x_min_m: float = 0.0
    """West edge, m."""
    x_max_m: float = 2000.0
    """East edge, m."""
    y_min_m: float = 0.0
    """South edge, m."""
    y_max_m: float = 2000.0
    """North edge, m."""
    altitude_m: float = 100.0
    """Flight altitude above the ground, m (0.5-3000)."""
    resolution_m: float = 10.0
    """Map pixel size, m (0.5-500)."""
    altitude_reference: str | None = None
    """What ``altitude_m`` is measured from: ``"ground"`` (the terrain under the UAV:
    terrain-following, the default) or ``"msl"`` (mean sea level; -500..9000 m)."""
    min_clearance_m: float | None = None
    """The least height (m) the UAV keeps above terrain and obstacles (default 10): a pixel
    whose highest point plus this reaches the flight height is not flyable."""
    altitudes_m: list[float] | None = None
    """The flight altitudes a UAV may choose among (m, increasing, in the altitude reference
    of ``altitude_reference``), e.g. 30 to 120 every 15; None: ``altitude_m`` alone
    ([`rainuav.radio.outputs.levelmaps.build_radio_levels()`][rainuav.radio.outputs.levelmaps.build_radio_levels]
    maps each)."""

    def check(self, where: str = "area") -> None:
        """Checks the area's bounds, resolution and flight levels.

        Args:
            where: The name the error gives the area ("area", or "scenario.area").

        Raises:
            InvalidInputError: A bound, resolution or level outside its range, named as
                `where.FIELD`, or a map of more than 4e7 pixels.
        """
        for k in ("x_min_m", "x_max_m", "y_min_m", "y_max_m"):
            _num(f"{where}.{k}", getattr(self, k), -1e6, 1e6, " m")
        if not self.x_max_m > self.x_min_m:
            raise InvalidInputError(
                f"{where}.x_max_m must be > x_min_m ({self.x_max_m} <= {self.x_min_m})"
            )
        if not self.y_max_m > self.y_min_m:
            raise InvalidInputError(
                f"{where}.y_max_m must be > y_min_m ({self.y_max_m} <= {self.y_min_m})"
            )
        if self.altitude_reference is not None:
            _choice(f"{where}.altitude_reference", self.altitude_reference, ("ground", "msl"))
        if self.msl:
            _num(f"{where}.altitude_m", self.altitude_m, -500.0, 9000.0, " m above sea level")
        else:
            _num(f"{where}.altitude_m", self.altitude_m, 0.5, 3000.0, " m above the ground")
        if self.min_clearance_m is not None:
            _num(f"{where}.min_clearance_m", self.min_clearance_m, 0.0, 1000.0, " m")
        if self.altitudes_m is not None:
            levels = self.altitudes_m
            if not isinstance(levels, list | tuple) or len(levels) == 0:
                raise InvalidInputError(
                    f"{where}.altitudes_m must be a non-empty list of flight altitudes (m)"
                )
            lo, hi, unit = (-500.0, 9000.0, " m above sea level") if self.msl else (
                0.5, 3000.0, " m above the ground"
            )  # fmt: skip
            for k, a in enumerate(levels):
                _num(f"{where}.altitudes_m[{k}]", a, lo, hi, unit)
            if any(b <= a for a, b in itertools.pairwise(levels)):
                raise InvalidInputError(
                    f"{where}.altitudes_m must increase strictly (got {list(levels)})"
                )
            if len(levels) > 64:
                raise InvalidInputError(
                    f"{where}.altitudes_m holds {len(levels)} levels (at most 64)"
                )
        _num(f"{where}.resolution_m", self.resolution_m, 0.5, 500.0, " m")
        pixels = ((self.x_max_m - self.x_min_m) / self.resolution_m) * (
            (self.y_max_m - self.y_min_m) / self.resolution_m
        )
        if pixels > 4e7:
            raise InvalidInputError(
                f"{where}: the map would have {pixels:.3g} pixels "
                "(at most 4e7); use a coarser resolution_m"
            )

    @property
    def levels(self) -> list[float]:
        """The flight altitudes, m: [`altitudes_m`][rainuav.radio.scene.area.Area.altitudes_m], else
        [`altitude_m`][rainuav.radio.scene.area.Area.altitude_m] alone."""
        return [float(a) for a in self.altitudes_m] if self.altitudes_m else [self.altitude_m]

    @property
    def msl(self) -> bool:
        """Whether the flight altitude is above mean sea level (else above the ground)."""
        return self.altitude_reference == "msl"

    @property
    def clearance_m(self) -> float:
        """The minimum clearance over terrain and obstacles, m
        ([`min_clearance_m`][rainuav.radio.scene.area.Area.min_clearance_m])."""
        return DEFAULT_MIN_CLEARANCE_M if self.min_clearance_m is None else self.min_clearance_m

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max), m."""
        return (self.x_min_m, self.x_max_m, self.y_min_m, self.y_max_m)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) pixels of the map."""
        w = max(1, round((self.x_max_m - self.x_min_m) / self.resolution_m))
        h = max(1, round((self.y_max_m - self.y_min_m) / self.resolution_m))
        return h, w

    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """The pixel centres.

        Returns:
            `(east, north)`: the east coordinates (W,) and the north coordinates (H,) of the pixel
            centres, m.
        """
        h, w = self.shape
        x = self.x_min_m + (np.arange(w) + 0.5) * (self.x_max_m - self.x_min_m) / w
        y = self.y_min_m + (np.arange(h) + 0.5) * (self.y_max_m - self.y_min_m) / h
        return x, y


DEM_ROUGHNESS_M = 0.3
"""The default roughness a DEM does not resolve, m: the spread of heights rounded to whole metres
(1/sqrt(12) = 0.29 m), as SRTM delivers them."""


@dataclass
class TerrainFile:
    """The terrain under the area: a digital elevation model
    ([`rainuav.ground.dem`][rainuav.ground.dem])."""

    file: str
    """A GeoTIFF of heights above sea level in any CRS (SRTM, Copernicus GLO-30); in a TOML
    file, relative to the TOML's folder."""
    roughness_m: float = DEM_ROUGHNESS_M
    """The ground's roughness the DEM does not resolve, m (standard deviation; 0-100), added in
    quadrature to the terrain's own within a ground reflection's first Fresnel zone
    ([physics reference, section 8][8-rays-over-flat-ground]): heights in whole metres do not know
    the ground better than 1/sqrt(12) m, and trees and clutter are rougher still."""


@dataclass
class FootprintsFile:
    """Buildings from a footprint file
    ([`rainuav.ground.footprints`][rainuav.ground.footprints])."""

    file: str
    """A GeoJSON file of Polygon and MultiPolygon features in longitude/latitude, with
    OpenStreetMap's height tags; in a TOML file, relative to the TOML's folder."""
    material: str = "concrete"
    """The walls' ITU-R P.2040 material where a feature's ``building:material`` names none."""
    default_height_m: float = 10.0
    """The roof of a building on the ground whose feature gives neither a height nor storeys, m
    ([`rainuav.ground.footprints.DEFAULT_HEIGHT_M`][rainuav.ground.footprints.DEFAULT_HEIGHT_M];
    central-city buildings are often 18-28 m: a guess either way, which ``fly`` reports)."""
